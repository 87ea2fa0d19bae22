/* fdi_gen.c - generator parameters, descriptors, dispatch and the building blocks (see fdi_gen.h). */
#include "fdi_gen.h"

#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stddef.h>

#include "fdi_float.h"
#include "fdi_gen_impl.h"
#include "fdi_gen_internal.h"

fdi_status_t fdi_gen_param_init(fdi_gen_param_t *par, const fdi_gen_config_t *cfg)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((par != NULL) && (cfg != NULL))
    {
        fdi_svf_coef_t svf = {0.0f, 0.0f, 0.0f};
        fdi_obs_coef_t obs = {0.0f, 0.0f, 0.0f};
        const fdi_svf_config_t svf_cfg = {cfg->dt, cfg->cutoff_hz, cfg->zeta};
        const fdi_obs_config_t obs_cfg = {cfg->dt, 0.0f, cfg->obs_gain};
        uint32_t i;
        st = fdi_svf_design(&svf, &svf_cfg);
        if (st == FDI_OK)
        {
            st = fdi_obs_design(&obs, &obs_cfg);
        }
        for (i = 0U; (st == FDI_OK) && (i < FDI_GEN_N_PARAMS); ++i)
        {
            if (!fdi_float_is_finite(cfg->param[i]))
            {
                st = FDI_NOT_FINITE;
            }
        }
        if (st == FDI_OK)
        {
            par->svf = svf;
            par->obs = obs;
            for (i = 0U; i < FDI_GEN_N_PARAMS; ++i)
            {
                par->param[i] = cfg->param[i];
            }
        }
    }
    return st;
}

fdi_status_t fdi_gen_set_check(const fdi_gen_set_t *set)
{
    bool ok = (set != NULL) && (set->name != NULL) && (set->step != NULL) && (set->n_slots >= 1U) &&
              ((uint32_t)set->n_slots <= FDI_GEN_MAX_SLOTS) && ((set->bank != NULL) || (set->n_bank == 0U));
    uint32_t k;
    for (k = 0U; ok && (k < (uint32_t)set->n_bank); ++k)
    {
        const fdi_gen_bank_filter_t *f = &set->bank[k];
        if ((uint32_t)f->signal >= FDI_FRAME_MAX_SIGNALS)
        {
            ok = false;
        }
        else if (f->source == FDI_GEN_BANK_RAW)
        {
            ok = f->order == 0U;
        }
        else
        {
            ok = ((uint32_t)f->source < k) && (set->bank[f->source].signal == f->signal) && (f->order <= 1U);
        }
    }
    if (ok)
    {
        if (set->derive == NULL)
        {
            ok = (uint32_t)set->n_derived == 0U;
        }
        else
        {
            ok = ((uint32_t)set->n_derived >= 1U) && (set->derived != NULL);
        }
    }
    if (ok && ((uint32_t)set->n_derived > 0U))
    {
        const uint32_t places = fdi_gen_derived_signals(set);
        uint32_t seen = 0U;
        for (k = 0U; ok && (k < (uint32_t)set->n_derived); ++k)
        {
            const fdi_gen_derived_t *d = &set->derived[k];
            const uint32_t bit = (uint32_t)1U << (d->signal & 31U);
            ok = ((uint32_t)d->signal < FDI_FRAME_MAX_SIGNALS) && (d->sources != 0U) &&
                 ((d->sources & places) == 0U) && ((seen & bit) == 0U);
            seen |= bit;
        }
    }
    return ok ? FDI_OK : FDI_BAD_ARG;
}

/* The rate gains of a descriptor: none, or disjoint from its sensitivities with a finite non-zero gain per bit. */
static bool rates_usable(const fdi_gen_desc_t *desc)
{
    bool ok = (desc->rate_mask & desc->sens_mask) == 0U;
    if (ok && (desc->rate_mask != 0U))
    {
        ok = desc->rate_gain != NULL;
        if (ok)
        {
            uint32_t left = desc->rate_mask;
            uint32_t k = 0U;
            while (ok && (left != 0U))
            {
                /* finite and non-zero in one range check (false for NaN); written out rather than with
                   fdi_float_is_finite, whose one more call here makes gcc -Os stop inlining it into the bank step */
                const float g = fabsf(desc->rate_gain[k]);
                ok = (g > 0.0f) && (g <= FLT_MAX);
                left &= left - 1U;
                ++k;
            }
        }
    }
    return ok;
}

