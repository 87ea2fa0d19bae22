/*
 * fdi_eval_internal.h - internal: one evaluation step for callers that have already checked the inputs
 * (fdi_diag evaluates every test of a step in one loop; inline there, it saves the call and the argument checks of
 * fdi_eval_step() per test). self must be non-NULL and initialised, r finite; the step is exactly fdi_eval_step()'s.
 */
#ifndef FDI_EVAL_INTERNAL_H
#define FDI_EVAL_INTERNAL_H

#include <stdbool.h>
#include <stdint.h>

#include "fdi_eval.h"

static inline float fdi_eval_cusum(float g, float inc, float h2)
{
    const float v = g + inc;
    return (v < 0.0f) ? 0.0f : ((v > h2) ? h2 : v);
}

static inline uint16_t fdi_eval_count_up(uint16_t n)
{
    return (n < UINT16_MAX) ? (uint16_t)(n + 1U) : n;
}

/* The test ratio r^2 / (gate^2 sigma^2) into *ratio, the CUSUM and the hysteresis; true while the test is in alarm. */
static inline bool fdi_eval_update(fdi_eval_t *self, float r, float *ratio)
{
    const float z = r * self->inv_sigma;
    const float q = z * z * self->inv_gate2; /* may be +Inf for huge r: still an alarm */
    const float h2 = 2.0f * self->h;
    bool raw;
    self->g_pos = fdi_eval_cusum(self->g_pos, z - self->k, h2);
    self->g_neg = fdi_eval_cusum(self->g_neg, -z - self->k, h2);
    raw = (q > 1.0f) || (self->g_pos > self->h) || (self->g_neg > self->h);
    if (!self->alarm)
    {
        self->n_raw = raw ? fdi_eval_count_up(self->n_raw) : 0U;
        if (self->n_raw >= self->set_count)
        {
            self->alarm = true;
            self->n_quiet = 0U;
        }
    }
    else
    {
        self->n_quiet = raw ? 0U : fdi_eval_count_up(self->n_quiet);
        if (self->n_quiet >= self->clear_count)
        {
            self->alarm = false;
            self->n_raw = 0U;
        }
    }
    *ratio = q;
    return self->alarm;
}

#endif /* FDI_EVAL_INTERNAL_H */
