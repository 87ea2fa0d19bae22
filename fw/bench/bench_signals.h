/*
 * bench_signals.h - synthetic ROMO frames for the benchmarks: the reference turn of the unit tests (vx 10 m/s,
 * yaw rate 0.5 rad/s, sinusoidal manoeuvres) in float, without noise; the tables benchmarked. Header-only.
 */
#ifndef BENCH_SIGNALS_H
#define BENCH_SIGNALS_H

#include <math.h>

#include "fdi_diag.h"
#include "fdi_kin_table.h"
#include "fdi_romo_kin.h"
#include "fdi_romo_signals.h"
#include "fdi_romo_table.h"

#define BENCH_DT 0.01f
#define BENCH_DX 1.2f
#define BENCH_DY 0.3f

static inline void bench_frame(float t, fdi_frame_t *in)
{
    uint32_t i;
    const float wv = 0.6283185f;
    const float wy = 1.2566371f;
    const float ww = 1.5707963f;
    const float vx = 10.0f + sinf(wv * t);
    const float vy = 0.3f * sinf((wy * t) + 0.5f);
    const float w = 0.5f + (0.1f * sinf(ww * t));
    for (i = 0U; i < FDI_FRAME_MAX_SIGNALS; ++i)
    {
        in->value[i] = 0.0f;
    }
    in->value[ROMO_SIG_AX_M] = (wv * cosf(wv * t)) - (vy * w);
    in->value[ROMO_SIG_AY_M] = (0.3f * wy * cosf((wy * t) + 0.5f)) + (vx * w);
    in->value[ROMO_SIG_PSIDOT_M] = w;
    in->value[ROMO_SIG_VX_M] = vx - (BENCH_DY * w);
    in->value[ROMO_SIG_VY_M] = vy + (BENCH_DX * w);
    in->value[ROMO_SIG_DELTA1_M] = 0.05f;
    in->value[ROMO_SIG_DELTA2_M] = 0.05f;
    in->value[ROMO_SIG_DELTA3_M] = 0.0f;
    in->value[ROMO_SIG_DELTA4_M] = 0.0f;
    in->value[ROMO_SIG_ITM1_M] = 20.0f;
    in->value[ROMO_SIG_ITM2_M] = 20.0f;
    in->value[ROMO_SIG_ITM3_M] = 20.0f;
    in->value[ROMO_SIG_ITM4_M] = 20.0f;
    in->value[ROMO_SIG_P_F_M] = 0.0f;
    in->value[ROMO_SIG_P_R_M] = 0.0f;
    in->value[ROMO_SIG_OMEGA1_M] = 50.0f;
    in->value[ROMO_SIG_OMEGA2_M] = 50.0f;
    in->value[ROMO_SIG_OMEGA3_M] = 50.0f;
    in->value[ROMO_SIG_OMEGA4_M] = 50.0f;
}

/* The tables benchmarked: the kinematic table (4 hand-written tests) and the generated ROMO table. */
#define BENCH_N_TABLES 2U
static inline const fdi_table_t *bench_table(uint32_t k, const char **name)
{
    *name = (k == 0U) ? "kinematic table" : "generated ROMO table";
    return (k == 0U) ? &fdi_kin_table : &fdi_romo_table;
}

static inline fdi_diag_config_t bench_config(const fdi_table_t *table)
{
    fdi_diag_config_t c;
    uint32_t i;
    c.table = table;
    for (i = 0U; i < FDI_GEN_N_PARAMS; ++i)
    {
        c.gen_param[i] = 0.0f;
    }
    c.gen_param[FDI_ROMO_KIN_PARAM_D_X] = BENCH_DX;
    c.gen_param[FDI_ROMO_KIN_PARAM_D_Y] = BENCH_DY;
    c.cusum_k = 1.5f;
    c.cusum_h = 150.0f;
    c.set_count = 10U;
    c.clear_count = 100U;
    c.warmup_steps = 320U;
    c.mode = FDI_ISO_EXONERATION;
    c.noise_allowance = 3.0f;
    c.episode_clear_steps = 1U;
    c.sensitivities = false;
    return c;
}

#endif /* BENCH_SIGNALS_H */
