/* fdi_diag.c - the diagnoser: generators, evaluators, warm-up and isolation per table (see fdi_diag.h). */
#include "fdi_diag.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

#include "fdi_eval_internal.h"
#include "fdi_float.h"
#include "fdi_gen_internal.h"

#define FDI_TWO_PI_F 6.28318530717959f
#define WARMUP_MARGIN_STEPS 20U
/* the default re-entry of a generated test after its domain or the envelope held it out, its signals usable throughout
   (fdi_diag_config_t.reentry_steps): its filters ran on, its observer restarts and settles within 6 / (12.6 1/s) of
   the generated observers' error pole (fdi_analysis.residuals.generator) */
#define REENTRY_S 0.5f
/* Isolation episodes end after 3 s without any alarm; an alarmed residual's first 3 sigma are taken as noise
   when it implies a fault size. */
#define EPISODE_CLEAR_S 3.0f
#define NOISE_ALLOWANCE_SIGMA 3.0f
/* An alarm sets after 3 raw alarms in a row (30 ms at 10 ms): with the gates calibrated so that no fault-free
   calibration drive ever crossed them (the largest excursion 1 / 1.25 of the gate), the confirmation is short, so
   that a test whose fault-to-noise ratio is 1.67 times its gate alarms within 300 ms of a step fault (the
   practical selection's criterion, fdi_analysis.selection.practical.DETECT_S). */
#define SET_COUNT 3U
/* An alarmed residual implies fault sizes only once it has settled: within a fifth (plus two sigma of noise) of both
   its averages over SETTLE_FAST_S and SETTLE_SLOW_S (exponential averages). A step fault that enters through a
   filtered derivative first kicks the residual far above its steady value, and the kick decays with the filters;
   a decaying residual crosses one average at a time, never both (one alone was fooled where the decay and the
   average have the same rate). The implied size uses the smaller of the residual and its fast average. */
#define SETTLE_FAST_S 0.1f
#define SETTLE_SLOW_S 0.3f
#define SETTLE_REL 0.2f
#define SETTLE_NOISE_SIGMA 2.0f
/* The implied sizes forget with this time constant (recent evidence only: where an alarmed test's sensitivity
   passes near zero its bound spikes, and an episode may last as long as the fault), and a fault leaves the
   candidates only once the on-line rule has cleared it for CLEAR_CONFIRM_S. */
#define IMPLIED_TAU_S 1.0f
#define CLEAR_CONFIRM_S 0.1f
/* largest missing response (in gates) one quiet test adds to the joint rule: finite squares where an implied size
   is huge (an alarmed test's sensitivity near zero) */
#define JOINT_LACK_CAP 1.0e3f
/* During an episode a test's sensitivities are computed every SENS_EVERY steps, the tests in turn (40 ms at 10 ms:
   a quarter of the tests' sensitivity code per step; the rule's decisions are confirmed over CLEAR_CONFIRM_S). */
#define SENS_EVERY 4U
/* the default multiple of an estimate's prediction spread in its test's threshold (fdi_diag_config_t.estimate_kappa):
   three standard deviations */
#define ESTIMATE_KAPPA 3.0f
/* the default decorrelation factor of the estimators (fdi_diag_config_t.estimate_decorrelation): what a residual's model
   leaves unexplained follows the manoeuvre over about 0.1 s (10 steps at 10 ms) */
#define ESTIMATE_DECORRELATION 10.0f
/* the default start-up of an estimated test (fdi_diag_config_t.estimate_startup): its estimator learns for 1 s after
   the warm-up before the test is evaluable */
#define ESTIMATE_STARTUP_S 1.0f

/* The position of the lowest set bit of x != 0 (de Bruijn: x & -x times the sequence 0x077CB531 has a distinct top
   5 bits for each of the 32 powers of two). The isolation's loops over fault masks visit only their set bits with
   it: the undecided faults of an episode are a few of 25. */
static uint32_t lowest_bit(uint32_t x)
{
    static const uint8_t position[32] = {0U,  1U,  28U, 2U,  29U, 14U, 24U, 3U,  30U, 22U, 20U,
                                         15U, 25U, 17U, 4U,  8U,  31U, 27U, 13U, 23U, 21U, 19U,
                                         16U, 7U,  26U, 12U, 18U, 6U,  11U, 5U,  10U, 9U};
    return (uint32_t)position[((x & (~x + 1U)) * 0x077CB531U) >> 27U];
}

/* The number of set bits of x (the Cortex-M4 has no instruction for it: 12 operations). */
static uint32_t bit_count(uint32_t x)
{
    uint32_t c = x - ((x >> 1U) & 0x55555555U);
    c = (c & 0x33333333U) + ((c >> 2U) & 0x33333333U);
    c = (c + (c >> 4U)) & 0x0F0F0F0FU;
    return (c * 0x01010101U) >> 24U;
}

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

/* Sensitivity offsets of the table's tests (test i's entries are the faults of its sens_mask in ascending order:
   sens_at); false when they exceed FDI_DIAG_MAX_SENS. */
static bool sens_layout(const fdi_table_t *t, uint8_t *offset)
{
    uint32_t total = 0U;
    uint32_t i;
    for (i = 0U; i < (uint32_t)t->n_tests; ++i)
    {
        const uint32_t mask = (t->tests[i].gen != NULL) ? t->tests[i].gen->sens_mask : 0U;
        offset[i] = (uint8_t)((total < FDI_DIAG_MAX_SENS) ? total : FDI_DIAG_MAX_SENS);
        total += bit_count(mask & fdi_frame_low_mask(t->n_faults));
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
            cfg->set_count = SET_COUNT;
            cfg->clear_count = 100U;
            cfg->warmup_steps = (uint16_t)(settle + WARMUP_MARGIN_STEPS);
            cfg->reentry_steps = steps_of(REENTRY_S, table->design.dt);
            if (cfg->reentry_steps > cfg->warmup_steps)
            {
                cfg->reentry_steps = cfg->warmup_steps;
            }
            cfg->mode = FDI_ISO_EXONERATION;
            cfg->episode_clear_steps = steps_of(EPISODE_CLEAR_S, table->design.dt);
            cfg->noise_allowance = NOISE_ALLOWANCE_SIGMA;
            cfg->sensitivities = false;
            cfg->sens_every = SENS_EVERY;
            /* robust by default: every test with estimable quantities estimates them, every test's threshold
               adapts to what its model does not know (fdi_diag.h) */
            cfg->adaptive = true;
            cfg->estimate = 0U;
            for (i = 0U; (i < (uint32_t)table->n_tests) && (i < 32U); ++i)
            {
                const fdi_gen_desc_t *g = table->tests[i].gen;
                if ((g != NULL) && (g->n_est > 0U))
                {
                    cfg->estimate |= (uint32_t)1U << i;
                }
            }
            cfg->estimate_kappa = ESTIMATE_KAPPA;
            cfg->estimate_decorrelation = ESTIMATE_DECORRELATION;
            cfg->estimate_startup = steps_of(ESTIMATE_STARTUP_S, table->design.dt);
            st = FDI_OK;
        }
    }
    return st;
}

/* The tests with a generator, the signals they read, and those tests in runs of consecutive tests whose generators
   share their domain function (generated tables give every distinct condition one function and order the tests so):
   runnable() evaluates each run's function once per step. */
