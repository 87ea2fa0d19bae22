/* fdi_deriv.c - first-order filtered derivative, Tustin with pre-warping (see fdi_deriv.h). */
#include "fdi_deriv.h"

#include <stddef.h>

#include "fdi_float.h"
#include "fdi_prewarp.h"

fdi_status_t fdi_deriv_design(fdi_deriv_coef_t *coef, const fdi_deriv_config_t *cfg)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((coef != NULL) && (cfg != NULL))
    {
        float w = 0.0f;
        st = fdi_prewarp_omega(cfg->dt, cfg->cutoff_hz, &w);
        if (st == FDI_OK)
        {
            const float wt = w * cfg->dt;
            coef->a = (2.0f - wt) / (2.0f + wt);
            coef->b = (2.0f * w) / (2.0f + wt);
            coef->tau = 1.0f / w;
        }
    }
    return st;
}

fdi_status_t fdi_deriv_reset(fdi_deriv_t *self, float u0)
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
        self->y = 0.0f;
        self->u_prev = u0;
    }
    return st;
}

fdi_status_t fdi_deriv_step(fdi_deriv_t *self, const fdi_deriv_coef_t *coef, float u, fdi_deriv_out_t *out)
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
        const float y = (coef->a * self->y) + (coef->b * (u - self->u_prev));
        const float uf = u - (coef->tau * y);
        if (!fdi_float_is_finite(y) || !fdi_float_is_finite(uf))
        {
            st = FDI_NOT_FINITE;
        }
        else
        {
            self->y = y;
            self->u_prev = u;
            out->y = uf;
            out->dy = y;
        }
    }
    return st;
}
