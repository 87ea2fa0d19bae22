/* fdi_est.c - a residual's slowly varying offset, frozen while the test alarms (see fdi_est.h). */
#include "fdi_est.h"

#include <stddef.h>

#include "fdi_float.h"

fdi_status_t fdi_est_init(fdi_est_t *self, float dt, float tau, uint16_t startup)
{
    fdi_status_t st = FDI_OK;
    if (self == NULL)
    {
        st = FDI_BAD_ARG;
    }
    else if (!fdi_float_is_finite(dt) || !fdi_float_is_finite(tau))
    {
        st = FDI_NOT_FINITE;
    }
    else if ((dt <= 0.0f) || (tau < dt) || (startup == 0U) ||
             ((((float)startup - 1.0f) * dt) >= tau))
    {
        st = FDI_BAD_ARG;
    }
    else
    {
        self->gain = dt / tau; /* in (0, 1] */
        self->offset = 0.0f;
        self->n = 0U;
        self->startup = startup;
    }
    return st;
}

fdi_status_t fdi_est_update(fdi_est_t *self, float r, float limit, bool freeze, float *corrected)
{
    fdi_status_t st = FDI_OK;
    if ((self == NULL) || (corrected == NULL))
    {
        st = FDI_BAD_ARG;
    }
    else if (!fdi_float_is_finite(r) || !fdi_float_is_finite(limit))
    {
        st = FDI_NOT_FINITE;
    }
    else if (limit < 0.0f)
    {
        st = FDI_BAD_ARG;
    }
    else
    {
        *corrected = r - self->offset;
        if (!freeze)
        {
            float g = self->gain;
            float b;
            if (self->n < 0xFFFFU)
            {
                self->n++;
            }
            if (self->n <= self->startup) /* start-up: the running mean of the samples so far */
            {
                g = 1.0f / (float)self->n;
            }
            b = self->offset + (g * (r - self->offset));
            if (b > limit)
            {
                b = limit;
            }
            else if (b < -limit)
            {
                b = -limit;
            }
            else
            {
                /* inside the bound */
            }
            self->offset = b;
        }
    }
    return st;
}

float fdi_est_offset(const fdi_est_t *self)
{
    return (self == NULL) ? 0.0f : self->offset;
}

bool fdi_est_ready(const fdi_est_t *self)
{
    return (self != NULL) && (self->n >= self->startup);
}

uint32_t fdi_est_samples(const fdi_est_t *self)
{
    return (self == NULL) ? 0U : self->n;
}
