/*
 * fdi_obs.h - constant-gain observer for scalar first-order dynamics; its output error is a residual.
 *
 * Model of one dynamic constraint of an MSO set, with the measured output y = x:
 *   x' = a * x + f(t),     f = model right-hand side supplied by the generator at every step
 * (e.g. wheel spin: a = 0, f = (M_TM + M_DB - R * F_L) / J). Observer and residual:
 *   xh' = a * xh + f + L * (y - xh),    r = y - xh
 * The error dynamics have the pole lambda = a - L < 0 (checked in design), so the residual neither drifts
 * open loop nor depends on the unknown initial state after ~5/|lambda| seconds. Discretised with the
 * exact exponential of the error pole and the input g = f + L*y averaged over the step (first-order hold
 * approximation; a plain zero-order hold would leave a bias of dt/2 * dy/dt in r), stable for every dt > 0:
 *   g[k]  = f[k] + L * y[k]
 *   xh[k] = ad * xh[k-1] + bd * (g[k-1] + g[k]) / 2,   ad = exp(lambda dt),  bd = (ad - 1) / lambda
 *   r[k]  = y[k] - xh[k]
 * Cost per step: 4 multiplications, 4 additions, 5 finiteness checks. Memory: coefficients 12 bytes
 * (shareable), state 8 bytes.
 */
#ifndef FDI_OBS_H
#define FDI_OBS_H

#include "fdi_static_assert.h"
#include "fdi_status.h"

typedef struct
{
    float dt;   /* sample time [s], > 0 */
    float a;    /* linear state coefficient of the model [1/s] (0 for a pure integrator) */
    float gain; /* observer gain L [1/s]; a - L must be < 0 */
} fdi_obs_config_t;

typedef struct
{
    float ad;
    float bd;
    float gain;
} fdi_obs_coef_t;

typedef struct
{
    float xh;     /* state estimate */
    float g_prev; /* f + L*y of the previous step */
} fdi_obs_t;  /* opaque by convention */

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(sizeof(fdi_obs_coef_t) == 12U, fdi_sa_obs_coef_size);
/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(sizeof(fdi_obs_t) == 8U, fdi_sa_obs_size);

/* Design the coefficients. BAD_ARG: NULL, dt <= 0, a - gain >= 0; NOT_FINITE: NaN/Inf in cfg. */
fdi_status_t fdi_obs_design(fdi_obs_coef_t *coef, const fdi_obs_config_t *cfg);

/* Start at the current sample: xh = y (residual 0), previous input f + L*y. NOT_FINITE on NaN/Inf. */
fdi_status_t fdi_obs_reset(fdi_obs_t *self, const fdi_obs_coef_t *coef, float f, float y);

/* One sample: the estimate advances to this sample, *r = y - xh. NOT_FINITE (state, *r unchanged). */
fdi_status_t fdi_obs_step(fdi_obs_t *self, const fdi_obs_coef_t *coef, float f, float y, float *r);

#endif /* FDI_OBS_H */
