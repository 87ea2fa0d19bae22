/*
 * fdi_eval.h - residual evaluation: test ratio, two-sided CUSUM, set/clear hysteresis.
 *
 * With sigma^2 = variance and z = r / sigma (normalised residual):
 *   ratio[k] = r^2 / (gate^2 * sigma^2)                       (> 1: the sample is outside the gate)
 *   g+[k] = min(max(0, g+[k-1] + z - k_drift), 2h),  g-[k] = min(max(0, g-[k-1] - z - k_drift), 2h)
 *   raw[k] = ratio > 1  or  g+ > h  or  g- > h
 * Adaptive threshold (fdi_eval_step_adaptive): with an allowance a >= 0 in units of r, the residual's worst-case
 * spread over what the model does not know at this step (sum over the uncertain quantities theta of
 * |d r / d theta| * dtheta, computed by the generator from its operating point: fdi_gen.h), the same rule runs on the
 * excess e = r shrunk towards 0 by a (e = 0 for |r| <= a): ratio = e^2 / (gate^2 sigma^2) > 1 exactly where
 * |r| > gate * sigma + a, and the CUSUM integrates e / sigma, so an offset the uncertainty explains builds no
 * CUSUM. a = 0 is the fixed gate, bit for bit (fdi_eval_step).
 * The CUSUM catches small persistent offsets (mean shift > k_drift sigma) that stay inside the gate; the
 * clamp at 2h bounds the time it needs to clear after a fault disappears (< 2h / k_drift steps).
 * Hysteresis: the alarm sets after set_count consecutive raw samples and clears after clear_count
 * consecutive quiet samples. A non-finite residual is rejected: FDI_NOT_FINITE, state unchanged.
 * The diagnoser decides "not evaluable" (invalid inputs, warm-up) and then restarts the evaluator with
 * fdi_eval_reset(), so an evaluator itself only reports FDI_TEST_OK or FDI_TEST_ALARM.
 * Cost per step: 4 multiplications, 5 additions, 9 comparisons, no division (1/sigma and 1/gate^2 precomputed).
 * Memory: 36 bytes (asserted below).
 */
#ifndef FDI_EVAL_H
#define FDI_EVAL_H

#include <stdbool.h>
#include <stdint.h>

#include "fdi_static_assert.h"
#include "fdi_status.h"

typedef enum
{
    FDI_TEST_OK = 0,            /* evaluable and consistent */
    FDI_TEST_ALARM = 1,         /* evaluable and inconsistent (after hysteresis) */
    FDI_TEST_NOT_EVALUABLE = 2  /* inputs invalid/stale, warming up, or no generator */
} fdi_test_status_t;

typedef struct
{
    float gate;         /* threshold in sigmas, > 0 */
    float variance;     /* fault-free residual variance, > 0 */
    float cusum_k;      /* CUSUM drift in sigmas, > 0 (0.5 detects a 1-sigma mean shift) */
    float cusum_h;      /* CUSUM threshold in sigmas, > 0 */
    uint16_t set_count;   /* consecutive raw alarms to set, >= 1 */
    uint16_t clear_count; /* consecutive quiet samples to clear, >= 1 */
} fdi_eval_config_t;

typedef struct
{
    float inv_sigma;
    float inv_gate2;
    float k;
    float h;
    float g_pos;
    float g_neg;
    uint16_t set_count;
    uint16_t clear_count;
    uint16_t n_raw;   /* consecutive raw alarms (while quiet) */
    uint16_t n_quiet; /* consecutive quiet samples (while alarmed) */
    bool alarm;
} fdi_eval_t; /* opaque by convention */

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(sizeof(fdi_eval_t) == 36U, fdi_sa_eval_size);

typedef struct
{
    fdi_test_status_t status;
    float ratio; /* r^2 / (gate^2 sigma^2) of this sample */
} fdi_eval_out_t;

/* BAD_ARG: NULL, non-positive values, zero counts; NOT_FINITE: NaN/Inf. Starts quiet (FDI_TEST_OK). */
fdi_status_t fdi_eval_init(fdi_eval_t *self, const fdi_eval_config_t *cfg);

/* Forget the history: CUSUM 0, counters 0, no alarm. */
fdi_status_t fdi_eval_reset(fdi_eval_t *self);

/* Evaluate one residual sample at the fixed gate. NOT_FINITE (state and *out unchanged) when r is NaN/Inf. */
fdi_status_t fdi_eval_step(fdi_eval_t *self, float r, fdi_eval_out_t *out);

/* Evaluate one residual sample against the adaptive threshold gate * sigma + allowance (see above); out->ratio is the
   excess's ratio. BAD_ARG (state unchanged) for a negative allowance; NOT_FINITE (state and *out unchanged) when r
   or the allowance is NaN/Inf. */
fdi_status_t fdi_eval_step_adaptive(fdi_eval_t *self, float r, float allowance, fdi_eval_out_t *out);

#endif /* FDI_EVAL_H */
