/* fdi_prewarp.c - pre-warped cut-off for the bilinear transform (see fdi_prewarp.h). */
#include "fdi_prewarp.h"

#include <math.h>
#include <stddef.h>

#include "fdi_float.h"

#define FDI_PI_F 3.14159265358979f

fdi_status_t fdi_prewarp_omega(float dt, float cutoff_hz, float *w)
{
    fdi_status_t st = FDI_OK;
    if (w == NULL)
    {
        st = FDI_BAD_ARG;
    }
    else if (!fdi_float_is_finite(dt) || !fdi_float_is_finite(cutoff_hz))
    {
        st = FDI_NOT_FINITE;
    }
    else if ((dt <= 0.0f) || (cutoff_hz <= 0.0f) || ((cutoff_hz * dt) >= 0.5f))
    {
        st = FDI_BAD_ARG;
    }
    else
    {
        const float wv = (2.0f / dt) * tanf(FDI_PI_F * cutoff_hz * dt);
        if (!fdi_float_is_finite(wv) || (wv <= 0.0f))
        {
            st = FDI_BAD_ARG;
        }
        else
        {
            *w = wv;
        }
    }
    return st;
}
