/* fdi_eval.c - test ratio, two-sided CUSUM and hysteresis of one residual (see fdi_eval.h). */
#include "fdi_eval.h"

#include <math.h>
#include <stddef.h>

#include "fdi_eval_internal.h"
#include "fdi_float.h"

static bool eval_positive_finite(float x)
{
    return fdi_float_is_finite(x) && (x > 0.0f);
}

fdi_status_t fdi_eval_init(fdi_eval_t *self, const fdi_eval_config_t *cfg)
{
    fdi_status_t st = FDI_OK;
    if ((self == NULL) || (cfg == NULL))
    {
        st = FDI_BAD_ARG;
    }
    else if (!fdi_float_is_finite(cfg->gate) || !fdi_float_is_finite(cfg->variance) ||
             !fdi_float_is_finite(cfg->cusum_k) || !fdi_float_is_finite(cfg->cusum_h))
    {
        st = FDI_NOT_FINITE;
    }
    else if (!eval_positive_finite(cfg->gate) || !eval_positive_finite(cfg->variance) || !eval_positive_finite(cfg->cusum_k) ||
             !eval_positive_finite(cfg->cusum_h) || (cfg->set_count == 0U) || (cfg->clear_count == 0U))
    {
        st = FDI_BAD_ARG;
    }
    else
    {
        const float sigma = sqrtf(cfg->variance);
        const float gate2 = cfg->gate * cfg->gate;
        /* both may underflow to 0 for tiny positive inputs: check before dividing */
        float inv_sigma = 0.0f;
        float inv_gate2 = 0.0f;
        if (sigma > 0.0f)
        {
            inv_sigma = 1.0f / sigma;
        }
        if (gate2 > 0.0f)
        {
            inv_gate2 = 1.0f / gate2;
        }
        if (!eval_positive_finite(inv_sigma) || !eval_positive_finite(inv_gate2))
        {
            st = FDI_BAD_ARG; /* variance or gate so small that the reciprocal is not representable */
        }
        else
        {
            self->inv_sigma = inv_sigma;
            self->inv_gate2 = inv_gate2;
            self->k = cfg->cusum_k;
            self->h = cfg->cusum_h;
            self->set_count = cfg->set_count;
            self->clear_count = cfg->clear_count;
            st = fdi_eval_reset(self);
        }
    }
    return st;
}

fdi_status_t fdi_eval_reset(fdi_eval_t *self)
{
    fdi_status_t st = FDI_BAD_ARG;
    if (self != NULL)
    {
        self->g_pos = 0.0f;
        self->g_neg = 0.0f;
        self->n_raw = 0U;
        self->n_quiet = 0U;
        self->alarm = false;
        st = FDI_OK;
    }
    return st;
}

/* The checked step of both entry points (one body: fdi_eval_step is fdi_eval_step_adaptive at allowance 0). */
static fdi_status_t eval_step(fdi_eval_t *self, float r, float allowance, fdi_eval_out_t *out)
{
    fdi_status_t st = FDI_OK;
    if ((self == NULL) || (out == NULL))
    {
        st = FDI_BAD_ARG;
    }
    else if (!fdi_float_is_finite(r) || !fdi_float_is_finite(allowance))
    {
        st = FDI_NOT_FINITE;
    }
    else if (allowance < 0.0f)
    {
        st = FDI_BAD_ARG;
    }
    else
    {
        float ratio = 0.0f;
        out->status = fdi_eval_update(self, r, allowance, &ratio) ? FDI_TEST_ALARM : FDI_TEST_OK;
        out->ratio = ratio;
    }
    return st;
}

fdi_status_t fdi_eval_step(fdi_eval_t *self, float r, fdi_eval_out_t *out)
{
    return eval_step(self, r, 0.0f, out);
}

fdi_status_t fdi_eval_step_adaptive(fdi_eval_t *self, float r, float allowance, fdi_eval_out_t *out)
{
    return eval_step(self, r, allowance, out);
}
