/* fdi_gen.c - generator parameters, input masks and dispatch on the kind (see fdi_gen.h). */
#include "fdi_gen.h"

#include <math.h>
#include <stdbool.h>
#include <stddef.h>

#include "fdi_arr_kin.h"
#include "fdi_gen_internal.h"
#include "fdi_float.h"

fdi_status_t fdi_gen_param_init(fdi_gen_param_t *par, const fdi_gen_config_t *cfg)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((par != NULL) && (cfg != NULL))
    {
        fdi_svf_coef_t svf = {0.0f, 0.0f, 0.0f};
        fdi_obs_coef_t obs = {0.0f, 0.0f, 0.0f};
        const fdi_svf_config_t svf_cfg = {cfg->dt, cfg->cutoff_hz, cfg->zeta};
        const fdi_obs_config_t obs_cfg = {cfg->dt, 0.0f, cfg->obs_gain};
        st = fdi_svf_design(&svf, &svf_cfg);
        if (st == FDI_OK)
        {
            st = fdi_obs_design(&obs, &obs_cfg);
        }
        if ((st == FDI_OK) && (!fdi_float_is_finite(cfg->d_x) || !fdi_float_is_finite(cfg->d_y)))
        {
            st = FDI_NOT_FINITE;
        }
        if (st == FDI_OK)
        {
            par->svf = svf;
            par->obs = obs;
            par->d_x = cfg->d_x;
            par->d_y = cfg->d_y;
        }
    }
    return st;
}

/* Slot of a generated kind, FDI_GEN_GENERATED_MAX for any other kind. */
static uint32_t generated_slot(fdi_gen_kind_t kind)
{
    const uint32_t k = (uint32_t)kind;
    const uint32_t first = (uint32_t)FDI_GEN_GENERATED_1;
    uint32_t slot = FDI_GEN_GENERATED_MAX;
    if (k >= first)
    {
        const uint32_t d = k - first;
        if (d < FDI_GEN_GENERATED_MAX)
        {
            slot = d;
        }
    }
    return slot;
}

static uint32_t generated_slot_inputs(fdi_gen_kind_t kind)
{
    const uint32_t slot = generated_slot(kind);
    return (slot < FDI_GEN_GENERATED_MAX) ? fdi_gen_generated_inputs(slot) : 0U;
}

uint32_t fdi_gen_inputs(fdi_gen_kind_t kind)
{
    uint32_t m;
    switch (kind)
    {
    case FDI_GEN_KIN_X_DERIV:
    case FDI_GEN_KIN_X_OBS:
        m = FDI_SIGM_AX_M | FDI_SIGM_PSIDOT_M | FDI_SIGM_VX_M | FDI_SIGM_VY_M;
        break;
    case FDI_GEN_KIN_Y_DERIV:
    case FDI_GEN_KIN_Y_OBS:
        m = FDI_SIGM_AY_M | FDI_SIGM_PSIDOT_M | FDI_SIGM_VX_M | FDI_SIGM_VY_M;
        break;
    case FDI_GEN_KIN_ARR3:
        m = FDI_SIGM_AX_M | FDI_SIGM_AY_M | FDI_SIGM_PSIDOT_M | FDI_SIGM_VX_M;
        break;
    case FDI_GEN_KIN_ARR4:
        m = FDI_SIGM_AX_M | FDI_SIGM_AY_M | FDI_SIGM_PSIDOT_M | FDI_SIGM_VY_M;
        break;
    case FDI_GEN_NONE:
        m = 0U;
        break;
    default:
        m = generated_slot_inputs(kind);
        break;
    }
    return m;
}

bool fdi_gen_in_domain(fdi_gen_kind_t kind, const fdi_inputs_t *in)
{
    bool ok = false;
    if (in != NULL)
    {
        const uint32_t slot = generated_slot(kind);
        ok = (slot < FDI_GEN_GENERATED_MAX) ? fdi_gen_generated_in_domain(slot, in) : true;
    }
    return ok;
}

fdi_status_t fdi_gen_init(fdi_gen_t *self, fdi_gen_kind_t kind)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((self != NULL) && (fdi_gen_inputs(kind) != 0U))
    {
        uint32_t i;
        self->kind = kind;
        for (i = 0U; i < FDI_GEN_MAX_FILTERS; ++i)
        {
            self->filt[i].x1 = 0.0f;
            self->filt[i].x2 = 0.0f;
            self->filt[i].u_prev = 0.0f;
        }
        self->obs.xh = 0.0f;
        self->obs.g_prev = 0.0f;
        st = FDI_OK;
    }
    return st;
}

