/* fdi_diag.c - the diagnoser: generators, evaluators, warm-up and isolation per table (see fdi_diag.h). */
#include "fdi_diag.h"

#include <math.h>
#include <stddef.h>

#include "fdi_float.h"
#include "fdi_gen_internal.h"

#define FDI_TWO_PI_F 6.28318530717959f
#define WARMUP_MARGIN_STEPS 20U
/* Isolation episodes: a quiet test exonerates only after 3 s, the response window in which the analysis states the
   per-test fault sizes (fdi-tune fault-sizes: alarm within a 3 s step); an episode ends after 3 s without any
   alarm. */
#define ISO_SETTLE_S 3.0f
#define EPISODE_CLEAR_S 3.0f

/* Settling time of the design point in steps (see fdi_diag.h); 0 if it is not representable. */
static uint32_t settle_steps(const fdi_table_design_t *d)
{
    const float rate = d->zeta * FDI_TWO_PI_F * d->cutoff_hz; /* decay rate of one filter stage [1/s] */
    uint32_t steps = 0U;
    if ((rate > 0.0f) && (d->obs_gain > 0.0f) && (d->dt > 0.0f))
    {
        const float t_svf = (2.0f * FDI_DIAG_SETTLE_TAUS) / rate;
        const float t_obs = FDI_DIAG_SETTLE_TAUS / d->obs_gain;
        const float t = (t_svf > t_obs) ? t_svf : t_obs;
        const float n = ceilf(t / d->dt);
        if (fdi_float_is_finite(n) && (n < 65535.0f))
        {
            steps = (uint32_t)n;
        }
    }
    return steps;
}

/* Sensitivity offsets of the table's tests; false when they exceed FDI_DIAG_MAX_SENS. */
static bool sens_layout(const fdi_table_t *t, uint8_t *offset)
{
    uint32_t total = 0U;
    uint32_t i;
    for (i = 0U; i < (uint32_t)t->n_tests; ++i)
    {
        offset[i] = (uint8_t)((total < FDI_DIAG_MAX_SENS) ? total : FDI_DIAG_MAX_SENS);
        total += fdi_gen_sens_count(t->tests[i].gen);
    }
    for (i = (uint32_t)t->n_tests; i <= FDI_DIAG_MAX_TESTS; ++i)
    {
        offset[i] = (uint8_t)((total < FDI_DIAG_MAX_SENS) ? total : FDI_DIAG_MAX_SENS);
    }
    return total <= FDI_DIAG_MAX_SENS;
}

/* Whole steps of t seconds at dt (>= 1, saturating at 65535). */
static uint16_t steps_of(float t, float dt)
{
    const float n = (t / dt) + 0.5f;
    uint16_t k = 1U;
    if (n >= 65535.0f)
    {
        k = 0xFFFFU;
    }
    else if (n >= 1.0f)
    {
        k = (uint16_t)n;
    }
    else
    {
        /* at least one step */
    }
    return k;
}

fdi_status_t fdi_diag_config_default(fdi_diag_config_t *cfg, const fdi_table_t *table)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((cfg != NULL) && (table != NULL))
    {
        const uint32_t settle = settle_steps(&table->design);
        st = FDI_BAD_TABLE;
        if ((settle > 0U) && ((settle + WARMUP_MARGIN_STEPS) <= 0xFFFFU))
        {
            uint32_t i;
            cfg->table = table;
            for (i = 0U; i < FDI_GEN_N_PARAMS; ++i)
            {
                cfg->gen_param[i] = 0.0f;
            }
            cfg->cusum_k = 1.5f;
            cfg->cusum_h = 150.0f;
            cfg->set_count = 10U;
            cfg->clear_count = 100U;
            cfg->warmup_steps = (uint16_t)(settle + WARMUP_MARGIN_STEPS);
            cfg->mode = FDI_ISO_EXONERATION;
            cfg->iso_settle_steps = steps_of(ISO_SETTLE_S, table->design.dt);
            cfg->episode_clear_steps = steps_of(EPISODE_CLEAR_S, table->design.dt);
            cfg->sensitivities = FDI_DIAG_SENS_OFF;
            st = FDI_OK;
        }
    }
    return st;
}

