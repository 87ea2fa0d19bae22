/*
 * fuzz_diag.c - libFuzzer harness of the diagnoser step path (fdi_diag_init / fdi_diag_step / fdi_diag_result /
 * fdi_diag_explain).
 *
 * From the input: a table (the kinematic table, the generated ROMO table, or a random table of the ROMO
 * target's generator descriptors, hand-written and generated, that passes fdi_table_check()), a configuration
 * (sensitivities on or off) (any float bits for the CUSUM, counts, warm-up,
 * mode; init may reject it, then the default configuration, for the kin and ROMO tables from an instance
 * warmed up once by 10 s of clean driving), then up to 1,200 steps. Each step starts
 * from the fault-free reference vehicle at that instant and applies input-chosen edits: a signal set to
 * arbitrary float bits (NaN, Inf, denormals, +-FLT_MAX), a signal scaled or offset, validity bits cleared or
 * set at random, and occasional NULL arguments. Invariants after every call:
 *  - init / step / result never crash; NULL arguments give FDI_BAD_ARG; step returns FDI_OK otherwise;
 *  - alarm within evaluable; a test is evaluable only if it has a generator and all its inputs are valid
 *    and finite in this step; residuals of evaluable tests are finite, ratios >= 0 and not NaN (+Inf for
 *    a huge residual, documented in fdi_eval.c);
 *  - no candidate outside the table's faults; alarms within the accused tests of the episode; detected iff
 *    an episode is active; no episode -> no candidate, not isolated; every candidate explains the accused
 *    tests; class_mask = the classes of the candidates;
 *  - with the kin table and the default configuration, fault-free inputs never raise an alarm once the
 *    last edit is more than warm-up + 4 s in the past.
 */
#include <float.h>
#include <math.h>
#include <stdbool.h>

#include "fdi_diag.h"
#include "fdi_gen.h"
#include "fdi_kin_table.h"
#include "fdi_romo_generators.h"
#include "fdi_romo_kin.h"
#include "fdi_romo_table.h"
#include "fdi_test_vehicle.h"
#include "fuzz_input.h"

#define DT 0.01

typedef struct
{
    fdi_table_t t;
    fdi_test_desc_t tests[FDI_DIAG_MAX_TESTS];
    uint32_t sig[FDI_TABLE_MAX_FAULTS];
    uint32_t cls[FDI_TABLE_MAX_FAULTS];
    const char *names[FDI_TABLE_MAX_FAULTS];
    float size[25U * FDI_DIAG_MAX_TESTS];
} table_buf_t;

static uint32_t low_bits(uint32_t n)
{
    return (n >= 32U) ? 0xFFFFFFFFU : (((uint32_t)1U << n) - 1U);
}

/* Generator k of the ROMO target (NULL, the hand-written kinematic ones, the generated ones), any k. */
static const fdi_gen_desc_t *pick_gen(uint8_t k)
{
    static const fdi_gen_desc_t *const kin[7] = {NULL,
                                                 &fdi_romo_kin_x_deriv,
                                                 &fdi_romo_kin_y_deriv,
                                                 &fdi_romo_kin_arr3,
                                                 &fdi_romo_kin_arr4,
                                                 &fdi_romo_kin_x_obs,
                                                 &fdi_romo_kin_y_obs};
    const uint32_t n = 7U + FDI_ROMO_N_GENERATORS;
    const uint32_t i = (uint32_t)k % n;
    return (i < 7U) ? kin[i] : &fdi_romo_generators[i - 7U];
}

