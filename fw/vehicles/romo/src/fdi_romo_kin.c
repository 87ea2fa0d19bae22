/* fdi_romo_kin.c - the hand-written kinematic residual generators MSO1..MSO4 (see fdi_romo_kin.h). */
#include "fdi_romo_kin.h"

#include <stdbool.h>
#include <stddef.h>

#include "fdi_float.h"
#include "fdi_gen_impl.h"
#include "fdi_romo_signals.h"

/* Filter slots. Stage 1 filters raw signals, stage 2 filters stage-1 outputs (r3, r4 only). */
#define S1_V 0U  /* the differentiated velocity (vx for MSO1/3, vy for MSO2/4) */
#define S1_A 1U  /* the acceleration on the same axis (ax_m for MSO1/3, ay_m for MSO2/4) */
#define S1_W 2U  /* yaw rate */
#define S1_O 3U  /* the other quantity (vy / vx for MSO1/2, ay_m / ax_m for MSO3/4) */
#define S2_P 4U  /* p or q */
#define S2_W 5U  /* yaw rate, second stage */
#define S2_O 6U  /* other acceleration, second stage */
#define S2_V 7U  /* velocity, second stage */

/* r = a_along - (dv/dt + sign * v_other * w), one filter stage: MSO1 (sign -1), MSO2 (sign +1). */
static fdi_status_t one_stage(fdi_gen_t *g, const fdi_gen_param_t *par, float v, float a_along, float w,
                              float v_other, float sign, bool reset, float *r)
{
    fdi_svf_out_t fv = {0.0f, 0.0f};
    fdi_svf_out_t fa = {0.0f, 0.0f};
    fdi_svf_out_t fw = {0.0f, 0.0f};
    fdi_svf_out_t fo = {0.0f, 0.0f};
    fdi_status_t st = fdi_gen_filter_step(g, par, S1_V, v, reset, &fv);
    st = fdi_gen_status_worst(st, fdi_gen_filter_step(g, par, S1_A, a_along, reset, &fa));
    st = fdi_gen_status_worst(st, fdi_gen_filter_step(g, par, S1_W, w, reset, &fw));
    st = fdi_gen_status_worst(st, fdi_gen_filter_step(g, par, S1_O, v_other, reset, &fo));
    return fdi_gen_finish(st, fa.y - (fv.dy + (sign * fo.y * fw.y)), reset, r);
}

/*
 * Two filter stages: pq = dv/dt - a_along; r = w*d/dt pq - pq*d/dt w + sign * (a_other + cross*v*w)*w^2.
 * MSO3: v = vx, a_along = ax_m, a_other = ay_m, cross = -1, sign = -1.
 * MSO4: v = vy, a_along = ay_m, a_other = ax_m, cross = +1, sign = +1.
 */
static fdi_status_t two_stage(fdi_gen_t *g, const fdi_gen_param_t *par, float v, float a_along, float w,
                              float a_other, float cross, float sign, bool reset, float *r)
{
    fdi_svf_out_t fv = {0.0f, 0.0f};
    fdi_svf_out_t fa = {0.0f, 0.0f};
    fdi_svf_out_t fw = {0.0f, 0.0f};
    fdi_svf_out_t fo = {0.0f, 0.0f};
    fdi_svf_out_t fp2 = {0.0f, 0.0f};
    fdi_svf_out_t fw2 = {0.0f, 0.0f};
    fdi_svf_out_t fo2 = {0.0f, 0.0f};
    fdi_svf_out_t fv2 = {0.0f, 0.0f};
    fdi_status_t st = fdi_gen_filter_step(g, par, S1_V, v, reset, &fv);
    st = fdi_gen_status_worst(st, fdi_gen_filter_step(g, par, S1_A, a_along, reset, &fa));
    st = fdi_gen_status_worst(st, fdi_gen_filter_step(g, par, S1_W, w, reset, &fw));
    st = fdi_gen_status_worst(st, fdi_gen_filter_step(g, par, S1_O, a_other, reset, &fo));
    st = fdi_gen_status_worst(st, fdi_gen_filter_step(g, par, S2_P, fv.dy - fa.y, reset, &fp2));
    st = fdi_gen_status_worst(st, fdi_gen_filter_step(g, par, S2_W, fw.y, reset, &fw2));
    st = fdi_gen_status_worst(st, fdi_gen_filter_step(g, par, S2_O, fo.y, reset, &fo2));
    st = fdi_gen_status_worst(st, fdi_gen_filter_step(g, par, S2_V, fv.y, reset, &fv2));
    {
        const float w2 = fw2.y;
        const float bracket = fo2.y + (cross * fv2.y * w2);
        const float value = ((w2 * fp2.dy) - (fp2.y * fw2.dy)) + (sign * bracket * w2 * w2);
        st = fdi_gen_finish(st, value, reset, r);
    }
    return st;
}

