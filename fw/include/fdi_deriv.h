/*
 * fdi_deriv.h - first-order filtered derivative (and the matching first-order low-pass).
 *
 * Computes y ~ du/dt through H(s) = s / (tau*s + 1) and the filtered signal u_f = u - tau*y, which is
 * u through 1 / (tau*s + 1). Discretised with the bilinear (Tustin) transform, so it is stable for every
 * dt > 0; the cut-off is pre-warped, tau = 1 / W with W = (2/dt) * tan(pi * cutoff_hz * dt), so the discrete
 * -3 dB point is exactly cutoff_hz. Requires 0 < cutoff_hz < 1 / (2*dt) (below Nyquist).
 *
 *   y[k]   = a * y[k-1] + b * (u[k] - u[k-1]),   a = (2 - W*dt) / (2 + W*dt),  b = 2*W / (2 + W*dt)
 *   u_f[k] = u[k] - tau * y[k]
 *
 * A constant input gives y = 0 exactly and a ramp of slope s gives y -> s exactly (no coefficient
 * rounding can bias it: the input enters only as a difference).
 * Cost per step: 3 multiplications, 3 additions, 3 finiteness checks. Memory: coefficients 12 bytes
 * (fdi_deriv_coef_t, shareable by any number of filters with equal dt and cut-off), state 8 bytes.
 */
#ifndef FDI_DERIV_H
#define FDI_DERIV_H

#include "fdi_static_assert.h"
#include "fdi_status.h"

typedef struct
{
    float dt;        /* sample time [s], > 0 */
    float cutoff_hz; /* low-pass cut-off [Hz], 0 < cutoff_hz < 0.5 / dt */
} fdi_deriv_config_t;

typedef struct
{
    float a;   /* pole of the discrete filter, |a| < 1 */
    float b;   /* input gain */
    float tau; /* pre-warped time constant [s] */
} fdi_deriv_coef_t;

typedef struct
{
    float y;      /* last derivative output */
    float u_prev; /* last input */
} fdi_deriv_t;  /* opaque by convention */

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(sizeof(fdi_deriv_coef_t) == 12U, fdi_sa_deriv_coef_size);
/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(sizeof(fdi_deriv_t) == 8U, fdi_sa_deriv_size);

typedef struct
{
    float y;  /* low-pass filtered signal u_f */
    float dy; /* filtered derivative */
} fdi_deriv_out_t;

/* Design the coefficients. BAD_ARG: NULL, dt <= 0, cut-off out of (0, Nyquist); NOT_FINITE: NaN/Inf in cfg. */
fdi_status_t fdi_deriv_design(fdi_deriv_coef_t *coef, const fdi_deriv_config_t *cfg);

/* Start in steady state at the value u0 (derivative 0). NOT_FINITE if u0 is not finite. */
fdi_status_t fdi_deriv_reset(fdi_deriv_t *self, float u0);

/* One sample. NOT_FINITE (state and *out unchanged) when u or the result is not finite. */
fdi_status_t fdi_deriv_step(fdi_deriv_t *self, const fdi_deriv_coef_t *coef, float u, fdi_deriv_out_t *out);

#endif /* FDI_DERIV_H */