static void domain_layout(fdi_diag_t *self, const fdi_table_t *t)
{
    fdi_gen_domain_fn_t fn = NULL;
    uint32_t n = 0U;
    uint32_t i;
    self->gen_tests = 0U;
    self->inputs = 0U;
    self->range_tests = 0U;
    for (i = 0U; i < (uint32_t)t->n_tests; ++i)
    {
        const fdi_gen_desc_t *g = t->tests[i].gen;
        if (g != NULL)
        {
            self->range_tests |= (g->in_range != NULL) ? ((uint32_t)1U << i) : 0U;
            if ((n == 0U) || (g->in_domain != fn))
            {
                fn = g->in_domain;
                self->domain_test[n] = (uint8_t)i;
                self->domain_tests[n] = 0U;
                ++n;
            }
            self->domain_tests[n - 1U] |= (uint32_t)1U << i;
            self->gen_tests |= (uint32_t)1U << i;
            self->inputs |= t->tests[i].input_mask;
        }
    }
    self->n_domains = (uint8_t)n; /* the entries beyond are never read */
}

/* The generator state of the table: the set (the bank first in filt[]), the instance filters of the hand-written
   generators after it, the slot maps, every state zeroed. false when the filters do not fit FDI_DIAG_MAX_FILTERS. */