static fdi_status_t check_config(const fdi_diag_config_t *cfg)
{
    fdi_status_t st = fdi_table_check(cfg->table);
    if (st != FDI_OK)
    {
        /* keep the status of the table check */
    }
    else if (!fdi_float_is_finite(cfg->cusum_k) || !fdi_float_is_finite(cfg->cusum_h))
    {
        st = FDI_NOT_FINITE;
    }
    else if ((cfg->table->n_tests > FDI_DIAG_MAX_TESTS) || (cfg->episode_clear_steps == 0U) ||
             ((cfg->mode != FDI_ISO_NO_EXONERATION) && (cfg->mode != FDI_ISO_EXONERATION)) ||
             ((cfg->sensitivities != FDI_DIAG_SENS_OFF) && (cfg->sensitivities != FDI_DIAG_SENS_EPISODE) &&
              (cfg->sensitivities != FDI_DIAG_SENS_ALWAYS)))
    {
        st = FDI_BAD_ARG;
    }
    else
    {
        const uint32_t need = settle_steps(&cfg->table->design);
        if ((need == 0U) || ((uint32_t)cfg->warmup_steps < need))
        {
            st = FDI_BAD_ARG;
        }
    }
    return st;
}

/* The generator state of the table: the set (the bank first in filt[]), the instance filters of the hand-written
   generators after it, the slot map, every state zeroed. false when the filters do not fit FDI_DIAG_MAX_FILTERS. */
static bool gen_layout(fdi_diag_t *self, const fdi_table_t *t)
{
    uint32_t used = 0U;
    uint32_t i;
    self->set = NULL;
    self->set_tests = 0U;
    for (i = 0U; i < FDI_GEN_MAX_SLOTS; ++i)
    {
        self->slot_test[i] = 0U;
    }
    for (i = 0U; i < (uint32_t)t->n_tests; ++i)
    {
        const fdi_gen_desc_t *g = t->tests[i].gen;
        self->filt_base[i] = 0U;
        if ((g != NULL) && (g->set != NULL)) /* one set per table, each slot once: fdi_table_check */
        {
            self->set = g->set;
            self->set_tests |= (uint32_t)1U << i;
            self->slot_test[g->slot & 31U] = (uint8_t)i;
        }
    }
    if (self->set != NULL)
    {
        used = (uint32_t)self->set->n_bank;
    }
    for (i = 0U; i < (uint32_t)t->n_tests; ++i)
    {
        const fdi_gen_desc_t *g = t->tests[i].gen;
        if ((g != NULL) && (g->set == NULL))
        {
            self->filt_base[i] = (uint8_t)((used < FDI_DIAG_MAX_FILTERS) ? used : 0U);
            used += (uint32_t)g->n_filters;
        }
    }
    for (i = 0U; i < FDI_DIAG_MAX_FILTERS; ++i)
    {
        self->filt[i].x1 = 0.0f;
        self->filt[i].x2 = 0.0f;
        self->filt[i].u_prev = 0.0f;
    }
    for (i = 0U; i < FDI_DIAG_MAX_TESTS; ++i)
    {
        self->obs[i].xh = 0.0f;
        self->obs[i].g_prev = 0.0f;
    }
    return used <= FDI_DIAG_MAX_FILTERS;
}

