/* fdi_est.c - on-line estimation of a test's uncertain quantities, frozen while the test alarms (see fdi_est.h). */
#include "fdi_est.h"

#include <math.h>
#include <stddef.h>

#include "fdi_float.h"

/* Index of P[i][j] (i <= j) in the packed upper triangle of an FDI_EST_MAX_PARAMS square matrix. */
static uint32_t at(uint32_t i, uint32_t j)
{
    return ((i * ((2U * FDI_EST_MAX_PARAMS) + 1U - i)) / 2U) + (j - i);
}

static uint32_t idx(uint32_t i, uint32_t j)
{
    return (i <= j) ? at(i, j) : at(j, i);
}

static bool param_ok(const fdi_est_param_t *p, fdi_status_t *st)
{
    bool ok = true;
    if (!fdi_float_is_finite(p->mean) || !fdi_float_is_finite(p->var) || !fdi_float_is_finite(p->q) ||
        !fdi_float_is_finite(p->lo) || !fdi_float_is_finite(p->hi) || !fdi_float_is_finite(p->step))
    {
        *st = FDI_NOT_FINITE;
        ok = false;
    }
    else if ((p->var <= 0.0f) || (p->q < 0.0f) || (p->lo > p->mean) || (p->mean > p->hi) || (p->step <= 0.0f))
    {
        *st = FDI_BAD_ARG;
        ok = false;
    }
    else
    {
        /* a valid declaration */
    }
    return ok;
}

fdi_status_t fdi_est_check(const fdi_est_param_t *param, uint32_t n)
{
    fdi_status_t st = FDI_OK;
    uint32_t i;
    if ((param == NULL) || (n == 0U) || (n > FDI_EST_MAX_PARAMS))
    {
        st = FDI_BAD_ARG;
    }
    for (i = 0U; (st == FDI_OK) && (i < n); ++i)
    {
        (void)param_ok(&param[i], &st);
    }
    return st;
}

fdi_status_t fdi_est_init(fdi_est_t *self, const fdi_est_param_t *param, uint32_t n)
{
    fdi_status_t st = (self == NULL) ? FDI_BAD_ARG : fdi_est_check(param, n);
    if (st == FDI_OK)
    {
        uint32_t i;
        for (i = 0U; i < FDI_EST_P_SIZE; ++i)
        {
            self->p[i] = 0.0f;
        }
        for (i = 0U; i < FDI_EST_MAX_PARAMS; ++i)
        {
            self->theta[i] = (i < n) ? param[i].mean : 0.0f;
            if (i < n)
            {
                self->p[at(i, i)] = param[i].var;
            }
        }
    }
    return st;
}

/* P h (n entries) and h' P h. */
static float covariance_times(const fdi_est_t *self, uint32_t n, const float *h, float *ph)
{
    float hph = 0.0f;
    uint32_t i;
    for (i = 0U; i < n; ++i)
    {
        float s = 0.0f;
        uint32_t j;
        for (j = 0U; j < n; ++j)
        {
            s += self->p[idx(i, j)] * h[j];
        }
        ph[i] = s;
        hph += h[i] * s;
    }
    return (hph > 0.0f) ? hph : 0.0f;
}

/* The prediction: each quantity's variance grows by q, up to its prior variance (adding a non-negative diagonal
   keeps P positive semi-definite). */
static void predict(fdi_est_t *self, const fdi_est_param_t *param, uint32_t n, float q_scale)
{
    uint32_t i;
    for (i = 0U; i < n; ++i)
    {
        const uint32_t d = at(i, i);
        const float room = param[i].var - self->p[d];
        const float q = q_scale * param[i].q;
        if (room > 0.0f)
        {
            self->p[d] += (q < room) ? q : room;
        }
    }
}

/* The correction with innovation nu, P h = ph and s = h' P h + noise > 0: each move limited to its quantity's step
   (the part cut off added to its variance), theta clamped to its bounds, P's diagonal kept >= 0 (float rounding). */
static void correct(fdi_est_t *self, const fdi_est_param_t *param, uint32_t n, const float *ph, float nu, float s)
{
    const float inv = 1.0f / s;
    uint32_t i;
    for (i = 0U; i < n; ++i)
    {
        float move = ph[i] * inv * nu;
        float cut = 0.0f;
        float th;
        uint32_t j;
        if (move > param[i].step)
        {
            cut = move - param[i].step;
            move = param[i].step;
        }
        else if (move < -param[i].step)
        {
            cut = -param[i].step - move;
            move = -param[i].step;
        }
        else
        {
            /* within its step */
        }
        th = self->theta[i] + move;
        if (th > param[i].hi)
        {
            th = param[i].hi;
        }
        else if (th < param[i].lo)
        {
            th = param[i].lo;
        }
        else
        {
            /* inside its bounds */
        }
        self->theta[i] = th;
        for (j = i; j < n; ++j)
        {
            self->p[at(i, j)] -= ph[i] * ph[j] * inv;
        }
        if (self->p[at(i, i)] < 0.0f)
        {
            self->p[at(i, i)] = 0.0f;
        }
        self->p[at(i, i)] += cut * cut;
        if (self->p[at(i, i)] > param[i].var) /* never less certain than the prior */
        {
            self->p[at(i, i)] = param[i].var;
        }
    }
}

fdi_status_t fdi_est_update(fdi_est_t *self, const fdi_est_param_t *param, uint32_t n, const float *h, float r,
                            float noise, float q_scale, bool freeze, float *innovation, float *spread)
{
    fdi_status_t st = FDI_OK;
    uint32_t i;
    if ((self == NULL) || (param == NULL) || (h == NULL) || (innovation == NULL) || (spread == NULL) || (n == 0U) ||
        (n > FDI_EST_MAX_PARAMS))
    {
        st = FDI_BAD_ARG;
    }
    else if (!fdi_float_is_finite(r) || !fdi_float_is_finite(noise) || !fdi_float_is_finite(q_scale))
    {
        st = FDI_NOT_FINITE;
    }
    else if ((noise <= 0.0f) || (q_scale < 1.0f))
    {
        st = FDI_BAD_ARG;
    }
    else
    {
        for (i = 0U; (st == FDI_OK) && (i < n); ++i)
        {
            if (!fdi_float_is_finite(h[i]))
            {
                st = FDI_NOT_FINITE;
            }
        }
    }
    if (st == FDI_OK)
    {
        float ph[FDI_EST_MAX_PARAMS];
        float pred = 0.0f;
        float hph;
        for (i = 0U; i < n; ++i)
        {
            pred += h[i] * self->theta[i];
        }
        predict(self, param, n, q_scale);
        hph = covariance_times(self, n, h, ph);
        *innovation = r - pred;
        *spread = sqrtf(hph);
        if (!freeze && (hph > 0.0f))
        {
            correct(self, param, n, ph, *innovation, hph + noise);
        }
    }
    return st;
}

float fdi_est_value(const fdi_est_t *self, uint32_t k)
{
    return ((self == NULL) || (k >= FDI_EST_MAX_PARAMS)) ? 0.0f : self->theta[k];
}

float fdi_est_std(const fdi_est_t *self, uint32_t k)
{
    return ((self == NULL) || (k >= FDI_EST_MAX_PARAMS)) ? 0.0f : sqrtf(self->p[at(k, k)]);
}
