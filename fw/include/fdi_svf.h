/*
 * fdi_svf.h - second-order state-variable filter: filtered signal and its filtered derivative.
 *
 * Continuous model (x1 = filtered u, x2 = d/dt x1), a unit-gain low-pass
 *   x1' = x2,   x2' = W^2 * (u - x1) - 2*zeta*W*x2,   i.e. x1 = W^2 / (s^2 + 2 zeta W s + W^2) * u.
 * Any signal can be fed in, so a generator gets d/dt of any signal (also of a derivative-like quantity:
 * chain two filters). Discretised with the trapezoidal rule (bilinear/Tustin, stable for every dt > 0),
 * solved for the implicit step once in fdi_svf_design(); W is the pre-warped natural frequency
 * W = (2/dt) * tan(pi * cutoff_hz * dt), so 0 < cutoff_hz < 1 / (2*dt) is required. With h = dt/2:
 *
 *   x2[k+1] = c1 * x2[k] + c2 * ((u[k] - x1[k]) + (u[k+1] - x1[k]) - h * x2[k])
 *   x1[k+1] = x1[k] + h * (x2[k] + x2[k+1])
 *   c1 = (1 - 2 zeta W h) / D,  c2 = W^2 h / D,  D = 1 + 2 zeta W h + W^2 h^2
 *
 * The input enters only as u - x1, so a constant is reproduced exactly (x2 = 0) and a ramp of slope s
 * gives x2 -> s exactly, whatever the rounding of c1, c2. The low-frequency delay of x1 and x2 is
 * 2*zeta/W seconds; generators feed all signals of one relation through equal filters so the delays match.
 * Cost per step: 4 multiplications, 7 additions, 3 finiteness checks. Memory: coefficients 12 bytes
 * (fdi_svf_coef_t, shareable), state 12 bytes per filter.
 */
#ifndef FDI_SVF_H
#define FDI_SVF_H

#include "fdi_static_assert.h"
#include "fdi_status.h"

typedef struct
{
    float dt;        /* sample time [s], > 0 */
    float cutoff_hz; /* natural frequency [Hz], 0 < cutoff_hz < 0.5 / dt */
    float zeta;      /* damping, 0.1 <= zeta <= 2 (0.7071 gives a Butterworth low-pass) */
} fdi_svf_config_t;

typedef struct
{
    float h;  /* dt / 2 */
    float c1; /* see header */
    float c2;
} fdi_svf_coef_t;

typedef struct
{
    float x1;     /* filtered signal */
    float x2;     /* filtered derivative */
    float u_prev; /* last input */
} fdi_svf_t;    /* opaque by convention */

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(sizeof(fdi_svf_coef_t) == 12U, fdi_sa_svf_coef_size);
/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(sizeof(fdi_svf_t) == 12U, fdi_sa_svf_size);

typedef struct
{
    float y;  /* filtered signal x1 */
    float dy; /* filtered derivative x2 */
} fdi_svf_out_t;

/* Design the coefficients. BAD_ARG: NULL or out-of-range values; NOT_FINITE: NaN/Inf in cfg. */
fdi_status_t fdi_svf_design(fdi_svf_coef_t *coef, const fdi_svf_config_t *cfg);

/* Start in steady state at u0: x1 = u0, x2 = 0. NOT_FINITE if u0 is not finite. */
fdi_status_t fdi_svf_reset(fdi_svf_t *self, float u0);

/* One sample. NOT_FINITE (state and *out unchanged) when u or the new state is not finite. */
fdi_status_t fdi_svf_step(fdi_svf_t *self, const fdi_svf_coef_t *coef, float u, fdi_svf_out_t *out);

#endif /* FDI_SVF_H */