fdi_status_t fdi_diag_init(fdi_diag_t *self, const fdi_diag_config_t *cfg)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((self != NULL) && (cfg != NULL))
    {
        st = check_config(cfg);
    }
    if (st == FDI_OK)
    {
        const fdi_table_t *t = cfg->table;
        fdi_gen_config_t gcfg = {t->design.dt, t->design.cutoff_hz, t->design.zeta, t->design.obs_gain,
                                 {0.0f, 0.0f, 0.0f, 0.0f}};
        uint32_t i;
        for (i = 0U; i < FDI_GEN_N_PARAMS; ++i)
        {
            gcfg.param[i] = cfg->gen_param[i];
        }
        st = fdi_gen_param_init(&self->par, &gcfg);
        if ((st == FDI_OK) && !sens_layout(t, self->sens_offset) && (cfg->sensitivities != FDI_DIAG_SENS_OFF))
        {
            st = FDI_BAD_ARG;
        }
        if ((st == FDI_OK) && !gen_layout(self, t))
        {
            st = FDI_BAD_ARG;
        }
        for (i = 0U; i < FDI_DIAG_MAX_TEST_SENS; ++i)
        {
            self->sens[i] = 0.0f;
        }
        self->signals = 0U;
        for (i = 0U; (st == FDI_OK) && (i < (uint32_t)t->n_tests); ++i)
        {
            const fdi_test_desc_t *d = &t->tests[i];
            const fdi_eval_config_t ecfg = {d->gate,        d->variance,    cfg->cusum_k,
                                            cfg->cusum_h,   cfg->set_count, cfg->clear_count};
            self->signals |= d->input_mask;
            st = fdi_eval_init(&self->eval[i], &ecfg);
            self->residual[i] = 0.0f;
            self->ratio[i] = 0.0f;
            self->warm[i] = cfg->warmup_steps;
            self->quiet_run[i] = 0U;
            self->sens_step[i] = 0U;
        }
        if (st == FDI_OK)
        {
            self->table = t;
            self->mode = cfg->mode;
            self->sens_mode = cfg->sensitivities;
            self->warmup_steps = cfg->warmup_steps;
            self->iso_settle_steps = cfg->iso_settle_steps;
            self->episode_clear_steps = cfg->episode_clear_steps;
            self->episode_age = 0U;
            self->calm = 0U;
            self->accused = 0U;
            self->n_tests = t->n_tests;
            self->sens_next = 0U;
            self->rearm = 0xFFFFFFFFU;
            self->alarm = 0U;
            self->evaluable = 0U;
            self->bank_live = 0U;
            self->steps = 0U;
            self->sens_fresh = 0U;
            self->iso.candidates = 0U;
            self->iso.class_mask = 0U;
            self->iso.n_classes = 0U;
            self->iso.detected = false;
            self->iso.isolated = false;
        }
    }
    if ((self != NULL) && (st != FDI_OK))
    {
        self->table = NULL; /* a failed init leaves an instance that fdi_diag_step() refuses */
    }
    return st;
}

/* Run hand-written test i on a usable frame (restarting it first when re-armed): *r, sens when non-NULL. */
static fdi_status_t run_hand_written(fdi_diag_t *self, uint32_t i, const fdi_frame_t *in, float *r, float *sens)
{
    fdi_gen_t g;
    fdi_status_t st = FDI_OK;
    g.desc = self->table->tests[i].gen;
    g.filt = &self->filt[self->filt_base[i]];
    g.obs = &self->obs[i];
    if ((self->rearm & ((uint32_t)1U << i)) != 0U)
    {
        float r0 = 0.0f;
        st = fdi_gen_run_checked(&g, &self->par, in, true, &r0, NULL);
    }
    if (st == FDI_OK)
    {
        st = fdi_gen_run_checked(&g, &self->par, in, false, r, sens); /* inputs checked by the caller */
    }
    return st;
}

/* Evaluation of test i after its generator ran (ok: a finite residual r); true if it is evaluable this step (then
   *alarm is set). */
static bool evaluate(fdi_diag_t *self, uint32_t i, bool ok, float r, bool *alarm)
{
    const uint32_t bit = (uint32_t)1U << i;
    bool evaluable = false;
    fdi_status_t st = ok ? FDI_OK : FDI_NOT_FINITE;
    if ((st == FDI_OK) && ((self->rearm & bit) != 0U))
    {
        st = fdi_eval_reset(&self->eval[i]);
        self->warm[i] = self->warmup_steps;
        self->rearm &= ~bit;
    }
    if (st != FDI_OK)
    {
        self->rearm |= bit;
        self->residual[i] = 0.0f;
        self->ratio[i] = 0.0f;
    }
    else if (self->warm[i] > 0U)
    {
        self->warm[i]--;
        self->residual[i] = r;
        self->ratio[i] = 0.0f;
    }
    else
    {
        fdi_eval_out_t eo = {FDI_TEST_OK, 0.0f};
        if (fdi_eval_step(&self->eval[i], r, &eo) == FDI_OK)
        {
            evaluable = true;
            *alarm = (eo.status == FDI_TEST_ALARM);
            self->residual[i] = r;
            self->ratio[i] = eo.ratio;
        }
        else
        {
            self->rearm |= bit;
        }
    }
    return evaluable;
}