static void random_table(table_buf_t *b, const fdi_table_t *design_from, fuzz_in_t *in)
{
    uint32_t i;
    uint32_t j;
    uint32_t g;
    const uint8_t nf = (uint8_t)(1U + (fz_u8(in) % 25U));
    const uint8_t nt = (uint8_t)(1U + (fz_u8(in) % FDI_DIAG_MAX_TESTS));
    memset(b, 0, sizeof *b);
    b->t = *design_from;
    b->t.n_faults = nf;
    b->t.n_tests = nt;
    for (i = 0U; i < nt; ++i)
    {
        uint32_t m = fz_u32(in) & low_bits(nf);
        const fdi_gen_desc_t *gen = pick_gen(fz_u8(in));
        b->tests[i].mso_id = (uint16_t)(i + 1U);
        b->tests[i].gen = gen;
        b->tests[i].fault_mask = (m != 0U) ? m : 1U;
        if ((gen != NULL) && (((gen->sens_mask | gen->rate_mask) & ~b->tests[i].fault_mask) != 0U))
        {
            /* else fdi_table_check refuses it */
            b->tests[i].fault_mask |= (gen->sens_mask | gen->rate_mask) & low_bits(nf);
        }
        b->tests[i].input_mask = ((gen != NULL) ? gen->input_mask : 0U) | (fz_u32(in) & ROMO_SIGM_ALL);
        b->tests[i].gate = 1.0f + (float)(fz_u8(in) % 10U);
        b->tests[i].variance = design_from->tests[i % design_from->n_tests].variance;
        b->tests[i].response_steps = (uint16_t)(1U + (fz_u32(in) & 0x01FFU));
        b->tests[i].interpretation = "fuzz";
    }
    for (j = 0U; j < nf; ++j)
    {
        b->names[j] = "f";
        b->sig[j] = 0U;
        for (i = 0U; i < nt; ++i)
        {
            b->sig[j] |= ((b->tests[i].fault_mask >> j) & 1U) << i;
        }
    }
    for (j = 0U; j < nf; ++j)
    {
        b->cls[j] = 0U;
        for (g = 0U; g < nf; ++g)
        {
            b->cls[j] |= (b->sig[g] == b->sig[j]) ? ((uint32_t)1U << g) : 0U;
        }
    }
    b->t.fault_names = b->names;
    b->t.tests = b->tests;
    b->t.fault_signature = b->sig;
    b->t.iso_class = b->cls;
    b->t.exoneration_margin = 1.0f + (float)(fz_u8(in) % 4U);
    b->t.sensitivity_margin = 1.0f + (0.25f * (float)(fz_u8(in) % 8U));
    for (j = 0U; j < nf; ++j)
    {
        for (i = 0U; i < nt; ++i)
        {
            b->size[(j * nt) + i] = (((b->sig[j] >> i) & 1U) != 0U) ? (float)(fz_u8(in) % 4U) : 0.0f;
        }
    }
    b->t.test_size = b->size;
}

/* Filter states a table needs in the diagnoser: its set's bank and the hand-written generators' filters. */
static uint32_t filters_needed(const fdi_table_t *t)
{
    uint32_t n = 0U;
    const fdi_gen_set_t *set = NULL;
    uint32_t i;
    for (i = 0U; i < t->n_tests; ++i)
    {
        const fdi_gen_desc_t *g = t->tests[i].gen;
        if ((g != NULL) && (g->set != NULL))
        {
            set = g->set;
        }
        else if (g != NULL)
        {
            n += g->n_filters;
        }
    }
    return n + ((set != NULL) ? set->n_bank : 0U);
}

static fdi_diag_config_t good_config(const fdi_table_t *t)
{
    fdi_diag_config_t c;
    c.table = t;
    c.gen_param[FDI_ROMO_KIN_PARAM_D_X] = (float)VEH_DX;
    c.gen_param[FDI_ROMO_KIN_PARAM_D_Y] = (float)VEH_DY;
    c.gen_param[2] = 0.0f;
    c.gen_param[3] = 0.0f;
    c.sensitivities = false;
    c.adaptive = false;
    c.estimate = 0U;
    c.estimate_kappa = 3.0f;
    c.estimate_decorrelation = 10.0f;
    c.estimate_startup = 100U;
    c.sens_every = 4U; /* the default's turns */
    c.cusum_k = 1.5f;
    c.cusum_h = 150.0f;
    c.set_count = 10U;
    c.clear_count = 100U;
    c.warmup_steps = 400U; /* > the settling time of the kin design point (300 steps) */
    c.reentry_steps = 50U;
    c.mode = FDI_ISO_EXONERATION;
    c.noise_allowance = 3.0f;
    c.episode_clear_steps = 300U;
    return c;
}