fdi_status_t fdi_gen_run_checked(fdi_gen_t *self, const fdi_gen_param_t *par, const fdi_inputs_t *in, bool reset,
                                 float *r)
{
    fdi_status_t st;
    switch (self->kind)
    {
    case FDI_GEN_KIN_X_DERIV:
        st = fdi_arr_kin_x_deriv(self, par, in, reset, r);
        break;
    case FDI_GEN_KIN_Y_DERIV:
        st = fdi_arr_kin_y_deriv(self, par, in, reset, r);
        break;
    case FDI_GEN_KIN_ARR3:
        st = fdi_arr_kin_arr3(self, par, in, reset, r);
        break;
    case FDI_GEN_KIN_ARR4:
        st = fdi_arr_kin_arr4(self, par, in, reset, r);
        break;
    case FDI_GEN_KIN_X_OBS:
        st = fdi_arr_kin_x_obs(self, par, in, reset, r);
        break;
    case FDI_GEN_KIN_Y_OBS:
        st = fdi_arr_kin_y_obs(self, par, in, reset, r);
        break;
    case FDI_GEN_NONE:
        st = FDI_BAD_ARG;
        break;
    default:
    {
        const uint32_t slot = generated_slot(self->kind);
        st = (slot < FDI_GEN_GENERATED_MAX) ? fdi_gen_generated_step(slot, self, par, in, reset, r) : FDI_BAD_ARG;
        break;
    }
    }
    return st;
}

static fdi_status_t run(fdi_gen_t *self, const fdi_gen_param_t *par, const fdi_inputs_t *in, bool reset, float *r)
{
    fdi_status_t st;
    if ((self == NULL) || (par == NULL) || (in == NULL) || (r == NULL))
    {
        st = FDI_BAD_ARG;
    }
    else
    {
        const uint32_t need = fdi_gen_inputs(self->kind);
        if (need == 0U)
        {
            st = FDI_BAD_ARG;
        }
        else if ((fdi_signals_finite_mask(in) & need) != need)
        {
            st = FDI_NOT_FINITE;
        }
        else
        {
            st = fdi_gen_run_checked(self, par, in, reset, r);
        }
    }
    return st;
}

fdi_status_t fdi_gen_reset(fdi_gen_t *self, const fdi_gen_param_t *par, const fdi_inputs_t *in)
{
    float r = 0.0f;
    return run(self, par, in, true, &r);
}

fdi_status_t fdi_gen_step(fdi_gen_t *self, const fdi_gen_param_t *par, const fdi_inputs_t *in, float *r)
{
    return run(self, par, in, false, r);
}

fdi_status_t fdi_gen_filter_step(fdi_gen_t *g, const fdi_gen_param_t *par, uint32_t idx, float u, bool reset,
                                 fdi_svf_out_t *out)
{
    fdi_status_t st;
    if ((g == NULL) || (par == NULL) || (out == NULL) || (idx >= FDI_GEN_MAX_FILTERS))
    {
        st = FDI_BAD_ARG;
    }
    else if (reset)
    {
        st = fdi_svf_reset(&g->filt[idx], u);
        out->y = u;
        out->dy = 0.0f;
    }
    else
    {
        st = fdi_svf_step(&g->filt[idx], &par->svf, u, out);
    }
    return st;
}

fdi_status_t fdi_gen_status_worst(fdi_status_t a, fdi_status_t b)
{
    return (a != FDI_OK) ? a : b;
}

fdi_status_t fdi_gen_finish(fdi_status_t st, float value, bool reset, float *r)
{
    fdi_status_t res = st;
    if (r == NULL)
    {
        res = FDI_BAD_ARG;
    }
    else if ((res == FDI_OK) && !fdi_float_is_finite(value))
    {
        res = FDI_NOT_FINITE;
    }
    else if (res == FDI_OK)
    {
        *r = reset ? 0.0f : value;
    }
    else
    {
        /* the failing status is returned unchanged */
    }
    return res;
}

float fdi_gen_obs_predict(const fdi_gen_t *g, const fdi_gen_param_t *par, float g1, float jac)
{
    float xh = 0.0f;
    if ((g != NULL) && (par != NULL))
    {
        const float dt = 2.0f * par->svf.h;
        const float jdt = jac * dt;
        const float phi = (fabsf(jdt) > 1.0e-6f) ? (expm1f(jdt) / jac) : dt;
        xh = g->obs.xh + (phi * (0.5f * (g->obs.g_prev + g1)));
    }
    return xh;
}

fdi_status_t fdi_gen_obs_store(fdi_gen_t *g, float xh, float g_next)
{
    fdi_status_t st = FDI_OK;
    if (g == NULL)
    {
        st = FDI_BAD_ARG;
    }
    else if (!fdi_float_is_finite(xh) || !fdi_float_is_finite(g_next))
    {
        st = FDI_NOT_FINITE;
    }
    else
    {
        g->obs.xh = xh;
        g->obs.g_prev = g_next;
    }
    return st;
}

float fdi_gen_heaviside(float x)
{
    return (x > 0.0f) ? 1.0f : 0.0f;
}

float fdi_gen_sign(float x)
{
    float s = 0.0f;
    if (x > 0.0f)
    {
        s = 1.0f;
    }
    else if (x < 0.0f)
    {
        s = -1.0f;
    }
    else
    {
        /* 0 (and NaN, caught by the caller's finiteness check) */
    }
    return s;
}