fdi_status_t fdi_gen_desc_check(const fdi_gen_desc_t *desc)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((desc != NULL) && (desc->name != NULL) && (desc->input_mask != 0U) && (desc->n_obs <= 1U) &&
        rates_usable(desc) &&
        ((desc->n_est == 0U) || (fdi_est_check(desc->est, (uint32_t)desc->n_est) == FDI_OK)))
    {
        if ((desc->step != NULL) && (desc->set == NULL))
        {
            st = ((uint32_t)desc->n_filters <= FDI_GEN_MAX_FILTERS) ? FDI_OK : FDI_BAD_ARG;
        }
        else if ((desc->step == NULL) && (fdi_gen_set_check(desc->set) == FDI_OK))
        {
            st = ((desc->n_filters == 0U) && (desc->slot < desc->set->n_slots)) ? FDI_OK : FDI_BAD_ARG;
        }
        else
        {
            /* neither a hand-written generator nor a slot of a usable set */
        }
    }
    return st;
}

uint32_t fdi_gen_bank_signals(const fdi_gen_set_t *set)
{
    uint32_t m = 0U;
    if (set != NULL)
    {
        uint32_t k;
        for (k = 0U; k < (uint32_t)set->n_bank; ++k)
        {
            m |= (uint32_t)1U << (set->bank[k].signal & 31U);
        }
    }
    return m;
}

uint32_t fdi_gen_derived_signals(const fdi_gen_set_t *set)
{
    uint32_t m = 0U;
    if ((set != NULL) && (set->derived != NULL))
    {
        uint32_t k;
        for (k = 0U; k < (uint32_t)set->n_derived; ++k)
        {
            m |= (uint32_t)1U << (set->derived[k].signal & 31U);
        }
    }
    return m;
}

uint32_t fdi_gen_derive(const fdi_gen_set_t *set, fdi_frame_t *frame, uint32_t usable)
{
    uint32_t out = usable;
    if ((set != NULL) && (frame != NULL) && (set->derive != NULL) && (set->derived != NULL))
    {
        uint32_t k;
        set->derive(frame);
        for (k = 0U; k < (uint32_t)set->n_derived; ++k)
        {
            const fdi_gen_derived_t *d = &set->derived[k];
            const uint32_t bit = (uint32_t)1U << (d->signal & 31U);
            out &= ~bit; /* usable only as computed here, never from the caller's validity */
            if ((usable & d->sources) == d->sources)
            {
                if (fdi_float_is_finite(frame->value[d->signal & 31U]))
                {
                    out |= bit;
                }
                else
                {
                    out &= ~d->sources;
                }
            }
        }
    }
    return out;
}

uint32_t fdi_gen_bank_step(const fdi_gen_set_t *set, fdi_svf_t *bank, const fdi_svf_coef_t *coef,
                           const fdi_frame_t *in, uint32_t usable, uint32_t live)
{
    uint32_t failed = 0U;
    if ((set != NULL) && (bank != NULL) && (coef != NULL) && (in != NULL))
    {
        const float h = coef->h;
        const float c1 = coef->c1;
        const float c2 = coef->c2;
        uint32_t running = usable; /* signals whose filters run: usable, less those whose filter failed in this step */
        uint32_t k;
        for (k = 0U; k < (uint32_t)set->n_bank; ++k)
        {
            const fdi_gen_bank_filter_t *f = &set->bank[k];
            const uint32_t bit = (uint32_t)1U << (f->signal & 31U);
            if ((running & bit) != 0U)
            {
                fdi_svf_t *x = &bank[k];
                float u;
                if (f->source == FDI_GEN_BANK_RAW)
                {
                    u = in->value[f->signal & 31U];
                }
                else
                {
                    u = (f->order == 0U) ? bank[f->source].x1 : bank[f->source].x2;
                }
                if ((live & bit) == 0U)
                {
                    x->x1 = u; /* restart in steady state at the input (the source restarted in this step too) */
                    x->x2 = 0.0f;
                    x->u_prev = u;
                }
                else
                {
                    /* fdi_svf_step() inline: one bank, one set of coefficients (fdi_svf.h) */
                    const float x1p = x->x1;
                    const float x2p = x->x2;
                    const float x2 = (c1 * x2p) + (c2 * (((x->u_prev - x1p) + (u - x1p)) - (h * x2p)));
                    const float x1 = x1p + (h * (x2p + x2));
                    /* x * 0 is +-0 for a finite x and NaN for NaN and +-Inf: one check covers both */
                    if (fdi_float_is_finite((x1 * 0.0f) + (x2 * 0.0f)))
                    {
                        x->x1 = x1;
                        x->x2 = x2;
                        x->u_prev = u;
                    }
                    else
                    {
                        failed |= bit; /* holds; the signal's later filters hold too, all restart when usable */
                        running &= ~bit;
                    }
                }
            }
        }
    }
    return failed;
}