/* The test whose sensitivities this step computes (round robin over the tests of `run` that are evaluated this step
   and have some), or FDI_DIAG_MAX_TESTS for none. */
static uint32_t sens_pick(fdi_diag_t *self, uint32_t run)
{
    const uint32_t n = (uint32_t)self->n_tests;
    uint32_t pick = FDI_DIAG_MAX_TESTS;
    if ((self->sens_mode == FDI_DIAG_SENS_ALWAYS) || ((self->sens_mode == FDI_DIAG_SENS_EPISODE) &&
                                                      (self->accused != 0U)))
    {
        uint32_t k;
        for (k = 0U; (pick == FDI_DIAG_MAX_TESTS) && (k < n); ++k)
        {
            const uint32_t i = ((uint32_t)self->sens_next + k) % n;
            const uint32_t bit = (uint32_t)1U << i;
            if (((run & ~self->rearm & bit) != 0U) && (self->warm[i] == 0U) &&
                (self->sens_offset[i + 1U] > self->sens_offset[i]))
            {
                pick = i;
                self->sens_next = (uint8_t)((i + 1U) % n);
            }
        }
    }
    return pick;
}

/* The generators of the tests of `run` (inputs usable, in their domain): the set's slots in one call, the
   hand-written ones one by one; r[i] and ok (bit i: finite residual); sensitivities of test `pick`. */
static uint32_t run_generators(fdi_diag_t *self, const fdi_frame_t *in, uint32_t run, uint32_t pick, float *r)
{
    uint32_t ok = 0U;
    uint32_t i;
    float *sens_of_pick = NULL;
    for (i = 0U; i < (uint32_t)self->n_tests; ++i)
    {
        const uint32_t bit = (uint32_t)1U << i;
        if ((run & ~self->set_tests & bit) != 0U)
        {
            float *sens = (i == pick) ? self->sens : NULL;
            if (run_hand_written(self, i, in, &r[i], sens) == FDI_OK)
            {
                ok |= bit;
                sens_of_pick = (sens != NULL) ? sens : sens_of_pick;
            }
        }
    }
    if ((run & self->set_tests) != 0U)
    {
        static const uint8_t at_zero[FDI_GEN_MAX_SLOTS] = {0U}; /* the one picked slot writes at sens[0] */
        fdi_gen_io_t io;
        io.par = &self->par;
        io.in = in;
        io.bank = self->filt;
        io.obs = self->obs;
        io.r = r;
        io.at = self->slot_test;
        io.sens = self->sens;
        io.sens_at = at_zero;
        io.run = 0U;
        io.restart = 0U;
        io.sens_mask = 0U;
        io.failed = 0U;
        for (i = 0U; i < (uint32_t)self->n_tests; ++i)
        {
            const uint32_t bit = (uint32_t)1U << i;
            if ((run & self->set_tests & bit) != 0U)
            {
                const uint32_t slot = (uint32_t)1U << (self->table->tests[i].gen->slot & 31U);
                io.run |= slot;
                io.restart |= ((self->rearm & bit) != 0U) ? slot : 0U;
                io.sens_mask |= (i == pick) ? slot : 0U;
            }
        }
        self->set->step(&io);
        for (i = 0U; i < (uint32_t)self->n_tests; ++i)
        {
            const uint32_t bit = (uint32_t)1U << i;
            if ((run & self->set_tests & bit) != 0U)
            {
                const uint32_t slot = (uint32_t)1U << (self->table->tests[i].gen->slot & 31U);
                if ((io.failed & slot) == 0U)
                {
                    ok |= bit;
                    sens_of_pick = (i == pick) ? self->sens : sens_of_pick;
                }
            }
        }
    }
    if ((pick < FDI_DIAG_MAX_TESTS) && (sens_of_pick != NULL))
    {
        const uint32_t n = (uint32_t)self->sens_offset[pick + 1U] - (uint32_t)self->sens_offset[pick];
        bool finite = true;
        for (i = 0U; i < n; ++i)
        {
            finite = finite && fdi_float_is_finite(self->sens[i]);
        }
        if (finite)
        {
            self->sens_fresh = (uint32_t)1U << pick;
            self->sens_step[pick] = self->steps;
        }
    }
    return ok;
}

