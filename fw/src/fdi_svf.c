/* fdi_svf.c - second-order state-variable filter, trapezoidal/Tustin with pre-warping (see fdi_svf.h). */
#include "fdi_svf.h"

#include <stddef.h>

#include "fdi_float.h"
#include "fdi_prewarp.h"

#define FDI_SVF_ZETA_MIN 0.1f
#define FDI_SVF_ZETA_MAX 2.0f

fdi_status_t fdi_svf_design(fdi_svf_coef_t *coef, const fdi_svf_config_t *cfg)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((coef != NULL) && (cfg != NULL))
    {
        float w = 0.0f;
        st = fdi_prewarp_omega(cfg->dt, cfg->cutoff_hz, &w);
        if ((st == FDI_OK) && !fdi_float_is_finite(cfg->zeta))
        {
            st = FDI_NOT_FINITE;
        }
        else if ((st == FDI_OK) && ((cfg->zeta < FDI_SVF_ZETA_MIN) || (cfg->zeta > FDI_SVF_ZETA_MAX)))
        {
            st = FDI_BAD_ARG;
        }
        else if (st == FDI_OK)
        {
            const float h = 0.5f * cfg->dt;
            const float wh = w * h;
            const float two_zwh = 2.0f * cfg->zeta * wh;
            const float d = 1.0f + two_zwh + (wh * wh);
            coef->h = h;
            coef->c1 = (1.0f - two_zwh) / d;
            coef->c2 = (w * wh) / d;
        }
        else
        {
            /* st already carries the error of fdi_prewarp_omega() */
        }
    }
    return st;
}

fdi_status_t fdi_svf_reset(fdi_svf_t *self, float u0)
{
    fdi_status_t st = FDI_OK;
    if (self == NULL)
    {
        st = FDI_BAD_ARG;
    }
    else if (!fdi_float_is_finite(u0))
    {
        st = FDI_NOT_FINITE;
    }
    else
    {
        self->x1 = u0;
        self->x2 = 0.0f;
        self->u_prev = u0;
    }
    return st;
}

fdi_status_t fdi_svf_step(fdi_svf_t *self, const fdi_svf_coef_t *coef, float u, fdi_svf_out_t *out)
{
    fdi_status_t st = FDI_OK;
    if ((self == NULL) || (coef == NULL) || (out == NULL))
    {
        st = FDI_BAD_ARG;
    }
    else if (!fdi_float_is_finite(u))
    {
        st = FDI_NOT_FINITE;
    }
    else
    {
        const float e_sum = (self->u_prev - self->x1) + (u - self->x1);
        const float x2 = (coef->c1 * self->x2) + (coef->c2 * (e_sum - (coef->h * self->x2)));
        const float x1 = self->x1 + (coef->h * (self->x2 + x2));
        if (!fdi_float_is_finite(x1) || !fdi_float_is_finite(x2))
        {
            st = FDI_NOT_FINITE;
        }
        else
        {
            self->x1 = x1;
            self->x2 = x2;
            self->u_prev = u;
            out->y = x1;
            out->dy = x2;
        }
    }
    return st;
}
