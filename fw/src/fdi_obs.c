/* fdi_obs.c - constant-gain scalar observer, exact zero-order-hold discretisation (see fdi_obs.h). */
#include "fdi_obs.h"

#include <math.h>
#include <stddef.h>

#include "fdi_float.h"

fdi_status_t fdi_obs_design(fdi_obs_coef_t *coef, const fdi_obs_config_t *cfg)
{
    fdi_status_t st = FDI_OK;
    if ((coef == NULL) || (cfg == NULL))
    {
        st = FDI_BAD_ARG;
    }
    else if (!fdi_float_is_finite(cfg->dt) || !fdi_float_is_finite(cfg->a) || !fdi_float_is_finite(cfg->gain))
    {
        st = FDI_NOT_FINITE;
    }
    else if ((cfg->dt <= 0.0f) || ((cfg->a - cfg->gain) >= 0.0f))
    {
        st = FDI_BAD_ARG;
    }
    else
    {
        const float lambda = cfg->a - cfg->gain;
        const float em1 = expm1f(lambda * cfg->dt); /* exp(lambda dt) - 1 without cancellation */
        coef->ad = 1.0f + em1;
        coef->bd = em1 / lambda;
        coef->gain = cfg->gain;
    }
    return st;
}

fdi_status_t fdi_obs_reset(fdi_obs_t *self, const fdi_obs_coef_t *coef, float f, float y)
{
    fdi_status_t st = FDI_OK;
    if ((self == NULL) || (coef == NULL))
    {
        st = FDI_BAD_ARG;
    }
    else if (!fdi_float_is_finite(f) || !fdi_float_is_finite(y))
    {
        st = FDI_NOT_FINITE;
    }
    else
    {
        const float g = f + (coef->gain * y);
        if (!fdi_float_is_finite(g))
        {
            st = FDI_NOT_FINITE;
        }
        else
        {
            self->xh = y;
            self->g_prev = g;
        }
    }
    return st;
}

fdi_status_t fdi_obs_step(fdi_obs_t *self, const fdi_obs_coef_t *coef, float f, float y, float *r)
{
    fdi_status_t st = FDI_OK;
    if ((self == NULL) || (coef == NULL) || (r == NULL))
    {
        st = FDI_BAD_ARG;
    }
    else if (!fdi_float_is_finite(f) || !fdi_float_is_finite(y))
    {
        st = FDI_NOT_FINITE;
    }
    else
    {
        const float g = f + (coef->gain * y);
        const float xh = (coef->ad * self->xh) + (coef->bd * (0.5f * (self->g_prev + g)));
        const float res = y - xh;
        if (!fdi_float_is_finite(g) || !fdi_float_is_finite(xh) || !fdi_float_is_finite(res))
        {
            st = FDI_NOT_FINITE;
        }
        else
        {
            *r = res;
            self->xh = xh;
            self->g_prev = g;
        }
    }
    return st;
}
