/*
 * fdi_est.h - on-line estimation of what a test's model does not know, frozen while the test alarms.
 *
 * What it estimates: the deviations theta of a few of the vehicle's uncertain quantities from the model's values
 * (a rolling radius, the mass, an accelerometer's offset and tilt, the grade), as one test's residual sees them. To
 * first order the residual of a fault-free vehicle is
 *
 *   r[k] = h[k] . theta + v[k]        h[k] = d r / d theta at the step (the generator's regressors, fdi_gen.h)
 *
 * with v the residual's noise and what no declared quantity explains. What a residual's model leaves unexplained is
 * not white: it follows the manoeuvre over tenths of a second, so consecutive samples carry far less information than
 * white noise of the same variance would. The filter takes v's variance per sample as `noise` = sigma^2 * D (sigma
 * the test's calibrated standard deviation, D the decorrelation factor, fdi_diag_config_t.estimate_decorrelation)
 * and every declared q scaled by D alike: the same gains as with sigma^2 and q, so the same estimates, with an
 * uncertainty P D times larger (the Riccati equation is homogeneous in noise and q), which is what keeps the filter
 * from trusting a fit that the unexplained part made. A Kalman filter on theta (n <= FDI_EST_MAX_PARAMS quantities)
 * follows it:
 *
 *   predict   P += q_scale * Q  (per quantity its variance gain q per step, never beyond the prior variance)
 *   innovation  nu = r - h . theta        its spread  a = sqrt(h' P h)          (both before this sample)
 *   update    (not frozen, h != 0)   s = h' P h + noise,  K = P h / s,  theta += K nu,  P -= K (P h)'
 *             each quantity's move limited to its `step` (what it can change in one step: a fault that the
 *             estimate would follow faster is absorbed no faster than that), the part cut off added to its variance
 *             (the estimate is that much less certain; never beyond the prior variance), and theta clamped to the
 *             declared bounds [lo, hi]
 *
 * The test evaluates nu against gate * sigma + kappa * a (+ the spread of the quantities it does not estimate):
 * while the estimate is uncertain (the prior: the declared range) the threshold is as wide as the envelope, and it
 * narrows to the test's own noise as the drive teaches the filter the vehicle (fdi_diag.h). A quantity that enters
 * the residual as a constant (an offset: h = 1) converges like a running mean, sigma / sqrt(samples); one whose
 * regressor varies with the manoeuvre (the tilt of an accelerometer, d r / d c_ax = a_x) needs the manoeuvre to
 * excite it, and until then its share of the threshold stays wide (a = sqrt(h' P h) is large only where h is).
 *
 * What it can tell from a fault, and what not:
 *   - an abrupt fault (a step, or a ramp faster than the quantities' declared drift) reaches the evaluator almost
 *     in full: in the steps before the alarm the estimate moves by at most K h of it per step (small once the
 *     filter has converged), and the diagnoser freezes the filter while the test alarms and for the rest of an
 *     isolation episode that accuses it, so the fault is not absorbed later;
 *   - a fault whose effect on the residual is a combination of the regressors (an accelerometer offset against
 *     the estimated grade: both constants) present at start-up, or growing more slowly than the declared drift,
 *     is taken for the quantities, up to their bounds: beyond the declared range it still alarms;
 *   - a quantity that changes faster than its declared drift (driving onto a steep ramp) is indistinguishable
 *     from an abrupt fault: the test alarms, the filter freezes and keeps its estimate until the alarm clears.
 *
 * Cost per update (n quantities): about 2 n^2 + 6 n multiplications, as many additions, one division and one square
 * root; a frozen update n additions and one square root. Memory: 4 * (n_max + n_max (n_max + 1) / 2) bytes
 * (n_max = FDI_EST_MAX_PARAMS: 36 bytes at 3, asserted below); the quantities' declarations are const data of the
 * generator (fdi_gen_desc_t.est).
 */
#ifndef FDI_EST_H
#define FDI_EST_H

#include <stdbool.h>
#include <stdint.h>

#include "fdi_static_assert.h"
#include "fdi_status.h"

/* FDI_EST_MAX_PARAMS: quantities one test estimates, an overridable capacity (generated/fdi_capacity.h) */
#include "generated/fdi_capacity.h"
#define FDI_EST_P_SIZE ((FDI_EST_MAX_PARAMS * (FDI_EST_MAX_PARAMS + 1U)) / 2U) /* packed upper triangle of P */

/* One estimated quantity: its deviation from the model's value, in the quantity's units (const data). */
typedef struct
{
    float mean; /* prior mean of the deviation (the middle of the declared range minus the model's value) */
    float var;  /* prior variance, > 0 (a uniform range: width^2 / 12) */
    float q;    /* variance it may gain per step, >= 0 (from its declared drift: fdi_analysis.residuals.estimation) */
    float lo;   /* bounds of the deviation, lo <= mean <= hi */
    float hi;
    float step; /* the most the estimate moves in one step, > 0 (its declared drift, or its range over the learning
                   time, whichever is faster: fdi_analysis.residuals.estimation) */
} fdi_est_param_t;

typedef struct
{
    float theta[FDI_EST_MAX_PARAMS]; /* the estimated deviations */
    float p[FDI_EST_P_SIZE];         /* their covariance, upper triangle by rows */
} fdi_est_t; /* opaque by convention */

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(sizeof(fdi_est_t) == ((FDI_EST_MAX_PARAMS + FDI_EST_P_SIZE) * sizeof(float)), fdi_sa_est_size);

/* Whether param[0..n-1] declares n usable quantities: n in 1..FDI_EST_MAX_PARAMS, each finite with var > 0, q >= 0,
   lo <= mean <= hi and step > 0. OK, BAD_ARG (NULL, n out of range, a value out of its range) or NOT_FINITE. */
fdi_status_t fdi_est_check(const fdi_est_param_t *param, uint32_t n);

/* The n quantities of param[] (n in 1..FDI_EST_MAX_PARAMS, each with var > 0, q >= 0, lo <= mean <= hi, all
   finite). Starts at the prior (theta = mean, P = diag(var)); an init again forgets the estimate. BAD_ARG: NULL, n
   out of range, a declaration out of its ranges; NOT_FINITE: NaN/Inf in param. The quantities are not kept: every
   update takes the same param[] and n. */
fdi_status_t fdi_est_init(fdi_est_t *self, const fdi_est_param_t *param, uint32_t n);

/* One sample: h[0..n-1] the regressors at the step, r the residual, noise > 0 the variance per sample of what the
   declared quantities do not explain, q_scale >= 1 the factor of every declared q (the header comment); freeze:
   predict only (the estimate is kept, its uncertainty grows). *innovation = r - h . theta and *spread =
   sqrt(h' P h), both with the estimate before this sample. BAD_ARG (state unchanged) for NULL, n out of range,
   noise <= 0 or q_scale < 1; NOT_FINITE (state and outputs unchanged) when r, noise, q_scale or a regressor is
   NaN/Inf. */
fdi_status_t fdi_est_update(fdi_est_t *self, const fdi_est_param_t *param, uint32_t n, const float *h, float r,
                            float noise, float q_scale, bool freeze, float *innovation, float *spread);

/* Estimate k (0 for NULL or k out of range) and its standard deviation sqrt(P_kk). */
float fdi_est_value(const fdi_est_t *self, uint32_t k);
float fdi_est_std(const fdi_est_t *self, uint32_t k);

#endif /* FDI_EST_H */
