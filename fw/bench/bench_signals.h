/*
 * bench_signals.h - synthetic input frames for the benchmarks: the reference turn of the unit tests
 * (vx 10 m/s, yaw rate 0.5 rad/s, sinusoidal manoeuvres) in float, without noise. Header-only.
 */
#ifndef BENCH_SIGNALS_H
#define BENCH_SIGNALS_H

#include <math.h>

#include "fdi_diag.h"
#include "fdi_signals.h"

#define BENCH_DT 0.01f
#define BENCH_DX 1.2f
#define BENCH_DY 0.3f

static inline void bench_frame(float t, fdi_inputs_t *in)
{
    const float wv = 0.6283185f;
    const float wy = 1.2566371f;
    const float ww = 1.5707963f;
    const float vx = 10.0f + sinf(wv * t);
    const float vy = 0.3f * sinf((wy * t) + 0.5f);
    const float w = 0.5f + (0.1f * sinf(ww * t));
    in->ax_m = (wv * cosf(wv * t)) - (vy * w);
    in->ay_m = (0.3f * wy * cosf((wy * t) + 0.5f)) + (vx * w);
    in->psidot_m = w;
    in->vx_m = vx - (BENCH_DY * w);
    in->vy_m = vy + (BENCH_DX * w);
    in->delta1_m = 0.05f;
    in->delta2_m = 0.05f;
    in->delta3_m = 0.0f;
    in->delta4_m = 0.0f;
    in->iTM1_m = 20.0f;
    in->iTM2_m = 20.0f;
    in->iTM3_m = 20.0f;
    in->iTM4_m = 20.0f;
    in->P_f_m = 0.0f;
    in->P_r_m = 0.0f;
    in->omega1_m = 50.0f;
    in->omega2_m = 50.0f;
    in->omega3_m = 50.0f;
    in->omega4_m = 50.0f;
}

static inline fdi_diag_config_t bench_config(const fdi_table_t *table)
{
    fdi_diag_config_t c;
    c.table = table;
    c.d_x = BENCH_DX;
    c.d_y = BENCH_DY;
    c.cusum_k = 1.5f;
    c.cusum_h = 150.0f;
    c.set_count = 10U;
    c.clear_count = 100U;
    c.warmup_steps = 320U;
    c.mode = FDI_ISO_EXONERATION;
    c.iso_settle_steps = 0U;
    c.episode_clear_steps = 1U;
    return c;
}

#endif /* BENCH_SIGNALS_H */