uint32_t fdi_gen_sens_count(const fdi_gen_desc_t *desc)
{
    uint32_t n = 0U;
    if (desc != NULL)
    {
        uint32_t m = desc->sens_mask;
        while (m != 0U)
        {
            m &= m - 1U; /* clear the lowest set bit */
            ++n;
        }
    }
    return n;
}

bool fdi_gen_in_domain(const fdi_gen_desc_t *desc, const fdi_frame_t *in)
{
    bool ok = false;
    if ((desc != NULL) && (in != NULL))
    {
        ok = (desc->in_domain == NULL) || desc->in_domain(in);
    }
    return ok;
}

bool fdi_gen_in_range(const fdi_gen_desc_t *desc, const fdi_frame_t *in)
{
    bool ok = false;
    if ((desc != NULL) && (in != NULL))
    {
        ok = (desc->in_range == NULL) || desc->in_range(in);
    }
    return ok;
}

fdi_status_t fdi_gen_init(fdi_gen_t *self, const fdi_gen_desc_t *desc, fdi_svf_t *filt, uint32_t n_filt,
                          fdi_obs_t *obs)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((self != NULL) && (fdi_gen_desc_check(desc) == FDI_OK) && (desc->step != NULL) &&
        ((uint32_t)desc->n_filters <= n_filt) && ((filt != NULL) || (desc->n_filters == 0U)) &&
        ((obs != NULL) || (desc->n_obs == 0U)))
    {
        uint32_t i;
        self->desc = desc;
        self->filt = filt;
        self->obs = obs;
        for (i = 0U; i < (uint32_t)desc->n_filters; ++i)
        {
            filt[i].x1 = 0.0f;
            filt[i].x2 = 0.0f;
            filt[i].u_prev = 0.0f;
        }
        if (obs != NULL)
        {
            obs->xh = 0.0f;
            obs->g_prev = 0.0f;
        }
        st = FDI_OK;
    }
    return st;
}

fdi_status_t fdi_gen_run_checked(fdi_gen_t *self, const fdi_gen_param_t *par, const fdi_frame_t *in, bool reset,
                                 float *r, float *sens)
{
    return self->desc->step(self, par, in, reset, r, sens);
}

static fdi_status_t run(fdi_gen_t *self, const fdi_gen_param_t *par, const fdi_frame_t *in, bool reset, float *r,
                        float *sens)
{
    fdi_status_t st;
    if ((self == NULL) || (par == NULL) || (in == NULL) || (r == NULL) || (self->desc == NULL) ||
        (self->desc->step == NULL))
    {
        st = FDI_BAD_ARG;
    }
    else
    {
        const uint32_t need = self->desc->input_mask;
        if (fdi_frame_finite_mask(in, need) != need)
        {
            st = FDI_NOT_FINITE;
        }
        else
        {
            st = fdi_gen_run_checked(self, par, in, reset, r, sens);
        }
    }
    return st;
}

fdi_status_t fdi_gen_reset(fdi_gen_t *self, const fdi_gen_param_t *par, const fdi_frame_t *in)
{
    float r = 0.0f;
    return run(self, par, in, true, &r, NULL);
}

fdi_status_t fdi_gen_step(fdi_gen_t *self, const fdi_gen_param_t *par, const fdi_frame_t *in, float *r,
                          float *sens)
{
    return run(self, par, in, false, r, sens);
}