static float *field(fdi_frame_t *x, uint32_t k)
{
    float *const f[ROMO_SIG_COUNT] = {&x->value[ROMO_SIG_AX_M],     &x->value[ROMO_SIG_AY_M],     &x->value[ROMO_SIG_PSIDOT_M], &x->value[ROMO_SIG_VX_M],     &x->value[ROMO_SIG_VY_M],
                                     &x->value[ROMO_SIG_DELTA1_M], &x->value[ROMO_SIG_DELTA2_M], &x->value[ROMO_SIG_DELTA3_M], &x->value[ROMO_SIG_DELTA4_M], &x->value[ROMO_SIG_ITM1_M],
                                     &x->value[ROMO_SIG_ITM2_M],   &x->value[ROMO_SIG_ITM3_M],   &x->value[ROMO_SIG_ITM4_M],   &x->value[ROMO_SIG_P_F_M],    &x->value[ROMO_SIG_P_R_M],
                                     &x->value[ROMO_SIG_OMEGA1_M], &x->value[ROMO_SIG_OMEGA2_M], &x->value[ROMO_SIG_OMEGA3_M], &x->value[ROMO_SIG_OMEGA4_M]};
    return f[k % ROMO_SIG_COUNT];
}

#define WARM_STEPS 1000L /* > the default warm-up (400 steps) + CLEAN_MARGIN */
#define CLEAN_MARGIN 400L /* CUSUM clamp 2h/k = 200 steps + clear count 100 + filter settling */

/* A diagnoser of the kin (0) or ROMO (1) table with the default configuration after WARM_STEPS clean steps,
   computed once: inputs then start where every test with a generator is evaluable. */