static uint16_t sat_inc(uint16_t x)
{
    return (x < 0xFFFFU) ? (uint16_t)(x + 1U) : x;
}

/* Episode bookkeeping and the isolation of this step (see "Isolation episodes" in fdi_diag.h). */
static fdi_status_t isolate(fdi_diag_t *self, uint32_t alarm, uint32_t evaluable)
{
    uint32_t exonerate = 0U;
    uint32_t i;
    for (i = 0U; i < (uint32_t)self->n_tests; ++i)
    {
        const uint32_t bit = (uint32_t)1U << i;
        self->quiet_run[i] = (((evaluable & bit) != 0U) && ((alarm & bit) == 0U)) ? sat_inc(self->quiet_run[i]) : 0U;
    }
    if (alarm != 0U)
    {
        if (self->accused == 0U)
        {
            self->episode_age = 0U;
        }
        self->accused |= alarm;
        self->calm = 0U;
    }
    else if (self->accused != 0U)
    {
        self->calm = sat_inc(self->calm);
        if (self->calm >= self->episode_clear_steps)
        {
            self->accused = 0U;
        }
    }
    else
    {
        /* no episode */
    }
    if (self->accused != 0U)
    {
        self->episode_age = sat_inc(self->episode_age);
    }
    if ((self->mode == FDI_ISO_EXONERATION) && (self->episode_age >= self->iso_settle_steps))
    {
        for (i = 0U; i < (uint32_t)self->n_tests; ++i)
        {
            if (self->quiet_run[i] >= self->iso_settle_steps)
            {
                exonerate |= ((uint32_t)1U << i) & evaluable;
            }
        }
    }
    exonerate &= ~self->accused;
    /* accused tests stay in the alarm set even while not evaluable now: they alarmed in this episode */
    return fdi_iso_run(self->table, self->accused, self->accused | exonerate, self->mode, &self->iso);
}

fdi_status_t fdi_diag_step(fdi_diag_t *self, const fdi_frame_t *frame, uint32_t validity)
{
    fdi_status_t st = FDI_OK;
    if ((self == NULL) || (frame == NULL) || (self->table == NULL))
    {
        st = FDI_BAD_ARG;
    }
    else
    {
        uint32_t usable = fdi_frame_finite_mask(frame, validity & self->signals);
        uint32_t run = 0U;
        uint32_t alarm = 0U;
        uint32_t evaluable = 0U;
        uint32_t ok;
        uint32_t i;
        float r[FDI_DIAG_MAX_TESTS];
        self->steps = (self->steps < 0xFFFFFFFFU) ? (self->steps + 1U) : self->steps;
        self->sens_fresh = 0U;
        if (self->set != NULL)
        {
            usable &= ~fdi_gen_bank_step(self->set, self->filt, &self->par.svf, frame, usable, self->bank_live);
            self->bank_live = usable;
        }
        for (i = 0U; i < (uint32_t)self->n_tests; ++i)
        {
            const fdi_test_desc_t *d = &self->table->tests[i];
            const uint32_t bit = (uint32_t)1U << i;
            r[i] = 0.0f;
            if ((d->gen == NULL) || ((usable & d->input_mask) != d->input_mask) || !fdi_gen_in_domain(d->gen, frame))
            {
                self->rearm |= bit;
                self->residual[i] = 0.0f;
                self->ratio[i] = 0.0f;
            }
            else
            {
                run |= bit;
            }
        }
        ok = run_generators(self, frame, run, sens_pick(self, run), r);
        for (i = 0U; i < (uint32_t)self->n_tests; ++i)
        {
            const uint32_t bit = (uint32_t)1U << i;
            bool test_alarm = false;
            if (((run & bit) != 0U) && evaluate(self, i, (ok & bit) != 0U, r[i], &test_alarm))
            {
                evaluable |= bit;
                alarm |= test_alarm ? bit : 0U;
            }
        }
        self->alarm = alarm;
        self->evaluable = evaluable;
        st = isolate(self, alarm, evaluable);
    }
    return st;
}

