/* fdi_frame.c - finiteness mask of a signal frame (see fdi_frame.h). */
#include "fdi_frame.h"

#include <stddef.h>

#include "fdi_float.h"

uint32_t fdi_frame_finite_mask(const fdi_frame_t *frame, uint32_t mask)
{
    uint32_t m = 0U;
    if (frame != NULL)
    {
        uint32_t bit = 1U;
        uint32_t i;
        float zero = 0.0f;
        /* fast path: x * 0 is +-0 for a finite x and NaN for NaN and +-Inf, so the sum over every signal up to the
           highest bit of the mask is finite iff all of them are (IEEE arithmetic; no -ffast-math, fdi_float.h) */
        for (i = 0U; (i < FDI_FRAME_MAX_SIGNALS) && (bit <= mask); ++i)
        {
            zero += frame->value[i] * 0.0f;
            bit <<= 1U; /* 0 after bit 31: the loop ends by i */
        }
        if (fdi_float_is_finite(zero))
        {
            m = 0xFFFFFFFFU;
        }
        else
        {
            /* some signal is not finite: every signal up to the highest bit of the mask, one by one */
            bit = 1U;
            for (i = 0U; (i < FDI_FRAME_MAX_SIGNALS) && (bit <= mask); ++i)
            {
                if (fdi_float_is_finite(frame->value[i]))
                {
                    m |= bit;
                }
                bit <<= 1U;
            }
        }
    }
    return m & mask;
}