static fdi_status_t x_deriv(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_frame_t *in, bool reset, float *r,
                            float *sens) /* NOLINT(readability-non-const-parameter): the step type */
{
    const float w = in->value[ROMO_SIG_PSIDOT_M];
    const float vx = in->value[ROMO_SIG_VX_M] + (par->param[FDI_ROMO_KIN_PARAM_D_Y] * w);
    const float vy = in->value[ROMO_SIG_VY_M] - (par->param[FDI_ROMO_KIN_PARAM_D_X] * w);
    (void)sens; /* no sensitivities: sens_mask 0 */
    return one_stage(g, par, vx, in->value[ROMO_SIG_AX_M], w, vy, -1.0f, reset, r);
}

static fdi_status_t y_deriv(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_frame_t *in, bool reset, float *r,
                            float *sens) /* NOLINT(readability-non-const-parameter): the step type */
{
    const float w = in->value[ROMO_SIG_PSIDOT_M];
    const float vx = in->value[ROMO_SIG_VX_M] + (par->param[FDI_ROMO_KIN_PARAM_D_Y] * w);
    const float vy = in->value[ROMO_SIG_VY_M] - (par->param[FDI_ROMO_KIN_PARAM_D_X] * w);
    (void)sens; /* no sensitivities: sens_mask 0 */
    return one_stage(g, par, vy, in->value[ROMO_SIG_AY_M], w, vx, 1.0f, reset, r);
}

static fdi_status_t arr3(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_frame_t *in, bool reset, float *r,
                         float *sens) /* NOLINT(readability-non-const-parameter): the step type */
{
    const float w = in->value[ROMO_SIG_PSIDOT_M];
    const float vx = in->value[ROMO_SIG_VX_M] + (par->param[FDI_ROMO_KIN_PARAM_D_Y] * w);
    (void)sens; /* no sensitivities: sens_mask 0 */
    return two_stage(g, par, vx, in->value[ROMO_SIG_AX_M], w, in->value[ROMO_SIG_AY_M], -1.0f, -1.0f, reset, r);
}

static fdi_status_t arr4(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_frame_t *in, bool reset, float *r,
                         float *sens) /* NOLINT(readability-non-const-parameter): the step type */
{
    const float w = in->value[ROMO_SIG_PSIDOT_M];
    const float vy = in->value[ROMO_SIG_VY_M] - (par->param[FDI_ROMO_KIN_PARAM_D_X] * w);
    (void)sens; /* no sensitivities: sens_mask 0 */
    return two_stage(g, par, vy, in->value[ROMO_SIG_AY_M], w, in->value[ROMO_SIG_AX_M], 1.0f, 1.0f, reset, r);
}

static fdi_status_t observe(fdi_gen_t *g, const fdi_gen_param_t *par, float f, float y, bool reset, float *r)
{
    fdi_status_t st;
    float res = 0.0f;
    if (reset)
    {
        st = fdi_obs_reset(g->obs, &par->obs, f, y);
    }
    else
    {
        st = fdi_obs_step(g->obs, &par->obs, f, y, &res);
    }
    return fdi_gen_finish(st, res, reset, r);
}