fdi_status_t fdi_diag_result(const fdi_diag_t *self, fdi_diag_result_t *out)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((self != NULL) && (out != NULL) && (self->table != NULL))
    {
        const bool with_sens = self->sens_mode != FDI_DIAG_SENS_OFF;
        uint32_t i;
        out->n_tests = self->n_tests;
        out->alarm_mask = self->alarm;
        out->evaluable_mask = self->evaluable;
        for (i = 0U; i < FDI_DIAG_MAX_TESTS; ++i)
        {
            const uint32_t bit = (uint32_t)1U << (i & 31U);
            const bool used = i < (uint32_t)self->n_tests;
            if ((self->evaluable & bit) == 0U)
            {
                out->status[i] = FDI_TEST_NOT_EVALUABLE;
            }
            else
            {
                out->status[i] = ((self->alarm & bit) != 0U) ? FDI_TEST_ALARM : FDI_TEST_OK;
            }
            out->residual[i] = used ? self->residual[i] : 0.0f;
            out->ratio[i] = used ? self->ratio[i] : 0.0f;
            out->sens_step[i] = used ? self->sens_step[i] : 0U;
        }
        out->accused_mask = self->accused;
        out->iso = self->iso;
        out->step = self->steps;
        out->sens_fresh_mask = self->sens_fresh;
        for (i = 0U; i <= FDI_DIAG_MAX_TESTS; ++i)
        {
            out->sens_offset[i] = with_sens ? self->sens_offset[i] : 0U;
        }
        if (self->steps == 0U)
        {
            for (i = 0U; i < FDI_DIAG_MAX_SENS; ++i)
            {
                out->sens[i] = 0.0f;
            }
        }
        for (i = 0U; with_sens && (i < (uint32_t)self->n_tests); ++i)
        {
            if ((self->sens_fresh & ((uint32_t)1U << i)) != 0U)
            {
                uint32_t k;
                for (k = (uint32_t)self->sens_offset[i]; k < (uint32_t)self->sens_offset[i + 1U]; ++k)
                {
                    out->sens[k] = self->sens[k - (uint32_t)self->sens_offset[i]];
                }
            }
        }
        st = FDI_OK;
    }
    return st;
}

uint32_t fdi_diag_sens_fresh(const fdi_diag_t *self)
{
    return ((self != NULL) && (self->table != NULL)) ? self->sens_fresh : 0U;
}

fdi_status_t fdi_diag_sens(const fdi_diag_t *self, uint32_t test, const float **values, uint32_t *n)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((self != NULL) && (self->table != NULL) && (values != NULL) && (n != NULL) &&
        (test < (uint32_t)self->n_tests) && ((self->sens_fresh & ((uint32_t)1U << test)) != 0U))
    {
        *values = self->sens;
        *n = (uint32_t)self->sens_offset[test + 1U] - (uint32_t)self->sens_offset[test];
        st = FDI_OK;
    }
    return st;
}

uint32_t fdi_diag_sens_step(const fdi_diag_t *self, uint32_t test)
{
    uint32_t step = 0U;
    if ((self != NULL) && (self->table != NULL) && (test < (uint32_t)self->n_tests))
    {
        step = self->sens_step[test];
    }
    return step;
}
