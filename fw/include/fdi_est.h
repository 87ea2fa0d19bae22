/*
 * fdi_est.h - on-line estimation of a residual's slowly varying offset, frozen while the test alarms.
 *
 * What it estimates: the part of a residual that a slowly varying nuisance adds at a constant sensitivity, an
 * offset b. For the inertial tests of a vehicle this is the lumped sum of what the accelerometer and gyro see that
 * the model does not: the sensor biases and the components of gravity on a grade or a bank (b_ax + g sin(theta) in
 * the longitudinal balance). The generators cannot tell these apart (they enter with the same sensitivity), and
 * the test needs only their sum, which is observable from the residual itself whenever no fault acts.
 *
 *   n = updates since init;  g_k = 1 / n while n <= startup, then dt / tau
 *   b[k] = clamp(b[k-1] + g_k * (r[k] - b[k-1]), -limit, +limit)          (not frozen)
 *   b[k] = b[k-1]                                                          (frozen)
 *   corrected residual: r[k] - b[k-1]   (the estimate before this sample: a step in r shows in full)
 *
 * Start-up: the first `startup` samples are averaged (g_k = 1/n): the estimate is their mean, within
 * sigma / sqrt(startup) of the offset (a tenth of sigma after 100 samples); afterwards it forgets with time constant
 * tau (its noise sigma * sqrt(g / (2 - g)), 0.02 sigma at g = dt / tau = 0.001), so a step that arrives right after
 * the start-up is absorbed at dt / tau per step, not at 1 / n.
 *
 * What it can tell from a fault, and what not:
 *   - an abrupt fault (a step, or a ramp faster than the offset's slowest expected change over tau) reaches the
 *     evaluator almost in full: in the set_count steps before the alarm the estimate moves by at most
 *     set_count * dt / tau of the step (0.3 % for 3 steps at 10 ms and tau = 10 s), and the diagnoser freezes the
 *     estimate while the test alarms and for the rest of an isolation episode that accuses it, so the fault
 *     cannot be absorbed later;
 *   - a fault present at start-up, or one that grows more slowly than the nuisance is allowed to change, is
 *     indistinguishable from the nuisance by this test: it is absorbed, up to `limit`. The limit is the largest
 *     offset the declared uncertainty explains (the generator's spread, fdi_gen.h), so any part beyond the envelope
 *     still alarms;
 *   - a nuisance that changes faster than tau allows (driving onto a steep ramp) is indistinguishable from a step
 *     fault: the test alarms, the estimate freezes and stays until the alarm clears.
 * Cost per update: 2 multiplications, 3 additions, 4 comparisons, no division after start-up (one per update
 * during it). Memory: 12 bytes (asserted below).
 */
#ifndef FDI_EST_H
#define FDI_EST_H

#include <stdbool.h>
#include <stdint.h>

#include "fdi_static_assert.h"
#include "fdi_status.h"

typedef struct
{
    float offset;  /* the estimate b (units of the residual) */
    float gain;       /* dt / tau */
    uint16_t n;       /* updates since init (saturating) */
    uint16_t startup; /* samples averaged at start-up, 1 .. tau / dt */
} fdi_est_t; /* opaque by convention */

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(sizeof(fdi_est_t) == 12U, fdi_sa_est_size);

/* dt > 0 [s], tau >= dt [s], startup in 1 .. tau / dt samples. BAD_ARG: NULL, dt <= 0, tau < dt, startup 0
   or (startup - 1) * dt >= tau; NOT_FINITE: NaN/Inf. Starts at offset 0 with the start-up average (so an init
   again forgets the estimate). */
fdi_status_t fdi_est_init(fdi_est_t *self, float dt, float tau, uint16_t startup);

/* One sample r of the residual; limit >= 0 bounds |offset|; freeze: keep the estimate. *corrected = r minus the
   estimate before this sample. BAD_ARG (state unchanged) for NULL or a negative limit; NOT_FINITE (state and
   *corrected unchanged) when r or limit is NaN/Inf. */
fdi_status_t fdi_est_update(fdi_est_t *self, float r, float limit, bool freeze, float *corrected);

/* The current estimate (0 for NULL). */
float fdi_est_offset(const fdi_est_t *self);

/* Whether the start-up average is complete (startup samples taken; false for NULL). */
bool fdi_est_ready(const fdi_est_t *self);

/* Updates (not frozen) since init, saturating at 65535 (0 for NULL). */
uint32_t fdi_est_samples(const fdi_est_t *self);

#endif /* FDI_EST_H */
