/* fdi_signals.c - finiteness mask of a signal frame (see fdi_signals.h). */
#include "fdi_signals.h"

#include <stddef.h>

#include "fdi_float.h"

#if (FDI_SIGM_ALL != ((1UL << FDI_SIG_COUNT) - 1UL))
#error "FDI_SIGM_ALL must have exactly FDI_SIG_COUNT bits"
#endif

static uint32_t finite_bit(float x, uint32_t mask)
{
    return fdi_float_is_finite(x) ? mask : 0U;
}

uint32_t fdi_signals_finite_mask(const fdi_inputs_t *in)
{
    uint32_t m = 0U;
    if (in != NULL)
    {
        m |= finite_bit(in->ax_m, FDI_SIGM_AX_M);
        m |= finite_bit(in->ay_m, FDI_SIGM_AY_M);
        m |= finite_bit(in->psidot_m, FDI_SIGM_PSIDOT_M);
        m |= finite_bit(in->vx_m, FDI_SIGM_VX_M);
        m |= finite_bit(in->vy_m, FDI_SIGM_VY_M);
        m |= finite_bit(in->delta1_m, FDI_SIGM_DELTA1_M);
        m |= finite_bit(in->delta2_m, FDI_SIGM_DELTA2_M);
        m |= finite_bit(in->delta3_m, FDI_SIGM_DELTA3_M);
        m |= finite_bit(in->delta4_m, FDI_SIGM_DELTA4_M);
        m |= finite_bit(in->iTM1_m, FDI_SIGM_ITM1_M);
        m |= finite_bit(in->iTM2_m, FDI_SIGM_ITM2_M);
        m |= finite_bit(in->iTM3_m, FDI_SIGM_ITM3_M);
        m |= finite_bit(in->iTM4_m, FDI_SIGM_ITM4_M);
        m |= finite_bit(in->P_f_m, FDI_SIGM_P_F_M);
        m |= finite_bit(in->P_r_m, FDI_SIGM_P_R_M);
        m |= finite_bit(in->omega1_m, FDI_SIGM_OMEGA1_M);
        m |= finite_bit(in->omega2_m, FDI_SIGM_OMEGA2_M);
        m |= finite_bit(in->omega3_m, FDI_SIGM_OMEGA3_M);
        m |= finite_bit(in->omega4_m, FDI_SIGM_OMEGA4_M);
    }
    return m;
}