static fdi_status_t x_obs(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_frame_t *in, bool reset, float *r,
                          float *sens) /* NOLINT(readability-non-const-parameter): the step type */
{
    const float w = in->value[ROMO_SIG_PSIDOT_M];
    const float vx = in->value[ROMO_SIG_VX_M] + (par->param[FDI_ROMO_KIN_PARAM_D_Y] * w);
    const float vy = in->value[ROMO_SIG_VY_M] - (par->param[FDI_ROMO_KIN_PARAM_D_X] * w);
    (void)sens; /* no sensitivities: sens_mask 0 */
    return observe(g, par, in->value[ROMO_SIG_AX_M] + (vy * w), vx, reset, r); /* K1 + D1: vx' = ax + vy w */
}

static fdi_status_t y_obs(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_frame_t *in, bool reset, float *r,
                          float *sens) /* NOLINT(readability-non-const-parameter): the step type */
{
    const float w = in->value[ROMO_SIG_PSIDOT_M];
    const float vx = in->value[ROMO_SIG_VX_M] + (par->param[FDI_ROMO_KIN_PARAM_D_Y] * w);
    const float vy = in->value[ROMO_SIG_VY_M] - (par->param[FDI_ROMO_KIN_PARAM_D_X] * w);
    (void)sens; /* no sensitivities: sens_mask 0 */
    return observe(g, par, in->value[ROMO_SIG_AY_M] - (vx * w), vy, reset, r); /* K2 + D2: vy' = ay - vx w */
}

/* Descriptors: name, step, domain (always), signals read, sensitivities (none), filters, observer states, no set,
   no rate gains, no estimable quantities, no range. */
const fdi_gen_desc_t fdi_romo_kin_x_deriv = {
    "MSO1", x_deriv, NULL, ROMO_SIGM_AX_M | ROMO_SIGM_PSIDOT_M | ROMO_SIGM_VX_M | ROMO_SIGM_VY_M,
    0U, 4U, 0U, NULL, 0U, 0U, NULL, 0U, NULL, NULL};
const fdi_gen_desc_t fdi_romo_kin_y_deriv = {
    "MSO2", y_deriv, NULL, ROMO_SIGM_AY_M | ROMO_SIGM_PSIDOT_M | ROMO_SIGM_VX_M | ROMO_SIGM_VY_M,
    0U, 4U, 0U, NULL, 0U, 0U, NULL, 0U, NULL, NULL};
const fdi_gen_desc_t fdi_romo_kin_arr3 = {
    "MSO3", arr3, NULL, ROMO_SIGM_AX_M | ROMO_SIGM_AY_M | ROMO_SIGM_PSIDOT_M | ROMO_SIGM_VX_M,
    0U, 8U, 0U, NULL, 0U, 0U, NULL, 0U, NULL, NULL};
const fdi_gen_desc_t fdi_romo_kin_arr4 = {
    "MSO4", arr4, NULL, ROMO_SIGM_AX_M | ROMO_SIGM_AY_M | ROMO_SIGM_PSIDOT_M | ROMO_SIGM_VY_M,
    0U, 8U, 0U, NULL, 0U, 0U, NULL, 0U, NULL, NULL};
const fdi_gen_desc_t fdi_romo_kin_x_obs = {
    "MSO1", x_obs, NULL, ROMO_SIGM_AX_M | ROMO_SIGM_PSIDOT_M | ROMO_SIGM_VX_M | ROMO_SIGM_VY_M,
    0U, 0U, 1U, NULL, 0U, 0U, NULL, 0U, NULL, NULL};
const fdi_gen_desc_t fdi_romo_kin_y_obs = {
    "MSO2", y_obs, NULL, ROMO_SIGM_AY_M | ROMO_SIGM_PSIDOT_M | ROMO_SIGM_VX_M | ROMO_SIGM_VY_M,
    0U, 0U, 1U, NULL, 0U, 0U, NULL, 0U, NULL, NULL};