fdi_status_t fdi_gen_filter_step(fdi_gen_t *g, const fdi_gen_param_t *par, uint32_t idx, float u, bool reset,
                                 fdi_svf_out_t *out)
{
    fdi_status_t st;
    if ((g == NULL) || (par == NULL) || (out == NULL) || (g->desc == NULL) || (g->filt == NULL) ||
        (idx >= (uint32_t)g->desc->n_filters))
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

fdi_status_t fdi_gen_sens_finish(fdi_status_t st, const float *sens, uint32_t n)
{
    fdi_status_t res = st;
    if (sens == NULL)
    {
        res = FDI_BAD_ARG;
    }
    else
    {
        uint32_t i;
        for (i = 0U; (res == FDI_OK) && (i < n); ++i)
        {
            if (!fdi_float_is_finite(sens[i]))
            {
                res = FDI_NOT_FINITE;
            }
        }
    }
    return res;
}

/* Elementary functions of the per-step code, float-only: the C library's are general-purpose (any argument,
   errno) and cost several times what the arguments met here need (fdi_gen_impl.h). */
#define SERIES_MAX 0.5f  /* |x| up to which expm1(x) / x is its Taylor series */
#define EXP_MIN (-18.5f) /* below: expm1f() (e^x under half an ulp of 1) */
#define INV_LN2 1.44269504f
#define LN2_HI 0.693145751953125f /* ln 2 with 12 trailing zero bits: n * LN2_HI is exact for n <= 27 */
#define LN2_LO 1.42860677e-06f    /* ln 2 - LN2_HI */
#define TANH_ONE 9.1f             /* tanh(x) rounds to 1 from here on */

/* (e^x - 1) / x for |x| <= SERIES_MAX: sum of x^n / (n + 1)!, n = 0 .. 7 (truncation < 1.2e-8 relative) */
static float expm1_series(float x)
{
    float p = 2.48015873e-5f; /* 1/8! */
    p = (p * x) + 1.98412698e-4f;
    p = (p * x) + 0.00138888889f;
    p = (p * x) + 0.00833333333f;
    p = (p * x) + 0.0416666667f;
    p = (p * x) + 0.166666667f;
    p = (p * x) + 0.5f;
    return (p * x) + 1.0f;
}

/* e^x - 1 for EXP_MIN <= x < -SERIES_MAX: e^x = 2^-n e^r, r = x + n ln2 (ln 2 in two parts), |r| <= ln2 / 2,
   e^r to r^7 (truncation < 6e-9 relative), 2^-n from the table; e^x <= 0.61, so e^x - 1 does not cancel */
static float expm1_negative(float x)
{
    /* 2^-n for n = 0 .. 27 (EXP_MIN / ln 2 rounds to -27) */
    static const float pow2_neg[28] = {
        1.0f, 0.5f, 0.25f, 0.125f, 0.0625f, 0.03125f, 0.015625f, 0.0078125f, 0.00390625f, 0.001953125f,
        9.765625e-4f, 4.8828125e-4f, 2.44140625e-4f, 1.220703125e-4f, 6.103515625e-5f, 3.0517578125e-5f,
        1.52587890625e-5f, 7.62939453125e-6f, 3.814697265625e-6f, 1.9073486328125e-6f, 9.5367431640625e-7f,
        4.76837158203125e-7f, 2.384185791015625e-7f, 1.1920928955078125e-7f, 5.9604644775390625e-8f,
        2.98023223876953125e-8f, 1.490116119384765625e-8f, 7.450580596923828125e-9f};
    const float scaled = (-x * INV_LN2) + 0.5f;
    const uint32_t n = (uint32_t)scaled; /* 1 .. 27 */
    const float nf = (float)n;
    const float r = (x + (nf * LN2_HI)) + (nf * LN2_LO);
    float p = 1.98412698e-4f; /* 1/7! */
    p = (p * r) + 0.00138888889f;
    p = (p * r) + 0.00833333333f;
    p = (p * r) + 0.0416666667f;
    p = (p * r) + 0.166666667f;
    p = (p * r) + 0.5f;
    p = (p * r) + 1.0f;
    p = (p * r) + 1.0f;
    return (p * pow2_neg[n]) - 1.0f;
}

/* expm1(x) / x (1 at x = 0), a few ulp; expm1f() outside [EXP_MIN, SERIES_MAX] and for NaN */
static float expm1_over(float x)
{
    float y;
    if ((x >= -SERIES_MAX) && (x <= SERIES_MAX))
    {
        y = expm1_series(x);
    }
    else if ((x >= EXP_MIN) && (x < -SERIES_MAX))
    {
        y = expm1_negative(x) / x;
    }
    else
    {
        y = expm1f(x) / x;
    }
    return y;
}

float fdi_gen_tanh(float x)
{
    const float a = fabsf(x);
    float t;
    if (a >= TANH_ONE)
    {
        t = 1.0f;
    }
    else if (a > (0.5f * SERIES_MAX))
    {
        const float m = expm1_negative(-2.0f * a); /* tanh(a) = -m / (2 + m), m = e^-2a - 1 in (-1, -0.63] */
        t = -m / (2.0f + m);
    }
    else
    {
        const float m = -2.0f * a * expm1_series(-2.0f * a);
        t = -m / (2.0f + m);
    }
    return (x < 0.0f) ? -t : t; /* NaN: a NaN t */
}

/* sin and cos: x = n pi/2 + r with |r| <= pi/4 (pi/2 in three parts, the first two with 12 significant bits, so
   that n times each is exact for |n| < 2^11: |x| <= TRIG_MAX), then +-sin r or +-cos r by the quadrant n mod 4;
   cos x = sin of the next quadrant. The polynomials: sin r = r + r^3 P(r^2), cos r = 1 - r^2 / 2 + r^4 Q(r^2), their
   coefficients a weighted least-squares fit of the relative error on [0, pi/4] rounded to float (at most 0.79 and
   1.25 ulp from the exact value there, evaluated in float as below; with the reduction 1.6 ulp for |x| <= 13, and
   within 1e-7 of the exact value up to TRIG_MAX: tests/fw/test_fdi_gen_generated.c checks both functions against
   the double ones). Beyond TRIG_MAX (no angle of a vehicle model) NaN, as for NaN and +-Inf: the test using it is
   then not evaluable for the step, and the image needs no C library sinf / cosf. */
#define TRIG_MAX 2048.0f
#define PI_4 0.785398163f
#define TWO_OVER_PI 0.636619772f
#define PIO2_1 1.5703125f   /* pi / 2 to 12 significant bits */
#define PIO2_2 4.837513e-4f /* the next 12 bits */
#define PIO2_3 7.54979e-8f  /* the rest */

static float sin_poly(float r)
{
    const float z = r * r;
    float p = -0.00019586566f;
    p = (p * z) + 0.008332739f;
    p = (p * z) - 0.16666664f;
    return r + ((r * z) * p);
}

static float cos_poly(float r)
{
    const float z = r * r;
    float p = 2.4432831e-5f;
    p = (p * z) - 0.0013887313f;
    p = (p * z) + 0.041666646f;
    return (1.0f - (0.5f * z)) + ((z * z) * p);
}

/* sin x (quadrant shift 0) or cos x (shift 1) for |x| > PI_4 (and NaN) */
static float trig_reduced(float x, uint32_t shift)
{
    float v = NAN; /* beyond TRIG_MAX, +-Inf, NaN */
    if (fabsf(x) <= TRIG_MAX)
    {
        const float half = (x < 0.0f) ? -0.5f : 0.5f;
        const float nearest = (x * TWO_OVER_PI) + half; /* truncated: n = x 2 / pi rounded half away from 0 */
        const int32_t n = (int32_t)nearest;
        const float fn = (float)n;
        const uint32_t q = shift + (uint32_t)n; /* modulo 2^32: n mod 4 in the low bits for a negative n too */
        const float r = ((x - (fn * PIO2_1)) - (fn * PIO2_2)) - (fn * PIO2_3);
        v = ((q & 1U) == 0U) ? sin_poly(r) : cos_poly(r);
        v = ((q & 2U) == 0U) ? v : -v;
    }
    return v;
}

float fdi_gen_sin(float x)
{
    return (fabsf(x) <= PI_4) ? sin_poly(x) : trig_reduced(x, 0U);
}

float fdi_gen_cos(float x)
{
    return (fabsf(x) <= PI_4) ? cos_poly(x) : trig_reduced(x, 1U);
}

float fdi_gen_obs_predict(const fdi_obs_t *obs, const fdi_gen_param_t *par, float g1, float jac)
{
    float xh = 0.0f;
    if ((obs != NULL) && (par != NULL))
    {
        const float dt = 2.0f * par->svf.h;
        const float jdt = jac * dt;
        const float phi = dt * expm1_over(jdt); /* expm1(jac dt) / jac, dt at jac = 0 */
        xh = obs->xh + (phi * (0.5f * (obs->g_prev + g1)));
    }
    return xh;
}

fdi_status_t fdi_gen_obs_store(fdi_obs_t *obs, float xh, float g_next)
{
    fdi_status_t st = FDI_OK;
    if (obs == NULL)
    {
        st = FDI_BAD_ARG;
    }
    else if (!fdi_float_is_finite(xh) || !fdi_float_is_finite(g_next))
    {
        st = FDI_NOT_FINITE;
    }
    else
    {
        obs->xh = xh;
        obs->g_prev = g_next;
    }
    return st;
}