static const fdi_diag_t *warmed(uint32_t which)
{
    static fdi_diag_t w[2];
    static bool have[2];
    if (!have[which])
    {
        const fdi_table_t *t = (which == 0U) ? &fdi_kin_table : &fdi_romo_table;
        const fdi_diag_config_t c = good_config(t);
        veh_meas_cfg_t mc;
        test_rng_t rng = {7U};
        fdi_frame_t x;
        long k;
        memset(&mc, 0, sizeof mc);
        FUZZ_CHECK(fdi_diag_init(&w[which], &c) == FDI_OK, "init of the warm instance");
        for (k = 1L; k <= WARM_STEPS; ++k)
        {
            veh_measure((double)k * DT, &mc, &rng, &x);
            FUZZ_CHECK(fdi_diag_step(&w[which], &x, ROMO_SIGM_ALL) == FDI_OK, "warm step");
        }
        have[which] = true;
    }
    return &w[which];
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_in_t in = {data, size};
    static table_buf_t tb;
    static fdi_diag_t d;
    fdi_diag_result_t res;
    fdi_diag_config_t c;
    const fdi_table_t *table;
    const uint8_t which = fz_u8(&in) % 3U;
    veh_meas_cfg_t mc;
    test_rng_t rng = {0x2545F4914F6CDD1DULL};
    uint32_t with_gen = 0U;
    long last_edit = 0L;
    long k0 = 0L;
    long k;
    uint32_t i;

    if (which == 0U)
    {
        table = &fdi_kin_table;
    }
    else if (which == 1U)
    {
        table = &fdi_romo_table;
    }
    else
    {
        random_table(&tb, &fdi_kin_table, &in);
        if ((fdi_table_check(&tb.t) != FDI_OK) || (filters_needed(&tb.t) > FDI_DIAG_MAX_FILTERS))
        {
            return 0; /* e.g. a generated generator twice, or more hand-written filters than the diagnoser holds:
                         not a case for the diagnoser */
        }
        table = &tb.t;
        uint32_t n_sens = 0U;
        for (i = 0U; i < tb.t.n_tests; ++i)
        {
            n_sens += fdi_gen_sens_count(tb.t.tests[i].gen);
        }
        if (n_sens > FDI_DIAG_MAX_SENS) /* more sensitivities than the diagnoser holds: refused, documented */
        {
            c = good_config(table);
            FUZZ_CHECK(fdi_diag_init(&d, &c) == FDI_BAD_ARG, "a table over FDI_DIAG_MAX_SENS was accepted");
            return 0;
        }
    }
    FUZZ_CHECK(fdi_diag_init(NULL, NULL) == FDI_BAD_ARG, "init NULL");
    c = good_config(table);
    c.cusum_k = fz_f32(&in);
    c.cusum_h = fz_f32(&in);
    c.set_count = (uint16_t)fz_u8(&in);
    c.clear_count = (uint16_t)fz_u8(&in);
    c.warmup_steps = (uint16_t)(fz_u32(&in) & 0x0FFFU);
    c.reentry_steps = (uint16_t)(fz_u32(&in) & 0x0FFFU);
    c.mode = (fdi_iso_mode_t)(fz_u8(&in) % 3U);
    c.noise_allowance = fz_f32(&in);
    c.episode_clear_steps = (uint16_t)fz_u8(&in);
    const uint8_t flags = fz_u8(&in);
    c.sensitivities = (flags & 1U) != 0U;
    c.adaptive = (flags & 2U) != 0U;
    c.sens_every = (uint16_t)(fz_u8(&in) % 20U); /* beyond FDI_DIAG_MAX_SENS_EVERY too */
    bool good_cfg = false;
    if (fdi_diag_init(&d, &c) != FDI_OK)
    {
        const fdi_status_t s = fdi_diag_init(&d, &c);
        FUZZ_CHECK(s == FDI_BAD_ARG || s == FDI_NOT_FINITE, "init status %d", (int)s);
        c = good_config(table);
        good_cfg = true;
        if (which < 2U) /* start from the warmed-up instance of this table (steps 1..WARM_STEPS, clean) */
        {
            d = *warmed(which);
            k0 = WARM_STEPS;
        }
        else
        {
            FUZZ_CHECK(fdi_diag_init(&d, &c) == FDI_OK, "a good configuration was rejected");
        }
    }
    for (i = 0U; i < table->n_tests; ++i)
    {
        with_gen |= (table->tests[i].gen != NULL) ? ((uint32_t)1U << i) : 0U;
    }
    for (i = 0U; i < 5U; ++i)
    {
        mc.f[i] = 0.0;
        mc.noise[i] = 0.0;
    }
    FUZZ_CHECK(fdi_diag_result(&d, &res) == FDI_OK, "result");
    FUZZ_CHECK((k0 > 0L) || ((res.alarm_mask == 0U) && (res.evaluable_mask == 0U)), "result before the first step");
    FUZZ_CHECK((k0 == 0L) || (table != &fdi_kin_table) || (res.evaluable_mask == 0x0FU), "warm kin not evaluable");
    for (k = k0 + 1L; (k <= k0 + 1200L) && (in.n > 0U); ++k)
    {
        fdi_frame_t x;
        uint32_t validity = ROMO_SIGM_ALL;
        const uint8_t op = fz_u8(&in);
        veh_measure((double)k * DT, &mc, &rng, &x);
        if ((op & 0x03U) == 0x01U) /* arbitrary bits in one signal */
        {
            *field(&x, fz_u8(&in)) = fz_f32(&in);
            last_edit = k;
        }
        else if ((op & 0x03U) == 0x02U) /* extreme scale or offset of one signal */
        {
            float *f = field(&x, fz_u8(&in));
            const uint8_t m = fz_u8(&in);
            *f = ((m & 1U) != 0U) ? (*f * ((m & 2U) ? FLT_MAX : 1e-30f)) : (*f + (float)(int8_t)m * 1e3f);
            last_edit = k;
        }
        else if ((op & 0x03U) == 0x03U) /* validity bits */
        {
            validity = fz_u32(&in);
            last_edit = k;
        }
        if (op == 0xFFU)
        {
            FUZZ_CHECK(fdi_diag_step(NULL, &x, validity) == FDI_BAD_ARG, "step NULL self");
            FUZZ_CHECK(fdi_diag_step(&d, NULL, validity) == FDI_BAD_ARG, "step NULL inputs");
            FUZZ_CHECK(fdi_diag_result(&d, NULL) == FDI_BAD_ARG, "result NULL");
        }
        FUZZ_CHECK(fdi_diag_step(&d, &x, validity) == FDI_OK, "step failed at %ld", k);
        FUZZ_CHECK(fdi_diag_result(&d, &res) == FDI_OK, "result failed");
        {
            const uint32_t usable = validity & fdi_frame_finite_mask(&x, ROMO_SIGM_ALL);
            FUZZ_CHECK(res.n_tests == table->n_tests, "n_tests");
            FUZZ_CHECK((res.alarm_mask & ~res.evaluable_mask) == 0U, "alarm outside evaluable");
            FUZZ_CHECK((res.evaluable_mask & ~with_gen) == 0U, "a test without generator is evaluable");
            for (i = 0U; i < table->n_tests; ++i)
            {
                const bool ev = ((res.evaluable_mask >> i) & 1U) != 0U;
                const uint32_t need = table->tests[i].input_mask;
                FUZZ_CHECK(!ev || ((usable & need) == need), "test %u evaluable with invalid inputs", i);
                FUZZ_CHECK(ev == (res.status[i] != FDI_TEST_NOT_EVALUABLE), "status/evaluable mismatch %u", i);
                FUZZ_CHECK(((res.alarm_mask >> i) & 1U) == (res.status[i] == FDI_TEST_ALARM ? 1U : 0U),
                           "status/alarm mismatch %u", i);
                if (ev)
                {
                    /* the ratio r^2/(gate^2 sigma^2) may overflow to +Inf for a huge finite r (fdi_eval.c:
                       "still an alarm"); it is never NaN or negative */
                    FUZZ_CHECK(isfinite(res.residual[i]) && !isnan(res.ratio[i]) && (res.ratio[i] >= 0.0f),
                               "test %u: residual %g ratio %g", i, (double)res.residual[i], (double)res.ratio[i]);
                }
            }
            FUZZ_CHECK((res.iso.candidates & ~low_bits(table->n_faults)) == 0U, "candidate outside faults");
            {
                uint32_t classes = 0U;
                uint32_t j;
                for (j = 0U; j < table->n_faults; ++j)
                {
                    classes |= ((res.iso.candidates >> j) & 1U) ? table->iso_class[j] : 0U;
                    if ((res.iso.candidates >> j) & 1U)
                    {
                        FUZZ_CHECK((res.accused_mask & ~table->fault_signature[j]) == 0U,
                                   "candidate f%u does not explain the accused tests", j + 1U);
                    }
                }
                FUZZ_CHECK(res.iso.class_mask == classes, "class mask is not the candidates' classes");
            }
            FUZZ_CHECK((res.alarm_mask & ~res.accused_mask) == 0U, "alarm not accused");
            FUZZ_CHECK(res.iso.detected == (res.accused_mask != 0U), "detected != episode active");
            {
                /* the exoneration's evidence agrees with the result: outside an episode it is empty; in one, a
                   candidate is latched or undecided and never cleared */
                fdi_diag_evidence_t ev;
                FUZZ_CHECK(fdi_diag_explain(&d, &ev) == FDI_OK, "explain");
                if (res.accused_mask == 0U)
                {
                    FUZZ_CHECK((ev.episode_age == 0U) && (ev.undecided == 0U) && (ev.cleared == 0U) &&
                                   (ev.latched == 0U),
                               "evidence outside an episode");
                }
                else if (ev.latched != FDI_DIAG_CONTRADICTED)
                {
                    FUZZ_CHECK((res.iso.candidates & ~(ev.undecided | ev.latched)) == 0U,
                               "a candidate neither undecided nor latched");
                    FUZZ_CHECK((res.iso.candidates & ev.cleared) == 0U, "a cleared candidate");
                }
                else
                {
                    FUZZ_CHECK(res.iso.candidates == 0U, "candidates of a contradicted episode");
                }
                for (i = 0U; i < FDI_TABLE_MAX_FAULTS; ++i)
                {
                    FUZZ_CHECK(!isnan(ev.implied[i]) && (ev.implied[i] >= 0.0f), "implied size %u: %g", i,
                               (double)ev.implied[i]);
                }
            }
            if (res.accused_mask == 0U)
            {
                FUZZ_CHECK(res.iso.candidates == 0U && !res.iso.detected && !res.iso.isolated,
                           "isolated or detected with no alarm");
            }
            if (good_cfg && (table == &fdi_kin_table) && (k - last_edit > (long)c.warmup_steps + CLEAN_MARGIN))
            {
                FUZZ_CHECK(res.alarm_mask == 0U, "alarm on clean inputs %ld steps after the last edit",
                           k - last_edit);
            }
        }
    }
    return 0;
}
