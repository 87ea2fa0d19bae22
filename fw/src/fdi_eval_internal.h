/*
 * fdi_eval_internal.h - internal: one evaluation step for callers that have already checked the inputs
 * (fdi_diag evaluates every test of a step in one loop; inline there, it saves the call and the argument checks of
 * fdi_eval_step() per test). self must be non-NULL and initialised, r finite, a finite and >= 0; the step is exactly
 * fdi_eval_step_adaptive()'s.
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

/* The part of r beyond the allowance a >= 0 (the adaptive threshold's model-uncertainty term, fdi_eval.h): r shrunk
   towards 0 by a, 0 inside [-a, a]; exactly r for a = 0. */
static inline float fdi_eval_excess(float r, float a)
{
    float e = 0.0f;
    if (r > a)
    {
        e = r - a;
    }
    else if (r < -a)
    {
        e = r + a;
    }
    else
    {
        e = 0.0f;
    }
    return e;
}

/* The test ratio e^2 / (gate^2 sigma^2) of the excess e of r beyond the allowance a into *ratio, the CUSUM of e and
   the hysteresis; true while the test is in alarm. */
static inline bool fdi_eval_update(fdi_eval_t *self, float r, float a, float *ratio)
{
    const float z = fdi_eval_excess(r, a) * self->inv_sigma;
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