static bool gen_layout(fdi_diag_t *self, const fdi_table_t *t)
{
    uint32_t used = 0U;
    uint32_t i;
    self->set = NULL;
    self->set_tests = 0U;
    for (i = 0U; i < FDI_GEN_MAX_SLOTS; ++i)
    {
        self->slot_test[i] = 0U;
        self->slot_sens[i] = 0U;
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
            self->slot_sens[g->slot & 31U] = self->sens_offset[i];
        }
    }
    self->slots_in_order = true;
    self->sens_tests = 0U;
    for (i = 0U; i < (uint32_t)t->n_tests; ++i)
    {
        const fdi_gen_desc_t *g = t->tests[i].gen;
        if ((g != NULL) && (g->set != NULL) && ((uint32_t)g->slot != i))
        {
            self->slots_in_order = false;
        }
        if (self->sens_offset[i + 1U] > self->sens_offset[i])
        {
            self->sens_tests |= (uint32_t)1U << i;
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
    domain_layout(self, t);
    return used <= FDI_DIAG_MAX_FILTERS;
}

/* The frame signals of an envelope (0 for none). */
static uint32_t envelope_signals(const fdi_table_envelope_t *e)
{
    uint32_t m = 0U;
    uint32_t k;
    for (k = 0U; (e != NULL) && (k < (uint32_t)e->n_signals); ++k)
    {
        m |= (uint32_t)1U << ((uint32_t)e->signal[k] & 31U);
    }
    return m;
}

/* The tests whose sensitivities are computed together at one step of an episode, every-th step each: the tests by
   their number of sensitivities (largest first, the lower index on a tie), each into the turn with the fewest so far
   (the first on a tie), so that the steps share the sensitivity code about evenly. */
static void sens_turns(fdi_diag_t *self, uint32_t every)
{
    uint32_t load[FDI_DIAG_MAX_SENS_EVERY];
    uint32_t placed = 0U;
    uint32_t g;
    uint32_t n;
    for (g = 0U; g < FDI_DIAG_MAX_SENS_EVERY; ++g)
    {
        load[g] = 0U;
        self->turns[g] = 0U;
    }
    for (n = 0U; n < (uint32_t)self->n_tests; ++n)
    {
        uint32_t best = 0U;
        uint32_t most = 0U;
        uint32_t least = 0U;
        uint32_t i;
        bool first = true;
        for (i = 0U; i < (uint32_t)self->n_tests; ++i)
        {
            const uint32_t count = (uint32_t)self->sens_offset[i + 1U] - (uint32_t)self->sens_offset[i];
            if (((placed & ((uint32_t)1U << i)) == 0U) && (first || (count > most)))
            {
                best = i;
                most = count;
                first = false;
            }
        }
        for (g = 1U; g < every; ++g)
        {
            least = (load[g] < load[least]) ? g : least;
        }
        self->turns[least] |= (uint32_t)1U << best;
        load[least] += most;
        placed |= (uint32_t)1U << best;
    }
}

/* The tests a quiet test may clear a fault by its reaction size for: test_size > 0 for a fault of no on-line
   sensitivity (the pairs fdi_iso_size_cleared() looks at). */
static uint32_t size_rule_tests(const fdi_table_t *t)
{
    uint32_t out = 0U;
    uint32_t i;
    for (i = 0U; i < (uint32_t)t->n_tests; ++i)
    {
        const uint32_t sens = (t->tests[i].gen != NULL) ? t->tests[i].gen->sens_mask : 0U;
        uint32_t j;
        for (j = 0U; j < (uint32_t)t->n_faults; ++j)
        {
            if ((t->test_size[(j * (uint32_t)t->n_tests) + i] > 0.0f) && ((sens & ((uint32_t)1U << j)) == 0U))
            {
                out |= (uint32_t)1U << i;
            }
        }
    }
    return out;
}

/* The tests whose generator lists rate gains (raise_drift). */
static uint32_t rate_gain_tests(const fdi_table_t *t)
{
    uint32_t out = 0U;
    uint32_t i;
    for (i = 0U; i < (uint32_t)t->n_tests; ++i)
    {
        const fdi_gen_desc_t *g = t->tests[i].gen;
        out |= ((g != NULL) && (g->rate_mask != 0U)) ? ((uint32_t)1U << i) : 0U;
    }
    return out;
}

/* The faults whose on-line exoneration can still change the candidates of the episode: those that explain every
   accused test and are not latched (none once the episode is contradicted). The accused tests only grow during an
   episode, so a fault outside this set stays outside until the episode ends. */
static uint32_t undecided_faults(const fdi_diag_t *self)
{
    uint32_t undecided = 0U;
    if (self->latched != FDI_DIAG_CONTRADICTED)
    {
        uint32_t j;
        for (j = 0U; j < (uint32_t)self->n_faults; ++j)
        {
            if ((self->accused & ~self->table->fault_signature[j]) == 0U)
            {
                undecided |= (uint32_t)1U << j;
            }
        }
        undecided &= ~self->latched;
    }
    return undecided;
}

/* Whether every test of `tests` is a test of the table whose generator declares estimable quantities. */
static bool estimable(const fdi_table_t *t, uint32_t tests)
{
    uint32_t left = tests;
    uint32_t i;
    for (i = 0U; (left != 0U) && (i < (uint32_t)t->n_tests); ++i)
    {
        const uint32_t bit = (uint32_t)1U << i;
        if (((left & bit) != 0U) && (t->tests[i].gen != NULL) && (t->tests[i].gen->n_est > 0U))
        {
            left &= ~bit;
        }
    }
    return left == 0U;
}

static fdi_status_t check_config(const fdi_diag_config_t *cfg)
{
    fdi_status_t st = fdi_table_check(cfg->table);
    if (st != FDI_OK)
    {
        /* keep the status of the table check */
    }
    else if (!fdi_float_is_finite(cfg->cusum_k) || !fdi_float_is_finite(cfg->cusum_h) ||
             !fdi_float_is_finite(cfg->noise_allowance))
    {
        st = FDI_NOT_FINITE;
    }
    else if ((cfg->table->n_tests > FDI_DIAG_MAX_TESTS) || (cfg->episode_clear_steps == 0U) ||
             (cfg->sens_every > FDI_DIAG_MAX_SENS_EVERY) ||
             (cfg->noise_allowance < 0.0f) ||
             ((cfg->mode != FDI_ISO_NO_EXONERATION) && (cfg->mode != FDI_ISO_EXONERATION)))
    {
        st = FDI_BAD_ARG;
    }
    else if ((cfg->estimate != 0U) &&
             (!fdi_float_is_finite(cfg->estimate_kappa) || !fdi_float_is_finite(cfg->estimate_decorrelation)))
    {
        st = FDI_NOT_FINITE;
    }
    else if ((cfg->estimate != 0U) && ((cfg->estimate_kappa < 0.0f) || (cfg->estimate_decorrelation < 1.0f) ||
                                       !estimable(cfg->table, cfg->estimate)))
    {
        st = FDI_BAD_ARG;
    }
    else
    {
        const uint32_t need = settle_steps(&cfg->table->design);
        if ((need == 0U) || ((uint32_t)cfg->warmup_steps < need) || (cfg->reentry_steps == 0U) ||
            (cfg->reentry_steps > cfg->warmup_steps))
        {
            st = FDI_BAD_ARG;
        }
    }
    return st;
}

fdi_status_t fdi_diag_layout(fdi_diag_layout_t *out)
{
    fdi_status_t st = FDI_BAD_ARG;
    if (out != NULL)
    {
        *out = fdi_diag_layout_here();
        st = FDI_OK;
    }
    return st;
}

/* Whether the caller's layout signature is the library's (field by field: the struct has no padding). */
static bool same_layout(const fdi_diag_layout_t *caller)
{
    const fdi_diag_layout_t own = fdi_diag_layout_here();
    return (caller->max_tests == own.max_tests) && (caller->max_sens == own.max_sens) &&
           (caller->max_filters == own.max_filters) && (caller->est_max_params == own.est_max_params) &&
           (caller->gen_max_filters == own.gen_max_filters) && (caller->size_diag == own.size_diag) &&
           (caller->size_config == own.size_config) && (caller->size_result == own.size_result) &&
           (caller->size_evidence == own.size_evidence) && (caller->size_table == own.size_table) &&
           (caller->size_gen_desc == own.size_gen_desc);
}

fdi_status_t fdi_diag_init_layout(fdi_diag_t *self, const fdi_diag_config_t *cfg, const fdi_diag_layout_t *caller)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((self != NULL) && (cfg != NULL) && (caller != NULL))
    {
        st = same_layout(caller) ? check_config(cfg) : FDI_BAD_LAYOUT;
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
        if ((st == FDI_OK) && !sens_layout(t, self->sens_offset) &&
            (cfg->sensitivities || (cfg->mode == FDI_ISO_EXONERATION)))
        {
            st = FDI_BAD_ARG;
        }
        if ((st == FDI_OK) && !gen_layout(self, t))
        {
            st = FDI_BAD_ARG;
        }
        for (i = 0U; i < FDI_DIAG_MAX_SENS; ++i)
        {
            self->sens[i] = 0.0f;
        }
        self->signals = envelope_signals(t->envelope); /* checked finite at every step, with the tests' */
        for (i = 0U; (st == FDI_OK) && (i < (uint32_t)t->n_tests); ++i)
        {
            const fdi_test_desc_t *d = &t->tests[i];
            const fdi_eval_config_t ecfg = {d->gate,        d->variance,    cfg->cusum_k,
                                            cfg->cusum_h,   cfg->set_count, cfg->clear_count};
            self->signals |= d->input_mask;
            st = fdi_eval_init(&self->eval[i], &ecfg);
            self->residual[i] = 0.0f;
            self->ratio[i] = 0.0f;
            self->spread[i] = 0.0f;
            self->correction[i] = 0.0f;
            self->est_seen[i] = 0U;
            if ((st == FDI_OK) && ((cfg->estimate & ((uint32_t)1U << i)) != 0U))
            {
                st = fdi_est_init(&self->est[i], d->gen->est, (uint32_t)d->gen->n_est);
            }
            self->warm[i] = cfg->warmup_steps;
            self->quiet_run[i] = 0U;
            self->alarm_run[i] = 0U;
            self->clears[i] = 0U;
            self->r_fast[i] = 0.0f;
            self->r_slow[i] = 0.0f;
        }
        for (i = 0U; i < FDI_TABLE_MAX_FAULTS; ++i)
        {
            self->implied[i] = 0.0f;
            self->drift[i] = 0.0f;
            self->cleared_run[i] = 0U;
        }
        if (st == FDI_OK)
        {
            self->table = t;
            self->mode = cfg->mode;
            self->warmup_steps = cfg->warmup_steps;
            self->episode_clear_steps = cfg->episode_clear_steps;
            self->set_count = cfg->set_count;
            self->noise_allowance = cfg->noise_allowance;
            self->fast_gain = t->design.dt / SETTLE_FAST_S;
            self->implied_keep = 1.0f - (t->design.dt / IMPLIED_TAU_S);
            self->clear_confirm = steps_of(CLEAR_CONFIRM_S, t->design.dt);
            self->n_faults = t->n_faults;
            self->slow_gain = t->design.dt / SETTLE_SLOW_S;
            self->fresh = 0U;
            self->latched = 0U;
            self->episode_age = 0U;
            self->calm = 0U;
            self->accused = 0U;
            self->n_tests = t->n_tests;
            self->sensitivities = cfg->sensitivities;
            self->adaptive = cfg->adaptive;
            self->estimate = cfg->estimate;
            self->est_kappa = cfg->estimate_kappa;
            self->est_decorrelation = cfg->estimate_decorrelation;
            self->est_startup = cfg->estimate_startup;
            self->sens_every = (cfg->sens_every > 1U) ? (uint8_t)cfg->sens_every : 1U;
            sens_turns(self, (uint32_t)self->sens_every);
            self->sens_known = 0U;
            self->rearm = 0xFFFFFFFFU;
            self->held = 0U;
            self->reentry_steps = cfg->reentry_steps;
            self->alarm = 0U;
            self->evaluable = 0U;
            self->in_envelope = true;
            self->iso_valid = false;
            self->size_accused = 0U; /* accused 0: no episode, never asked */
            self->size_quiet = 0U;
            self->size_cleared = 0U;
            self->iso_accused = 0U;
            self->iso_cleared = 0U;
            self->bank_live = 0U;
            self->size_tests = size_rule_tests(t);
            self->rate_tests = rate_gain_tests(t);
            self->undecided = undecided_faults(self);
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

/* The sensitivities of test i back to 0 (and unknown in the episode). */
static void clear_sens(fdi_diag_t *self, uint32_t i)
{
    uint32_t k;
    self->sens_known &= ~((uint32_t)1U << i);
    for (k = (uint32_t)self->sens_offset[i]; k < (uint32_t)self->sens_offset[i + 1U]; ++k)
    {
        self->sens[k] = 0.0f;
    }
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

/* Whether test i's sensitivities in self->sens are all finite: s * 0 is +-0 for a finite s and NaN for NaN and +-Inf,
   so the sum of these is finite iff every sensitivity is (one check per test). */
static bool sens_finite(const fdi_diag_t *self, uint32_t i)
{
    float zero = 0.0f;
    uint32_t k;
    for (k = (uint32_t)self->sens_offset[i]; k < (uint32_t)self->sens_offset[i + 1U]; ++k)
    {
        zero += self->sens[k] * 0.0f;
    }
    return fdi_float_is_finite(zero);
}

/* The slots of the set of the tests of `tests` (the identity when every test of the set is its slot, as in the
   generated tables). */
static uint32_t slots_of(const fdi_diag_t *self, uint32_t tests)
{
    uint32_t slots = tests;
    if (!self->slots_in_order)
    {
        uint32_t i;
        slots = 0U;
        for (i = 0U; i < (uint32_t)self->n_tests; ++i)
        {
            if ((tests & ((uint32_t)1U << i)) != 0U)
            {
                slots |= (uint32_t)1U << (self->table->tests[i].gen->slot & 31U);
            }
        }
    }
    return slots;
}

/* The tests of the set's slots `slots` (inverse of slots_of). */
static uint32_t tests_of(const fdi_diag_t *self, uint32_t slots)
{
    uint32_t tests = slots;
    if (!self->slots_in_order)
    {
        uint32_t k;
        tests = 0U;
        for (k = 0U; k < (uint32_t)self->set->n_slots; ++k)
        {
            if ((slots & ((uint32_t)1U << k)) != 0U)
            {
                tests |= (uint32_t)1U << (self->slot_test[k] & 31U);
            }
        }
    }
    return tests;
}

/* The generators of the tests of `run` (inputs usable, in their domain): the set's slots in one call, the
   hand-written ones one by one; r[i] and the returned mask (bit i: finite residual and sensitivities). The
   sensitivities of the tests of `want` are computed into self->sens (and the tests marked fresh). */
static uint32_t run_generators(fdi_diag_t *self, const fdi_frame_t *in, uint32_t run, uint32_t want, float *r,
                               float *reg)
{
    const uint32_t hand = run & ~self->set_tests;
    const uint32_t set = run & self->set_tests;
    uint32_t ok = 0U;
    uint32_t i;
    for (i = 0U; i < (uint32_t)self->n_tests; ++i)
    {
        self->spread[i] = 0.0f; /* hand-written generators and tests that do not run: the fixed gate */
    }
    if (hand != 0U)
    {
        for (i = 0U; i < (uint32_t)self->n_tests; ++i)
        {
            const uint32_t bit = (uint32_t)1U << i;
            if ((hand & bit) != 0U)
            {
                float *sens = ((want & self->sens_tests & bit) != 0U) ? &self->sens[self->sens_offset[i]] : NULL;
                if (run_hand_written(self, i, in, &r[i], sens) == FDI_OK)
                {
                    ok |= bit;
                    self->fresh |= (sens != NULL) ? bit : 0U;
                    self->sens_known |= (sens != NULL) ? bit : 0U;
                }
            }
        }
    }
    if ((set != 0U) && (self->set != NULL))
    {
        const uint32_t with_sens = set & want & self->sens_tests;
        uint32_t check;
        uint32_t failed;
        fdi_gen_io_t io;
        io.par = &self->par;
        io.in = in;
        io.bank = self->filt;
        io.obs = self->obs;
        io.r = r;
        io.at = self->slot_test;
        io.sens = self->sens;
        io.sens_at = self->slot_sens;
        io.run = slots_of(self, set);
        io.restart = slots_of(self, set & self->rearm);
        io.sens_mask = slots_of(self, with_sens);
        /* slots without an uncertainty term keep 0; the regressors of the estimable quantities come with it */
        io.spread = (self->adaptive || (self->estimate != 0U)) ? self->spread : NULL;
        io.reg = (io.spread != NULL) ? reg : NULL;
        io.failed = 0U;
        self->set->step(&io);
        failed = tests_of(self, io.failed & io.run);
        ok |= set & ~failed & ~with_sens; /* a non-finite residual or state is rejected by the evaluation */
        check = with_sens & ~failed;
        for (i = 0U; (check != 0U) && (i < (uint32_t)self->n_tests); ++i)
        {
            const uint32_t bit = (uint32_t)1U << i;
            if (((check & bit) != 0U) && sens_finite(self, i)) /* a non-finite sensitivity fails the step too */
            {
                ok |= bit;
                self->fresh |= bit;
                self->sens_known |= bit;
            }
            check &= ~bit;
        }
    }
    return ok;
}

static uint16_t sat_inc(uint16_t x)
{
    return (x < 0xFFFFU) ? (uint16_t)(x + 1U) : x;
}

/* Of the tests of `among`, those whose sensitivities the exoneration may read at this step (decided before the
   evaluation, so a superset): a sensitivity of an undecided fault, and in alarm for its response time should it alarm
   now, or settled and quiet should it stay quiet (the conditions of exonerated() on this step's counters). */
static uint32_t sens_wanted(const fdi_diag_t *self, uint32_t undecided, uint32_t among)
{
    const uint32_t age = (uint32_t)sat_inc(self->episode_age);
    uint32_t left = among;
    uint32_t want = 0U;
    uint32_t i;
    for (i = 0U; (left != 0U) && (i < (uint32_t)self->n_tests); ++i)
    {
        const fdi_test_desc_t *d = &self->table->tests[i];
        const uint32_t bit = (uint32_t)1U << i;
        if (((left & bit) != 0U) && (d->gen != NULL) && ((d->gen->sens_mask & undecided) != 0U))
        {
            const uint32_t resp = (uint32_t)d->response_steps + (uint32_t)self->set_count;
            const bool alarm_ready = (uint32_t)sat_inc(self->alarm_run[i]) >= resp;
            const bool quiet_ready = ((self->accused & bit) == 0U) && ((uint32_t)sat_inc(self->quiet_run[i]) >= resp) &&
                                     (age >= resp);
            want |= (alarm_ready || quiet_ready) ? bit : 0U;
        }
        left &= ~bit;
    }
    return want;
}

/* The tests whose turn it is to compute their sensitivities at this step of an episode (sens_turns). */
static uint32_t sens_turn(const fdi_diag_t *self)
{
    return self->turns[(uint32_t)sat_inc(self->episode_age) % (uint32_t)self->sens_every];
}

/* The residual test i evaluates and its threshold's spread (fdi_diag.h "On-line estimation", "Adaptive thresholds"):
   with an estimator, the innovation r - h . theta (the filter updated unless the test alarms or an episode accuses
   it) and kappa times the estimate's prediction spread plus the generator's spread over what it does not estimate;
   without one, r and, with adaptive thresholds, the generator's spread plus the estimable quantities at their
   declared widths (the whole envelope), else 0. reg: the test's regressors (FDI_EST_MAX_PARAMS entries; a
   hand-written generator's estimable quantities are offsets, regressor 1). */
static bool corrected(fdi_diag_t *self, uint32_t i, const float *reg, float *r)
{
    bool ready = true;
    const uint32_t bit = (uint32_t)1U << i;
    const fdi_gen_desc_t *g = self->table->tests[i].gen;
    const uint32_t n = (g != NULL) ? (uint32_t)g->n_est : 0U;
    float h[FDI_EST_MAX_PARAMS] = {0};
    uint32_t e;
    for (e = 0U; e < FDI_EST_MAX_PARAMS; ++e)
    {
        h[e] = ((e < n) && (g->set != NULL)) ? reg[e] : 1.0f;
    }
    if (((self->estimate & bit) != 0U) && (g != NULL)) /* fdi_diag_init admits only tests with estimable quantities */
    {
        /* frozen while the test alarms and for the rest of an episode it is accused in */
        const bool freeze = (((self->alarm | self->accused) & bit) != 0U);
        float nu = *r;
        float a = 0.0f;
        const float noise = self->table->tests[i].variance * self->est_decorrelation;
        if (fdi_est_update(&self->est[i], g->est, n, h, *r, noise, self->est_decorrelation, freeze, &nu, &a) ==
            FDI_OK)
        {
            self->correction[i] = *r - nu;
            *r = nu;
            self->spread[i] += self->est_kappa * a;
        }
        if (self->est_seen[i] < self->est_startup)
        {
            self->est_seen[i]++; /* the start-up: the estimator learns, the test is not evaluable yet */
            ready = false;
        }
    }
    else if (self->adaptive)
    {
        for (e = 0U; e < n; ++e)
        {
            const float lo = -g->est[e].lo;
            const float width = (g->est[e].hi > lo) ? g->est[e].hi : lo;
            self->spread[i] += fabsf(h[e]) * width;
        }
    }
    else
    {
        self->spread[i] = 0.0f;
    }
    return ready;
}

/* Evaluation of test i after its generator ran (ok: a finite residual r and spread) against its gate widened by the
   spread (the adaptive threshold, fdi_eval.h; 0 without one), with its offset estimate removed; true if it is
   evaluable this step (then *alarm is set). */
static bool evaluate(fdi_diag_t *self, uint32_t i, bool ok, float r_gen, const float *reg, bool *alarm)
{
    const uint32_t bit = (uint32_t)1U << i;
    bool evaluable = false;
    float r = r_gen;
    fdi_status_t st = ok ? FDI_OK : FDI_NOT_FINITE;
    if ((st == FDI_OK) && ((self->rearm & bit) != 0U))
    {
        st = fdi_eval_reset(&self->eval[i]);
        self->warm[i] = ((self->held & bit) != 0U) ? self->reentry_steps : self->warmup_steps;
        self->held &= ~bit;
        self->rearm &= ~bit;
    }
    if (st != FDI_OK)
    {
        self->rearm |= bit;
        self->residual[i] = 0.0f;
        self->ratio[i] = 0.0f;
        self->spread[i] = 0.0f;
        self->fresh &= ~bit;
        clear_sens(self, i);
    }
    else if (self->warm[i] > 0U)
    {
        self->warm[i]--;
        self->residual[i] = r;
        self->ratio[i] = 0.0f;
        if (!self->adaptive && ((self->estimate & bit) == 0U))
        {
            self->spread[i] = 0.0f;
        }
    }
    else if (!fdi_float_is_finite(r))
    {
        self->rearm |= bit;
    }
    else /* fdi_eval_step()'s evaluation inline: eval[i] is initialised, r checked here */
    {
        float ratio = 0.0f;
        if (corrected(self, i, reg, &r))
        {
            evaluable = true;
            *alarm = fdi_eval_update(&self->eval[i], r, self->spread[i], &ratio);
        }
        self->residual[i] = r;
        self->ratio[i] = ratio;
    }
    return evaluable;
}

/* Sigma of test i's residual (only asked for during episodes). */
static float test_sigma(const fdi_diag_t *self, uint32_t i)
{
    return sqrtf(self->table->tests[i].variance);
}

/* The smaller / larger of two finite values (residuals, averages and sizes are checked finite before they are kept;
   newlib's fminf/fmaxf classify both operands through library calls). */
static float smaller(float a, float b)
{
    return (a < b) ? a : b;
}

static float larger(float a, float b)
{
    return (a > b) ? a : b;
}

/* Where sensitivity s_ij of test i is in self->sens, for a fault j of its sens_mask: the entries of test i are the
   faults of its sens_mask in ascending order (sens_layout), so j's is after those of the faults below it. */
static uint32_t sens_at(const fdi_diag_t *self, uint32_t i, uint32_t sens_mask, uint32_t j)
{
    return (uint32_t)self->sens_offset[i] + bit_count(sens_mask & (((uint32_t)1U << j) - 1U));
}

/* Test i is in alarm and has been for its response time, with fresh sensitivities: once its residual has settled,
   its average and its sensitivities bound the size of each undecided fault of its sens_mask from below; the
   episode keeps the largest bound (see fdi_diag.h). A fault of its signature without a sensitivity (its
   steady-state sensitivity is zero: it reaches the residual only through a filtered derivative) gets no bound
   here: a drift of it explains a settled residual (raise_drift bounds how far it has moved instead, where the
   generator lists its rate gain). */
static void raise_implied(fdi_diag_t *self, uint32_t i, uint32_t undecided)
{
    const fdi_gen_desc_t *g = self->table->tests[i].gen;
    const float sigma = test_sigma(self, i);
    const float r = self->residual[i];
    const float fast = self->r_fast[i];
    const float slow = self->r_slow[i];
    const bool settled = (fabsf(r - fast) <= ((SETTLE_REL * fabsf(fast)) + (SETTLE_NOISE_SIGMA * sigma))) &&
                         (fabsf(r - slow) <= ((SETTLE_REL * fabsf(slow)) + (SETTLE_NOISE_SIGMA * sigma)));
    const float least = smaller(fabsf(r), fabsf(fast));
    /* the part of the residual neither noise nor the model's uncertainty (its spread) explains */
    const float excess = least - (self->noise_allowance * sigma) - self->spread[i];
    if ((g != NULL) && (g->sens_mask != 0U) && settled && (excess > 0.0f))
    {
        uint32_t left = g->sens_mask & undecided;
        while (left != 0U)
        {
            const uint32_t j = lowest_bit(left);
            const uint32_t k = sens_at(self, i, g->sens_mask, j);
            const float s = (k < (uint32_t)self->sens_offset[i + 1U]) ? fabsf(self->sens[k]) : 0.0f;
            if (s > 0.0f)
            {
                const float f = excess / s;
                if (fdi_float_is_finite(f) && (f > self->implied[j]))
                {
                    self->implied[j] = f;
                }
            }
            left &= left - 1U;
        }
    }
}

/* The tests of `tests` (in alarm, with rate gains) bound how fast each undecided fault of their rate_mask has
   moved: under fault j alone, test i's residual is r_i = g_ij d/dt (f_j through the filters) + noise, whatever the
   shape of f_j (a step gives a decaying kick, a drift a steady value), so at this step the filtered f_j moves at
   least by rho_j dt with rho_j = (|r_i| - noise_allowance sigma_i) / |g_ij|, signed as r_i / g_ij (the largest
   bound of the step). Added up over the alarmed steps of the episode, |drift_j| is a lower bound of how far the
   filtered f_j has moved since the episode began (moves of opposite sign cancel), and, for a fault absent before
   the episode, a size the alarms imply (see fdi_diag.h). */
static void raise_drift(fdi_diag_t *self, uint32_t tests, uint32_t undecided)
{
    float rate[FDI_TABLE_MAX_FAULTS]; /* read and written only at the faults of `bounded` */
    uint32_t bounded = 0U;
    uint32_t i;
    for (i = 0U; i < (uint32_t)self->n_tests; ++i)
    {
        const fdi_gen_desc_t *g = self->table->tests[i].gen;
        if (((tests & ((uint32_t)1U << i)) != 0U) && (g != NULL) && ((g->rate_mask & undecided) != 0U))
        {
            const float r = self->residual[i];
            const float above = fabsf(r) - (self->noise_allowance * test_sigma(self, i)) - self->spread[i];
            const float excess = (r < 0.0f) ? -above : above;
            uint32_t left = (above > 0.0f) ? g->rate_mask : 0U; /* gains ascend by fault */
            uint32_t k = 0U;
            while (left != 0U)
            {
                const uint32_t j = lowest_bit(left);
                const uint32_t bit = (uint32_t)1U << j;
                const float rho = excess / g->rate_gain[k]; /* finite / finite non-zero: at most +-Inf */
                if (((undecided & bit) != 0U) && (((bounded & bit) == 0U) || (fabsf(rho) > fabsf(rate[j]))))
                {
                    rate[j] = rho;
                    bounded |= bit;
                }
                left &= left - 1U;
                ++k;
            }
        }
    }
    while (bounded != 0U)
    {
        const uint32_t j = lowest_bit(bounded);
        /* a finite drift plus at most an infinite move: saturate, no NaN */
        const float moved = self->drift[j] + (rate[j] * self->table->design.dt);
        self->drift[j] = smaller(larger(moved, -FLT_MAX), FLT_MAX);
        self->implied[j] = larger(self->implied[j], fabsf(self->drift[j]));
        bounded &= bounded - 1U;
    }
}

/* The undecided faults a settled quiet test i clears with its fresh sensitivities: |s_ij| F_j >= margin * gate *
   sigma + 2 spread (with an adaptive threshold, the uncertainty may both hide up to a spread of the fault's
   response and have raised the threshold by as much). */
static uint32_t quiet_clears(const fdi_diag_t *self, uint32_t i, uint32_t undecided)
{
    const fdi_test_desc_t *d = &self->table->tests[i];
    uint32_t out = 0U;
    if (d->gen != NULL)
    {
        const float need = (self->table->sensitivity_margin * d->gate * test_sigma(self, i)) + (2.0f * self->spread[i]);
        uint32_t left = d->gen->sens_mask & undecided;
        while (left != 0U)
        {
            const uint32_t j = lowest_bit(left);
            const uint32_t k = sens_at(self, i, d->gen->sens_mask, j);
            if ((k < (uint32_t)self->sens_offset[i + 1U]) && ((fabsf(self->sens[k]) * self->implied[j]) >= need))
            {
                out |= (uint32_t)1U << j;
            }
            left &= left - 1U;
        }
    }
    return out;
}

/* The undecided faults of `faults` that the settled quiet tests of `settled` clear together (see fdi_diag.h): at
   the implied size F_j, with its sensitivity taken margin times smaller, quiet test q would show a response its
   residual lacks by d_q = (|s_qj| F_j / margin - max(|r_q|, |0.1 s average|)) / (gate_q sigma_q); j is cleared
   when the d_q > 0 reach 1 in the sum of their squares (together the tests miss a response worth a gate). */
static uint32_t joint_clears(const fdi_diag_t *self, uint32_t settled, uint32_t faults)
{
    uint32_t out = 0U;
    if ((faults != 0U) && (settled != 0U)) /* most episode steps: nothing left to decide */
    {
        float missing[FDI_TABLE_MAX_FAULTS]; /* read and written only at the faults of `faults` */
        const float per_margin = 1.0f / self->table->sensitivity_margin;
        uint32_t left = faults;
        uint32_t i;
        while (left != 0U)
        {
            missing[lowest_bit(left)] = 0.0f;
            left &= left - 1U;
        }
        for (i = 0U; i < (uint32_t)self->n_tests; ++i)
        {
            const fdi_test_desc_t *d = &self->table->tests[i];
            if (((settled & ((uint32_t)1U << i)) != 0U) && (d->gen != NULL) && ((d->gen->sens_mask & faults) != 0U))
            {
                const float per_gate = 1.0f / (d->gate * test_sigma(self, i));
                /* with an adaptive threshold, the response the uncertainty may hide and the threshold's rise */
                const float seen = larger(fabsf(self->residual[i]), fabsf(self->r_fast[i])) + (2.0f * self->spread[i]);
                uint32_t wanted = d->gen->sens_mask & faults;
                while (wanted != 0U)
                {
                    const uint32_t j = lowest_bit(wanted);
                    const uint32_t k = sens_at(self, i, d->gen->sens_mask, j);
                    if (k < (uint32_t)self->sens_offset[i + 1U])
                    {
                        /* capped: a huge implied size stays finite here */
                        const float expect = fabsf(self->sens[k]) * self->implied[j] * per_margin;
                        const float lack = smaller(JOINT_LACK_CAP, (expect - seen) * per_gate);
                        if (lack > 0.0f)
                        {
                            missing[j] += lack * lack;
                        }
                    }
                    wanted &= wanted - 1U;
                }
            }
        }
        left = faults;
        while (left != 0U)
        {
            const uint32_t j = lowest_bit(left);
            out |= (missing[j] >= 1.0f) ? ((uint32_t)1U << j) : 0U;
            left &= left - 1U;
        }
    }
    return out;
}

/* Episode start/end and age (see "Isolation episodes" in fdi_diag.h). */
static void track_episode(fdi_diag_t *self, uint32_t alarm)
{
    if (alarm != 0U)
    {
        if (self->accused == 0U)
        {
            uint32_t i;
            self->episode_age = 0U;
            self->latched = 0U;
            self->sens_known = 0U;
            for (i = 0U; i < FDI_TABLE_MAX_FAULTS; ++i)
            {
                self->implied[i] = 0.0f;
                self->drift[i] = 0.0f;
                self->cleared_run[i] = 0U;
            }
            for (i = 0U; i < FDI_DIAG_MAX_TESTS; ++i)
            {
                self->clears[i] = 0U;
            }
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
}

/* The faults the exoneration clears this step (see "Isolation episodes" in fdi_diag.h): on line by the settled
   quiet tests' fresh sensitivities (confirmed for clear_confirm steps), and by reaction sizes for the pairs
   without an on-line sensitivity. Only the undecided faults (self->undecided) can change the candidates: the
   implied sizes and on-line decisions of the others are left alone. */
static uint32_t exonerated(fdi_diag_t *self, uint32_t alarm)
{
    const uint32_t undecided = self->undecided;
    uint32_t cleared = 0U;
    /* no fault left to decide: nothing below can change the candidates, and none is left until the episode ends
       (undecided_faults) */
    if (undecided != 0U)
    {
        uint32_t settled = 0U;
        const uint32_t drifting = alarm & self->rate_tests; /* tests with rate gains in alarm */
        uint32_t online = 0U;
        uint32_t left = undecided;
        uint32_t i;
        /* the implied sizes and confirmation runs of the undecided faults only: no other is read again in the
           episode (undecided_faults), and track_episode resets them all at the next */
        while (left != 0U)
        {
            self->implied[lowest_bit(left)] *= self->implied_keep;
            left &= left - 1U;
        }
        for (i = 0U; i < (uint32_t)self->n_tests; ++i)
        {
            const uint32_t bit = (uint32_t)1U << i;
            const uint32_t resp = (uint32_t)self->table->tests[i].response_steps + (uint32_t)self->set_count;
            if (((alarm & self->fresh & bit) != 0U) && ((uint32_t)self->alarm_run[i] >= resp))
            {
                raise_implied(self, i, undecided);
            }
            if (((self->accused & bit) == 0U) && ((uint32_t)self->quiet_run[i] >= resp) &&
                ((uint32_t)self->episode_age >= resp))
            {
                settled |= bit;
            }
        }
        if (drifting != 0U)
        {
            raise_drift(self, drifting, undecided);
        }
        for (i = 0U; i < (uint32_t)self->n_tests; ++i)
        {
            const uint32_t bit = (uint32_t)1U << i;
            if ((settled & bit) == 0U)
            {
                self->clears[i] = 0U;
            }
            else if ((self->fresh & bit) != 0U)
            {
                self->clears[i] = quiet_clears(self, i, undecided);
            }
            else
            {
                /* keep the last decision until its sensitivities are computed again (sens_every) */
            }
            online |= self->clears[i];
        }
        /* the joint rule reads the tests' latest sensitivities: only those computed in this episode */
        online |= joint_clears(self, settled & self->sens_known, undecided & ~online);
        left = undecided;
        while (left != 0U)
        {
            const uint32_t j = lowest_bit(left);
            const uint32_t fbit = (uint32_t)1U << j;
            self->cleared_run[j] = ((online & fbit) != 0U) ? sat_inc(self->cleared_run[j]) : 0U;
            cleared |= (self->cleared_run[j] >= self->clear_confirm) ? fbit : 0U;
            left &= left - 1U;
        }
        /* only the tests of size_tests can clear by reaction sizes (fdi_iso_size_cleared gives 0 for the others); the
           rule reads nothing but the table and the two masks, so its result is kept until they change */
        if ((settled & self->size_tests) != 0U)
        {
            const uint32_t quiet = settled & self->size_tests;
            if ((self->accused != self->size_accused) || (quiet != self->size_quiet))
            {
                self->size_cleared = fdi_iso_size_cleared(self->table, self->accused, quiet);
                self->size_accused = self->accused;
                self->size_quiet = quiet;
            }
            cleared |= self->size_cleared;
        }
    }
    return cleared;
}

/* The first class isolated in the episode is latched; an accused test it cannot explain contradicts it for the
   rest of the episode (fdi_diag.h). */
static void latch(fdi_diag_t *self)
{
    if ((self->latched != 0U) && ((self->iso.candidates & self->latched) == 0U))
    {
        self->latched = FDI_DIAG_CONTRADICTED;
    }
    if (self->latched == FDI_DIAG_CONTRADICTED)
    {
        self->iso.candidates = 0U;
        self->iso.class_mask = 0U;
        self->iso.n_classes = 0U;
        self->iso.isolated = false;
    }
    else if ((self->latched == 0U) && self->iso.isolated)
    {
        self->latched = self->iso.candidates;
    }
    else
    {
        /* keep the latched class */
    }
}

/* Whether the frame is inside the table's calibrated envelope (fdi_table.h): fewer than `votes` of its signals that
   are usable at the step beyond their limits; always without an envelope. */
static bool inside_envelope(const fdi_table_envelope_t *e, const fdi_frame_t *frame, uint32_t usable)
{
    uint32_t over = 0U;
    if (e != NULL)
    {
        uint32_t k;
        for (k = 0U; k < (uint32_t)e->n_signals; ++k)
        {
            const uint32_t sig = (uint32_t)e->signal[k] & 31U;
            if (((usable & ((uint32_t)1U << sig)) != 0U) && (fabsf(frame->value[sig]) > e->limit[k]))
            {
                ++over;
            }
        }
    }
    return (e == NULL) || (over < (uint32_t)e->votes);
}

/* Episode bookkeeping and the isolation of this step (see "Isolation episodes" in fdi_diag.h). */
static fdi_status_t isolate(fdi_diag_t *self, uint32_t alarm)
{
    const uint32_t accused = self->accused;
    uint32_t latched = self->latched;
    uint32_t cleared = 0U;
    fdi_status_t st;
    track_episode(self, alarm);
    if ((self->accused != accused) || (self->latched != latched))
    {
        self->undecided = undecided_faults(self);
        latched = self->latched;
    }
    if ((self->mode == FDI_ISO_EXONERATION) && (self->accused != 0U))
    {
        cleared = exonerated(self, alarm);
    }
    /* accused tests stay in the alarm set even while not evaluable now: they alarmed in this episode; the faults
       isolated first in the episode are exonerated no more. The match of the same accused tests and cleared faults
       as at the last step is the same (latch() below leaves it as it is then). */
    cleared &= ~self->latched;
    st = FDI_OK;
    if (!self->iso_valid || (self->accused != self->iso_accused) || (cleared != self->iso_cleared))
    {
        st = fdi_iso_match(self->table, self->accused, cleared, &self->iso);
        self->iso_accused = self->accused;
        self->iso_cleared = cleared;
        self->iso_valid = (st == FDI_OK);
    }
    if (st == FDI_OK)
    {
        latch(self);
        if (self->latched != latched)
        {
            self->undecided = undecided_faults(self);
        }
    }
    return st;
}

/* The tests that run at this step (inside the envelope): a generator whose inputs are usable and whose domain
   holds. Each run of tests sharing a domain function (domain_layout) evaluates it once (it reads only the frame), and
   only where some test of the run has its inputs; while every signal the tests read is usable (steady state), no
   test is visited one by one. */
static uint32_t runnable(const fdi_diag_t *self, const fdi_frame_t *in, uint32_t usable)
{
    uint32_t ready = self->gen_tests;
    uint32_t run;
    uint32_t k;
    if ((usable & self->inputs) != self->inputs)
    {
        uint32_t i;
        ready = 0U;
        for (i = 0U; i < (uint32_t)self->n_tests; ++i)
        {
            const fdi_test_desc_t *d = &self->table->tests[i];
            if ((d->gen != NULL) && ((usable & d->input_mask) == d->input_mask))
            {
                ready |= (uint32_t)1U << i;
            }
        }
    }
    run = ready;
    for (k = 0U; k < (uint32_t)self->n_domains; ++k)
    {
        const uint32_t group = self->domain_tests[k];
        if (((ready & group) != 0U) && !fdi_gen_in_domain(self->table->tests[self->domain_test[k]].gen, in))
        {
            run &= ~group;
        }
    }
    return run;
}

/* Of the tests of `run`, those whose generator's range holds the frame (fdi_gen_in_range). */
static uint32_t in_range(const fdi_diag_t *self, const fdi_frame_t *in, uint32_t run)
{
    uint32_t out = run;
    uint32_t left = run & self->range_tests;
    uint32_t i;
    for (i = 0U; (left != 0U) && (i < (uint32_t)self->n_tests); ++i)
    {
        const uint32_t bit = (uint32_t)1U << i;
        if (((left & bit) != 0U) && !fdi_gen_in_range(self->table->tests[i].gen, in))
        {
            out &= ~bit;
        }
        left &= ~bit;
    }
    return out;
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
        fdi_frame_t derived; /* the frame with the set's derived signals (fdi_gen.h), when it has any */
        const fdi_frame_t *in = frame;
        const bool episode = (self->mode == FDI_ISO_EXONERATION) && (self->accused != 0U);
        const uint32_t undecided = episode ? self->undecided : 0U;
        uint32_t want = 0U;
        uint32_t run;
        uint32_t ready = 0U;
        uint32_t alarm = 0U;
        uint32_t evaluable = 0U;
        uint32_t idle;
        uint32_t ok;
        uint32_t i;
        float r[FDI_DIAG_MAX_TESTS];
        float reg[FDI_DIAG_MAX_TESTS * FDI_EST_MAX_PARAMS] = {0}; /* the estimable quantities' regressors */
        self->fresh = 0U;
        if (self->set != NULL)
        {
            if ((uint32_t)self->set->n_derived > 0U)
            {
                derived = *frame;
                usable = fdi_gen_derive(self->set, &derived, usable);
                in = &derived;
            }
            usable &= ~fdi_gen_bank_step(self->set, self->filt, &self->par.svf, in, usable, self->bank_live);
            self->bank_live = usable;
        }
        /* outside the calibrated envelope no test is evaluable (fdi_table.h, fdi_diag.h) */
        self->in_envelope = inside_envelope(self->table->envelope, frame, usable);
        ready = runnable(self, in, usable);
        run = self->in_envelope ? in_range(self, in, ready) : 0U;
        /* the tests that do not run (none in steady state): restarted once they run again; the mask of all tests
           written out as fdi_frame_low_mask() computes it: with the inline call instead, gcc -O3 lays out this step
           so that it costs 30 more instructions per fault-free step on the Cortex-M4F (bench_fw.sh: 8,880 -> 8,910) */
        idle = ~run & (((uint32_t)self->n_tests >= 32U) ? 0xFFFFFFFFU : (((uint32_t)1U << self->n_tests) - 1U));
        /* a generated test held out only by its range or the envelope, its signals usable and inside its domain
           throughout, comes back after reentry_steps (its filters ran on); one whose signals were lost or that left
           its domain takes the whole warm-up */
        self->held = (self->held & ~(idle & ~self->rearm)) | (idle & ~self->rearm & ready & self->set_tests);
        self->held &= ~(idle & ~ready);
        for (i = 0U; (idle != 0U) && (i < (uint32_t)self->n_tests); ++i)
        {
            const uint32_t bit = (uint32_t)1U << i;
            if ((idle & bit) != 0U)
            {
                if ((self->rearm & bit) == 0U)
                {
                    clear_sens(self, i);
                }
                self->rearm |= bit;
                self->residual[i] = 0.0f;
                self->ratio[i] = 0.0f;
                idle &= ~bit;
            }
        }
        if (self->sensitivities)
        {
            want = 0xFFFFFFFFU;
        }
        else if (undecided != 0U)
        {
            want = sens_wanted(self, undecided, sens_turn(self));
        }
        else
        {
            /* none needed */
        }
        ok = run_generators(self, in, run, want, r, reg);
        /* each test: its evaluation; its residual's averages over SETTLE_FAST_S and SETTLE_SLOW_S (restarted when it
           becomes evaluable again); its quiet and alarm runs. Outside the envelope no test runs, so the runs start
           again, and an open episode holds, its accusations and result too: there is no evidence for or against
           any fault, so it neither ends for want of alarms nor loses its isolation for want of exonerating tests
           (fdi_diag.h); back inside, the tests evaluate again after their warm-up. */
        for (i = 0U; i < (uint32_t)self->n_tests; ++i)
        {
            const uint32_t bit = (uint32_t)1U << i;
            bool test_alarm = false;
            const bool test_ok = (ok & bit) != 0U; /* r[i] holds the generator's residual */
            const bool test_evaluable =
                ((run & bit) != 0U) &&
                evaluate(self, i, test_ok, test_ok ? r[i] : 0.0f, &reg[(size_t)i * FDI_EST_MAX_PARAMS], &test_alarm);
            const float ri = self->residual[i];
            if (test_evaluable && ((self->evaluable & bit) != 0U))
            {
                self->r_fast[i] += self->fast_gain * (ri - self->r_fast[i]);
                self->r_slow[i] += self->slow_gain * (ri - self->r_slow[i]);
            }
            else
            {
                self->r_fast[i] = ri;
                self->r_slow[i] = ri;
            }
            evaluable |= test_evaluable ? bit : 0U;
            alarm |= test_alarm ? bit : 0U;
            self->quiet_run[i] = (test_evaluable && !test_alarm) ? sat_inc(self->quiet_run[i]) : 0U;
            self->alarm_run[i] = test_alarm ? sat_inc(self->alarm_run[i]) : 0U;
        }
        self->alarm = alarm;
        self->evaluable = evaluable;
        if (self->in_envelope)
        {
            st = isolate(self, alarm);
        }
    }
    return st;
}

fdi_status_t fdi_diag_result(const fdi_diag_t *self, fdi_diag_result_t *out)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((self != NULL) && (out != NULL) && (self->table != NULL))
    {
        uint32_t i;
        uint32_t e;
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
            out->spread[i] = used ? self->spread[i] : 0.0f;
            out->offset[i] = (used && ((self->estimate & bit) != 0U)) ? self->correction[i] : 0.0f;
            for (e = 0U; e < FDI_EST_MAX_PARAMS; ++e)
            {
                out->estimate[i][e] = (used && ((self->estimate & bit) != 0U)) ? fdi_est_value(&self->est[i], e)
                                                                                : 0.0f;
            }
        }
        out->accused_mask = self->accused;
        out->iso = self->iso;
        out->in_envelope = self->in_envelope;
        for (i = 0U; i <= FDI_DIAG_MAX_TESTS; ++i)
        {
            out->sens_offset[i] = self->sensitivities ? self->sens_offset[i] : 0U;
        }
        for (i = 0U; self->sensitivities && (i < (uint32_t)self->sens_offset[FDI_DIAG_MAX_TESTS]); ++i)
        {
            out->sens[i] = self->sens[i];
        }
        st = FDI_OK;
    }
    return st;
}

fdi_status_t fdi_diag_explain(const fdi_diag_t *self, fdi_diag_evidence_t *out)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((self != NULL) && (out != NULL) && (self->table != NULL))
    {
        const bool episode = self->accused != 0U;
        const uint32_t undecided = episode ? self->undecided : 0U;
        uint32_t i;
        out->episode_age = episode ? self->episode_age : 0U;
        out->undecided = undecided;
        out->latched = episode ? self->latched : 0U;
        out->cleared = episode ? self->iso_cleared : 0U; /* the cleared faults this step's match used */
        for (i = 0U; i < FDI_TABLE_MAX_FAULTS; ++i)
        {
            const bool open = ((undecided & ((uint32_t)1U << (i & 31U))) != 0U) && (i < (uint32_t)self->n_faults);
            out->implied[i] = open ? self->implied[i] : 0.0f;
            out->cleared_run[i] = open ? self->cleared_run[i] : 0U;
        }
        for (i = 0U; i < FDI_DIAG_MAX_TESTS; ++i)
        {
            out->clears[i] = (episode && (i < (uint32_t)self->n_tests)) ? (self->clears[i] & undecided) : 0U;
        }
        st = FDI_OK;
    }
    return st;
}
