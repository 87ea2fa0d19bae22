/*
 * test_fdi_gen_generated.c - the generated residual generators of the ROMO target
 * (fw/vehicles/romo/generated/fdi_romo_generators.c): one generator set (fdi_gen.h) whose slots the table's tests
 * point to; descriptors, slots and input masks, the bank (every filtered signal once, fed by its raw signal or an
 * earlier filter of the same signal; a filter restarts when its signal becomes usable and holds while it is not),
 * bad descriptors and sets rejected by fdi_gen_desc_check, fdi_gen_init and fdi_table_check (a slot used twice,
 * two sets), the exported table accepted, the sensitivities (finite, zero cost when not requested: the residual is
 * the same bit for bit), and the generated MSO3 generator equal to -r3 of the hand-written fdi_romo_kin_arr3 on
 * the analytic reference vehicle (same filters, same relation times w^2), and the operating domain: a tyre-law
 * test is "not evaluable" in fdi_diag below its minimum speed and restarts with a warm-up when the speed returns,
 * while the kinematic tests stay evaluable; the observer building blocks (fdi_gen_obs_predict/store, heaviside,
 * sign, max, min) against the exact solution of x' = J x + b; a table listing the slots in another order gives
 * each test the same residual and sensitivities; derived signals (fdi_gen_derive: usable masks, non-finite values,
 * bad sets).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

#include <cmocka.h>

#include "fdi_diag.h"
#include "fdi_float.h"
#include "fdi_gen.h"
#include "fdi_gen_impl.h" /* observer building blocks of the generated generators */
#include "fdi_romo_generators.h"
#include "fdi_romo_kin.h"
#include "fdi_romo_table.h"
#include "fdi_table.h"
#include "fdi_test_gen.h"
#include "fdi_test_vehicle.h"

#define DT 0.01

static void params(fdi_gen_param_t *p)
{
    const fdi_gen_config_t cfg = {(float)DT, 1.0f, 0.7071f, 2.0f, {(float)VEH_DX, (float)VEH_DY, 0.0f, 0.0f}};
    assert_int_equal(fdi_gen_param_init(p, &cfg), FDI_OK);
}

static void test_slots_and_inputs(void **state)
{
    uint32_t i;
    uint32_t k;
    (void)state;
    assert_int_equal((uint32_t)fdi_romo_table.n_tests, FDI_ROMO_N_GENERATORS);
    assert_int_equal(fdi_gen_set_check(&fdi_romo_gen_set), FDI_OK);
    assert_int_equal((uint32_t)fdi_romo_gen_set.n_slots, FDI_ROMO_N_GENERATORS);
    for (i = 0U; i < (uint32_t)fdi_romo_table.n_tests; ++i)
    {
        const fdi_test_desc_t *d = &fdi_romo_table.tests[i];
        assert_ptr_equal(d->gen, &fdi_romo_generators[i]);
        assert_int_equal(fdi_gen_desc_check(d->gen), FDI_OK);
        assert_ptr_equal(d->gen->set, &fdi_romo_gen_set);
        assert_int_equal((uint32_t)d->gen->slot, i);
        assert_null(d->gen->step);
        assert_int_equal((uint32_t)d->gen->n_filters, 0U);
        assert_true(d->gen->input_mask != 0U);
        assert_int_equal(d->input_mask & d->gen->input_mask, d->gen->input_mask);
        assert_int_equal(d->gen->sens_mask & ~d->fault_mask, 0U); /* sensitivities within the signature */
    }
    /* the bank: every signal the generators filter, once; a chain stays within its signal */
    assert_true(fdi_romo_gen_set.n_bank >= 1U);
    for (k = 0U; k < (uint32_t)fdi_romo_gen_set.n_bank; ++k)
    {
        const fdi_gen_bank_filter_t *f = &fdi_romo_gen_set.bank[k];
        uint32_t j;
        assert_true((f->source == FDI_GEN_BANK_RAW) || (fdi_romo_gen_set.bank[f->source].signal == f->signal));
        for (j = 0U; j < k; ++j)
        {
            const fdi_gen_bank_filter_t *g = &fdi_romo_gen_set.bank[j];
            assert_false((g->signal == f->signal) && (g->source == f->source) && (g->order == f->order));
        }
    }
    /* derived signals: free places of the frame, computed from the vehicle's signals, filtered by the bank */
    assert_int_equal(fdi_gen_derived_signals(&fdi_romo_gen_set) & ROMO_SIGM_ALL, 0U);
    for (k = 0U; k < (uint32_t)fdi_romo_gen_set.n_derived; ++k)
    {
        assert_int_equal(fdi_romo_gen_set.derived[k].sources & ~ROMO_SIGM_ALL, 0U);
    }
    assert_int_equal(fdi_gen_bank_signals(&fdi_romo_gen_set) &
                         ~(ROMO_SIGM_ALL | fdi_gen_derived_signals(&fdi_romo_gen_set)), 0U);
    assert_int_equal(fdi_gen_derived_signals(NULL), 0U);
    assert_int_equal(fdi_gen_bank_signals(NULL), 0U);
    assert_int_equal(fdi_table_check(&fdi_romo_table), FDI_OK);
}

/* A finite frame of the reference vehicle with the wheel signals of a steady drive at 10 m/s. */
static void wheel_frame(double t, fdi_frame_t *in)
{
    veh_meas_cfg_t mc = {{0.0, 0.0, 0.0, 0.0, 0.0}, {0.0, 0.0, 0.0, 0.0, 0.0}};
    test_rng_t rng = {1ULL};
    veh_measure(t, &mc, &rng, in);
    in->value[ROMO_SIG_ITM1_M] = 10.0f;
    in->value[ROMO_SIG_ITM2_M] = 10.0f;
    in->value[ROMO_SIG_ITM3_M] = 10.0f;
    in->value[ROMO_SIG_ITM4_M] = 10.0f;
    in->value[ROMO_SIG_OMEGA1_M] = 37.0f;
    in->value[ROMO_SIG_OMEGA2_M] = 37.0f;
    in->value[ROMO_SIG_OMEGA3_M] = 37.0f;
    in->value[ROMO_SIG_OMEGA4_M] = 37.0f;
    in->value[ROMO_SIG_P_F_M] = 0.0f;
    in->value[ROMO_SIG_P_R_M] = 0.0f;
    in->value[ROMO_SIG_DELTA1_M] = 0.0f;
    in->value[ROMO_SIG_DELTA2_M] = 0.0f;
    in->value[ROMO_SIG_DELTA3_M] = 0.0f;
    in->value[ROMO_SIG_DELTA4_M] = 0.0f;
}

/* A derive function for the tests below: place 30 = s0 * s1, place 31 = s0 * s2 (overflows for a huge s2). */
static void derive_two(fdi_frame_t *frame)
{
    frame->value[30] = frame->value[0] * frame->value[1];
    frame->value[31] = frame->value[0] * frame->value[2];
}

static void test_derived_signals(void **state)
{
    static const fdi_gen_derived_t two[2] = {{30U, 0x3U}, {31U, 0x5U}};
    fdi_gen_derived_t bad[2] = {{30U, 0x3U}, {31U, 0x5U}};
    fdi_gen_set_t set = fdi_romo_gen_set;
    fdi_frame_t frame;
    const uint32_t d30 = (uint32_t)1U << 30U;
    const uint32_t d31 = (uint32_t)1U << 31U;
    uint32_t k;
    (void)state;
    set.derive = derive_two;
    set.derived = two;
    set.n_derived = 2U;
    assert_int_equal(fdi_gen_set_check(&set), FDI_OK);
    assert_int_equal(fdi_gen_derived_signals(&set), d30 | d31);
    for (k = 0U; k < FDI_FRAME_MAX_SIGNALS; ++k)
    {
        frame.value[k] = 2.0f;
    }
    /* every source usable: both written and usable; the caller's bits for the derived places do not count */
    assert_int_equal(fdi_gen_derive(&set, &frame, 0x7U), 0x7U | d30 | d31);
    assert_float_equal(frame.value[30], 4.0f, 0.0f);
    assert_float_equal(frame.value[31], 4.0f, 0.0f);
    assert_int_equal(fdi_gen_derive(&set, &frame, 0x7U | d30 | d31), 0x7U | d30 | d31);
    assert_int_equal(fdi_gen_derive(&set, &frame, 0x3U), 0x3U | d30); /* s2 unusable: place 31 is not */
    assert_int_equal(fdi_gen_derive(&set, &frame, d30 | d31), 0U);
    /* a derived value that is not finite although its sources are usable takes its sources with it */
    frame.value[2] = FLT_MAX;
    assert_int_equal(fdi_gen_derive(&set, &frame, 0x7U), 0x2U | d30);
    /* no derived signal, NULL arguments: usable unchanged */
    {
        fdi_gen_set_t plain = fdi_romo_gen_set;
        plain.derive = NULL;
        plain.derived = NULL;
        plain.n_derived = 0U;
        assert_int_equal(fdi_gen_derive(&plain, &frame, 0x7U), 0x7U);
    }
    assert_int_equal(fdi_gen_derive(NULL, &frame, 0x7U), 0x7U);
    assert_int_equal(fdi_gen_derive(&set, NULL, 0x7U), 0x7U);
    /* bad sets */
    set.derived = bad;
    bad[1].signal = 30U; /* the same place twice */
    assert_int_equal(fdi_gen_set_check(&set), FDI_BAD_ARG);
    bad[1].signal = 31U;
    bad[1].sources = d30; /* computed from another derived signal */
    assert_int_equal(fdi_gen_set_check(&set), FDI_BAD_ARG);
    bad[1].sources = 0U; /* from nothing */
    assert_int_equal(fdi_gen_set_check(&set), FDI_BAD_ARG);
    bad[1].sources = 0x5U;
    assert_int_equal(fdi_gen_set_check(&set), FDI_OK);
    set.derived = NULL;
    assert_int_equal(fdi_gen_set_check(&set), FDI_BAD_ARG);
    set.derived = two;
    set.n_derived = 0U; /* a derive function without derived signals */
    assert_int_equal(fdi_gen_set_check(&set), FDI_BAD_ARG);
    set.derive = NULL;
    set.derived = NULL;
    assert_int_equal(fdi_gen_set_check(&set), FDI_OK);
    set.n_derived = 1U; /* derived signals without a derive function */
    assert_int_equal(fdi_gen_set_check(&set), FDI_BAD_ARG);
}

static void test_bad_descriptors_and_sets(void **state)
{
    fdi_test_desc_t tests_copy[FDI_TABLE_MAX_TESTS];
    fdi_gen_desc_t bad = fdi_romo_generators[0];
    fdi_gen_set_t bad_set = fdi_romo_gen_set;
    fdi_gen_bank_filter_t bank[2] = {{0U, FDI_GEN_BANK_RAW, 0U}, {0U, 0U, 1U}};
    fdi_table_t t = fdi_romo_table;
    (void)state;
    memcpy(tests_copy, fdi_romo_table.tests, sizeof(fdi_test_desc_t) * fdi_romo_table.n_tests);
    t.tests = tests_copy;
    tests_copy[0].gen = &bad;
    bad.set = NULL; /* neither a step nor a set */
    assert_int_equal(fdi_gen_desc_check(&bad), FDI_BAD_ARG);
    assert_int_equal(fdi_table_check(&t), FDI_BAD_TABLE);
    bad = fdi_romo_generators[0];
    bad.slot = fdi_romo_gen_set.n_slots; /* no such slot */
    assert_int_equal(fdi_gen_desc_check(&bad), FDI_BAD_ARG);
    bad = fdi_romo_generators[0];
    bad.n_filters = 1U; /* a slot has no instance filters */
    assert_int_equal(fdi_gen_desc_check(&bad), FDI_BAD_ARG);
    bad = fdi_romo_generators[0];
    bad.sens_mask = ~fdi_romo_table.tests[0].fault_mask; /* sensitivities outside the signature */
    assert_int_equal(fdi_table_check(&t), FDI_BAD_TABLE);
    bad = fdi_romo_generators[0];
    assert_int_not_equal(bad.rate_mask, 0U); /* MSO1: the vx offset's rate gain */
    bad.rate_mask |= 0x1U;                   /* a rate gain of f1, which has a sensitivity */
    assert_int_equal(fdi_gen_desc_check(&bad), FDI_BAD_ARG);
    bad = fdi_romo_generators[0];
    bad.rate_gain = NULL; /* rate gains without their values */
    assert_int_equal(fdi_gen_desc_check(&bad), FDI_BAD_ARG);
    {
        const float zero_gain[1] = {0.0f};
        const float nan_gain[1] = {NAN};
        bad = fdi_romo_generators[0];
        bad.rate_gain = zero_gain;
        assert_int_equal(fdi_gen_desc_check(&bad), FDI_BAD_ARG);
        bad.rate_gain = nan_gain;
        assert_int_equal(fdi_gen_desc_check(&bad), FDI_BAD_ARG);
    }
    bad = fdi_romo_generators[0];
    bad.rate_mask = 0x40U; /* a rate gain of f7, outside MSO1's signature */
    assert_int_equal(fdi_gen_desc_check(&bad), FDI_OK);
    assert_int_equal(fdi_table_check(&t), FDI_BAD_TABLE);
    bad = fdi_romo_generators[0];
    bad.input_mask |= ROMO_SIGM_ALL & ~fdi_romo_table.tests[0].input_mask; /* reads more than the test's signals */
    assert_int_equal(fdi_table_check(&t), FDI_BAD_TABLE);
    bad = fdi_romo_generators[0];
    assert_int_equal(fdi_table_check(&t), FDI_OK);
    bad = fdi_romo_generators[1]; /* slot 1 twice */
    assert_int_equal(fdi_table_check(&t), FDI_BAD_TABLE);
    bad = fdi_romo_generators[0];
    bad.set = &bad_set; /* a second set */
    assert_int_equal(fdi_table_check(&t), FDI_BAD_TABLE);
    /* sets */
    assert_int_equal(fdi_gen_set_check(NULL), FDI_BAD_ARG);
    bad_set.step = NULL;
    assert_int_equal(fdi_gen_set_check(&bad_set), FDI_BAD_ARG);
    bad_set = fdi_romo_gen_set;
    bad_set.n_slots = 0U;
    assert_int_equal(fdi_gen_set_check(&bad_set), FDI_BAD_ARG);
    bad_set = fdi_romo_gen_set;
    bad_set.n_slots = 33U;
    assert_int_equal(fdi_gen_set_check(&bad_set), FDI_BAD_ARG);
    bad_set = fdi_romo_gen_set;
    bad_set.bank = NULL;
    assert_int_equal(fdi_gen_set_check(&bad_set), FDI_BAD_ARG);
    bad_set.n_bank = 0U; /* no filters at all: allowed */
    assert_int_equal(fdi_gen_set_check(&bad_set), FDI_OK);
    bad_set.bank = bank;
    bad_set.n_bank = 2U;
    assert_int_equal(fdi_gen_set_check(&bad_set), FDI_OK);
    bank[1].signal = 1U; /* fed from a filter of another signal */
    assert_int_equal(fdi_gen_set_check(&bad_set), FDI_BAD_ARG);
    bank[1].signal = 0U;
    bank[1].source = 1U; /* fed from itself */
    assert_int_equal(fdi_gen_set_check(&bad_set), FDI_BAD_ARG);
    bank[1].source = 0U;
    bank[1].order = 2U;
    assert_int_equal(fdi_gen_set_check(&bad_set), FDI_BAD_ARG);
    bank[1].order = 1U;
    bank[0].order = 1U; /* a raw filter has no order */
    assert_int_equal(fdi_gen_set_check(&bad_set), FDI_BAD_ARG);
    bank[0].order = 0U;
    bank[0].signal = 32U;
    assert_int_equal(fdi_gen_set_check(&bad_set), FDI_BAD_ARG);
}

/* The bank: restart in steady state at the input, a chain's second filter fed with the first's derivative, hold
   while the signal is not usable, restart when usable again, hold and report a filter that would overflow. */
static void test_bank(void **state)
{
    fdi_gen_param_t p;
    fdi_frame_t in;
    fdi_svf_t b[2];
    const fdi_gen_bank_filter_t bank[2] = {{3U, FDI_GEN_BANK_RAW, 0U}, {3U, 0U, 1U}};
    fdi_gen_set_t set = fdi_romo_gen_set;
    const uint32_t sig = (uint32_t)1U << 3U;
    uint32_t k;
    (void)state;
    params(&p);
    set.bank = bank;
    set.n_bank = 2U;
    memset(&in, 0, sizeof in);
    memset(b, 0, sizeof b);
    in.value[3] = 2.0f;
    assert_int_equal(fdi_gen_bank_step(&set, b, &p.svf, &in, sig, 0U), 0U); /* first step: restart */
    assert_near(b[0].x1, 2.0, 0.0);
    assert_near(b[0].x2, 0.0, 0.0);
    assert_near(b[1].x1, 0.0, 0.0);
    assert_near(b[1].x2, 0.0, 0.0);
    for (k = 0U; k < 500U; ++k) /* a ramp of slope 1: y follows, dy -> 1, and the second filter's y -> 1 */
    {
        in.value[3] = 2.0f + (0.01f * (float)(k + 1U));
        assert_int_equal(fdi_gen_bank_step(&set, b, &p.svf, &in, sig, sig), 0U);
    }
    assert_near(b[0].x2, 1.0, 1e-3);
    assert_near(b[1].x1, 1.0, 1e-3);
    in.value[3] = 100.0f; /* not usable: holds */
    assert_int_equal(fdi_gen_bank_step(&set, b, &p.svf, &in, 0U, sig), 0U);
    assert_near(b[1].x1, 1.0, 1e-3);
    assert_int_equal(fdi_gen_bank_step(&set, b, &p.svf, &in, sig, 0U), 0U); /* usable again: restart */
    assert_near(b[0].x1, 100.0, 0.0);
    assert_near(b[0].x2, 0.0, 0.0);
    assert_near(b[1].x1, 0.0, 0.0);
    in.value[3] = FLT_MAX; /* the second such sample makes the state overflow: held, reported */
    assert_int_equal(fdi_gen_bank_step(&set, b, &p.svf, &in, sig, sig), 0U);
    {
        const float held = b[0].x1;
        assert_int_equal(fdi_gen_bank_step(&set, b, &p.svf, &in, sig, sig), sig);
        assert_near(b[0].x1, held, 0.0);
    }
    assert_int_equal(fdi_gen_bank_step(NULL, b, &p.svf, &in, sig, sig), 0U);
    assert_int_equal(fdi_gen_bank_step(&set, NULL, &p.svf, &in, sig, sig), 0U);
}

/* Every slot on finite frames: finite residuals and sensitivities; non-finite ones reported as failed. */
static void test_slots_run(void **state)
{
    static test_set_t ts;
    fdi_gen_param_t p;
    fdi_frame_t in;
    float r[FDI_GEN_MAX_SLOTS];
    float sens[FDI_DIAG_MAX_SENS];
    const uint32_t all = ((uint32_t)1U << FDI_ROMO_N_GENERATORS) - 1U;
    uint32_t failed;
    uint32_t i;
    int n;
    (void)state;
    params(&p);
    test_set_init(&ts, &fdi_romo_gen_set, fdi_romo_generators);
    for (n = 0; n < 50; ++n)
    {
        wheel_frame(1.0 + (0.01 * (double)n), &in);
        assert_int_equal(test_set_step(&ts, &p, &in, all, n == 0, r, sens), 0U);
        for (i = 0U; i < FDI_ROMO_N_GENERATORS; ++i)
        {
            assert_true(fdi_float_is_finite(r[i]));
            assert_true(fdi_gen_sens_count(&fdi_romo_generators[i]) <= 32U);
        }
    }
    for (i = 0U; i < (uint32_t)ts.sens_at[FDI_ROMO_N_GENERATORS - 1U] +
                     fdi_gen_sens_count(&fdi_romo_generators[FDI_ROMO_N_GENERATORS - 1U]); ++i)
    {
        assert_true(fdi_float_is_finite(sens[i]));
    }
    /* a huge frame value in a raw (unfiltered) node or the observer of the set makes slots fail, not crash */
    wheel_frame(2.0, &in);
    in.value[ROMO_SIG_OMEGA1_M] = 3.0e38f;
    in.value[ROMO_SIG_AX_M] = -3.0e38f;
    failed = test_set_step(&ts, &p, &in, all, false, r, NULL);
    assert_true(failed != 0U);
    for (i = 0U; i < FDI_ROMO_N_GENERATORS; ++i)
    {
        if (!fdi_float_is_finite(r[i])) /* every slot whose residual is not finite says so, observers included */
        {
            assert_true((failed & ((uint32_t)1U << i)) != 0U);
        }
    }
}

static void frame(fdi_frame_t *in, float vx)
{
    veh_meas_cfg_t mc = {{0.0, 0.0, 0.0, 0.0, 0.0}, {0.0, 0.0, 0.0, 0.0, 0.0}};
    test_rng_t rng = {3ULL};
    veh_measure(1.0, &mc, &rng, in);
    in->value[ROMO_SIG_ITM1_M] = 0.0f;
    in->value[ROMO_SIG_ITM2_M] = 0.0f;
    in->value[ROMO_SIG_ITM3_M] = 0.0f;
    in->value[ROMO_SIG_ITM4_M] = 0.0f;
    in->value[ROMO_SIG_P_F_M] = 0.0f;
    in->value[ROMO_SIG_P_R_M] = 0.0f;
    in->value[ROMO_SIG_DELTA1_M] = 0.0f;
    in->value[ROMO_SIG_DELTA2_M] = 0.0f;
    in->value[ROMO_SIG_DELTA3_M] = 0.0f;
    in->value[ROMO_SIG_DELTA4_M] = 0.0f;
    in->value[ROMO_SIG_PSIDOT_M] = 0.0f;
    in->value[ROMO_SIG_AX_M] = 0.0f;
    in->value[ROMO_SIG_AY_M] = 0.0f;
    in->value[ROMO_SIG_VY_M] = 0.0f;
    in->value[ROMO_SIG_VX_M] = vx;
    in->value[ROMO_SIG_OMEGA1_M] = vx / 0.27f;
    in->value[ROMO_SIG_OMEGA2_M] = vx / 0.27f;
    in->value[ROMO_SIG_OMEGA3_M] = vx / 0.27f;
    in->value[ROMO_SIG_OMEGA4_M] = vx / 0.27f;
}

/* Bitmask of the table's tests whose generator is outside its operating domain at frame `in`. */
static uint32_t out_of_domain(const fdi_frame_t *in)
{
    uint32_t m = 0U;
    uint32_t i;
    for (i = 0U; i < (uint32_t)fdi_romo_table.n_tests; ++i)
    {
        m |= fdi_gen_in_domain(fdi_romo_table.tests[i].gen, in) ? 0U : ((uint32_t)1U << i);
    }
    return m;
}

/* `steps` steps with the tests of `held` not evaluable, then one with every test of `all` evaluable */
static void back_after(fdi_diag_t *d, const fdi_frame_t *in, int steps, uint32_t held, uint32_t all)
{
    fdi_diag_result_t res;
    int n;
    for (n = 0; n < steps; ++n)
    {
        assert_int_equal(fdi_diag_step(d, in, ROMO_SIGM_ALL), FDI_OK);
        assert_int_equal(fdi_diag_result(d, &res), FDI_OK);
        assert_int_equal(res.evaluable_mask & held, 0U);
    }
    assert_int_equal(fdi_diag_step(d, in, ROMO_SIGM_ALL), FDI_OK);
    assert_int_equal(fdi_diag_result(d, &res), FDI_OK);
    assert_int_equal(res.evaluable_mask, all);
}

static void test_operating_domain(void **state)
{
    fdi_frame_t in;
    fdi_diag_t d;
    fdi_diag_result_t res;
    const fdi_diag_config_t cfg = {.table = &fdi_romo_table,
                                   .gen_param = {(float)VEH_DX, (float)VEH_DY, 0.0f, 0.0f},
                                   .cusum_k = 1.5f, .cusum_h = 150.0f, .set_count = 1U, .clear_count = 1U,
                                   .warmup_steps = 300U, .reentry_steps = 50U, .mode = FDI_ISO_EXONERATION,
                                   .episode_clear_steps = 1U, .noise_allowance = 3.0f, .sensitivities = false};
    const uint32_t all = ((uint32_t)1U << fdi_romo_table.n_tests) - 1U;
    uint32_t low;
    uint32_t readers;
    int n;
    (void)state;
    frame(&in, 0.5f);
    low = out_of_domain(&in);
    assert_true(low != 0U);   /* the tyre-law tests need speed */
    assert_true(low != all);  /* the kinematic ones do not */
    assert_false(fdi_gen_in_domain(fdi_romo_table.tests[0].gen, NULL));
    assert_true(fdi_gen_in_domain(&fdi_romo_kin_arr3, &in)); /* the hand-written generators: always */
    in.value[ROMO_SIG_VX_M] = -0.5f;
    assert_int_equal(out_of_domain(&in), low);
    in.value[ROMO_SIG_VX_M] = NAN;
    assert_int_equal(out_of_domain(&in), low); /* a non-finite domain signal is outside */
    frame(&in, 20.0f);
    assert_int_equal(out_of_domain(&in), 0U);
    in.value[ROMO_SIG_VX_M] = -20.0f; /* reversing: |vx| counts */
    assert_int_equal(out_of_domain(&in), 0U);

    assert_int_equal(fdi_diag_init(&d, &cfg), FDI_OK);
    frame(&in, 20.0f);
    for (n = 0; n < 301; ++n)
    {
        assert_int_equal(fdi_diag_step(&d, &in, ROMO_SIGM_ALL), FDI_OK);
    }
    assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
    assert_int_equal(res.evaluable_mask, all);
    frame(&in, 0.5f);
    assert_int_equal(fdi_diag_step(&d, &in, ROMO_SIGM_ALL), FDI_OK);
    assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
    assert_int_equal(res.evaluable_mask, all & ~low);
    for (n = 0; n < (int)fdi_romo_table.n_tests; ++n)
    {
        const bool out = (low & ((uint32_t)1U << (uint32_t)n)) != 0U;
        if (out)
        {
            assert_int_equal((int)res.status[n], (int)FDI_TEST_NOT_EVALUABLE);
            assert_true(fabsf(res.residual[n]) <= 0.0f);
        }
    }
    assert_int_equal(res.alarm_mask & low, 0U); /* out of domain neither accuses nor exonerates */
    frame(&in, 20.0f); /* back in the domain: restart and warm up again */
    back_after(&d, &in, 300, low, all);
    /* out of the tyre laws' range (the vehicle at 0.6 g: fdi_gen_desc_t.in_range) and back, its signals usable and in
       its domain all along: its filters ran on, so the re-entry's 50 steps and not the whole warm-up */
    in.value[ROMO_SIG_AY_M] = 6.0f;
    assert_int_equal(fdi_diag_step(&d, &in, ROMO_SIGM_ALL), FDI_OK);
    assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
    assert_int_equal(res.evaluable_mask & low, 0U);
    in.value[ROMO_SIG_AY_M] = 0.0f;
    back_after(&d, &in, 50, low, all);
    /* a signal missing: the tests that read it stop, the others of the same domain function run on */
    readers = 0U;
    for (n = 0; n < (int)fdi_romo_table.n_tests; ++n)
    {
        const bool reads = (fdi_romo_table.tests[n].input_mask & ROMO_SIGM_OMEGA1_M) != 0U;
        readers |= reads ? ((uint32_t)1U << (uint32_t)n) : 0U;
    }
    assert_true((readers != 0U) && ((low & ~readers) != 0U)); /* tyre-law tests on both sides */
    assert_int_equal(fdi_diag_step(&d, &in, ROMO_SIGM_ALL & ~ROMO_SIGM_OMEGA1_M), FDI_OK);
    assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
    assert_int_equal(res.evaluable_mask, all & ~readers);
    frame(&in, 0.5f); /* and below the domain's speed as well: the kinematic tests that do not read it */
    assert_int_equal(fdi_diag_step(&d, &in, ROMO_SIGM_ALL & ~ROMO_SIGM_OMEGA1_M), FDI_OK);
    assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
    assert_int_equal(res.evaluable_mask, all & ~low & ~readers);
    /* back in the domain with every signal: the tests that lost omega1 and those that left their domain take the
       whole warm-up */
    frame(&in, 20.0f);
    for (n = 0; n < 300; ++n)
    {
        assert_int_equal(fdi_diag_step(&d, &in, ROMO_SIGM_ALL), FDI_OK);
        assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
        assert_int_equal(res.evaluable_mask & (readers | low), 0U);
    }
    assert_int_equal(fdi_diag_step(&d, &in, ROMO_SIGM_ALL), FDI_OK);
    assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
    assert_int_equal(res.evaluable_mask, all);
}

/* With sensitivities requested every generated generator computes the same residual, bit for bit, as without,
   and its sensitivities are finite: the sensitivity code runs after the residual and only when asked. */
static void test_sensitivities_leave_the_residual_alone(void **state)
{
    static test_set_t a;
    static test_set_t b;
    fdi_gen_param_t p;
    fdi_frame_t in;
    float ra[FDI_GEN_MAX_SLOTS];
    float rb[FDI_GEN_MAX_SLOTS];
    float sens[FDI_DIAG_MAX_SENS];
    const uint32_t all = ((uint32_t)1U << FDI_ROMO_N_GENERATORS) - 1U;
    int n;
    (void)state;
    params(&p);
    test_set_init(&a, &fdi_romo_gen_set, fdi_romo_generators);
    test_set_init(&b, &fdi_romo_gen_set, fdi_romo_generators);
    for (n = 0; n < 400; ++n)
    {
        uint32_t i;
        frame(&in, 12.0f + (0.5f * sinf(0.01f * (float)n)));
        in.value[ROMO_SIG_PSIDOT_M] = 0.3f;
        in.value[ROMO_SIG_DELTA1_M] = 0.02f;
        in.value[ROMO_SIG_ITM1_M] = 15.0f;
        assert_int_equal(test_set_step(&a, &p, &in, all, n == 0, ra, NULL), 0U);
        assert_int_equal(test_set_step(&b, &p, &in, all, n == 0, rb, sens), 0U);
        assert_true(memcmp(ra, rb, sizeof(float) * FDI_ROMO_N_GENERATORS) == 0);
        for (i = 0U; i < FDI_ROMO_N_GENERATORS; ++i)
        {
            uint32_t j;
            for (j = 0U; j < fdi_gen_sens_count(&fdi_romo_generators[i]); ++j)
            {
                assert_true(fdi_float_is_finite(sens[b.sens_at[i] + j]));
            }
        }
    }
}

/*
 * The diagnoser on the ROMO table with sensitivities reported (cfg.sensitivities): its residuals are those of the
 * set run on its own, bit for bit (the bank restarted at the first step as the standalone run's), and so are every
 * evaluated test's sensitivities at every step, listed in the result by sens_offset.
 */
static void test_diag_sensitivities(void **state)
{
    static test_set_t ts;
    static fdi_diag_t d;
    static fdi_diag_result_t res;
    fdi_diag_config_t cfg;
    fdi_gen_param_t p;
    fdi_frame_t in;
    float r[FDI_GEN_MAX_SLOTS];
    float sens[FDI_DIAG_MAX_SENS];
    const uint32_t all = ((uint32_t)1U << FDI_ROMO_N_GENERATORS) - 1U;
    int n;
    (void)state;
    assert_int_equal(fdi_diag_config_default(&cfg, &fdi_romo_table), FDI_OK);
    cfg.gen_param[FDI_ROMO_KIN_PARAM_D_X] = (float)VEH_DX;
    cfg.gen_param[FDI_ROMO_KIN_PARAM_D_Y] = (float)VEH_DY;
    cfg.warmup_steps = 300U;
    cfg.reentry_steps = 50U;
    cfg.sensitivities = true;
    cfg.estimate = 0U; /* the generators' own residuals, not innovations */
    assert_int_equal(fdi_diag_init(&d, &cfg), FDI_OK);
    params(&p);
    test_set_init(&ts, &fdi_romo_gen_set, fdi_romo_generators);
    for (n = 0; n < 400; ++n)
    {
        uint32_t i;
        frame(&in, 12.0f + (0.5f * sinf(0.01f * (float)n)));
        in.value[ROMO_SIG_PSIDOT_M] = 0.3f + (0.05f * cosf(0.02f * (float)n));
        in.value[ROMO_SIG_DELTA1_M] = 0.02f;
        in.value[ROMO_SIG_ITM1_M] = 15.0f;
        assert_int_equal(test_set_step(&ts, &p, &in, all, n == 0, r, sens), 0U);
        assert_int_equal(fdi_diag_step(&d, &in, ROMO_SIGM_ALL), FDI_OK);
        assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
        assert_true(memcmp(r, res.residual, sizeof(float) * FDI_ROMO_N_GENERATORS) == 0);
        for (i = 0U; i < FDI_ROMO_N_GENERATORS; ++i)
        {
            uint32_t j;
            assert_int_equal((uint32_t)res.sens_offset[i + 1U] - (uint32_t)res.sens_offset[i],
                             fdi_gen_sens_count(&fdi_romo_generators[i]));
            for (j = 0U; j < fdi_gen_sens_count(&fdi_romo_generators[i]); ++j)
            {
                assert_true(memcmp(&res.sens[res.sens_offset[i] + j], &sens[ts.sens_at[i] + j], sizeof(float)) == 0);
            }
        }
    }
}

/* A table whose tests list the set's slots in another order (reversed): the diagnoser maps tests to slots (restart,
   sensitivities, failures) and gives each test the residual, sensitivities and isolation of the table in order. */
static void test_diag_slots_out_of_order(void **state)
{
    enum { NT = FDI_ROMO_N_GENERATORS };
    static fdi_test_desc_t tests[NT];
    static uint32_t signature[FDI_TABLE_MAX_FAULTS];
    static float size[FDI_TABLE_MAX_FAULTS * NT];
    static fdi_table_t rev;
    static fdi_diag_t d0;
    static fdi_diag_t d1;
    static fdi_diag_result_t r0;
    static fdi_diag_result_t r1;
    fdi_diag_config_t cfg;
    fdi_frame_t in;
    uint32_t i;
    uint32_t j;
    int n;
    (void)state;
    rev = fdi_romo_table;
    for (i = 0U; i < (uint32_t)NT; ++i)
    {
        tests[i] = fdi_romo_table.tests[(uint32_t)NT - 1U - i];
    }
    for (j = 0U; j < (uint32_t)fdi_romo_table.n_faults; ++j)
    {
        signature[j] = 0U;
        for (i = 0U; i < (uint32_t)NT; ++i)
        {
            if ((fdi_romo_table.fault_signature[j] & ((uint32_t)1U << ((uint32_t)NT - 1U - i))) != 0U)
            {
                signature[j] |= (uint32_t)1U << i;
            }
            size[(j * (uint32_t)NT) + i] = fdi_romo_table.test_size[(j * (uint32_t)NT) + (uint32_t)NT - 1U - i];
        }
    }
    rev.tests = tests;
    rev.fault_signature = signature;
    rev.test_size = size;
    assert_int_equal(fdi_table_check(&rev), FDI_OK);
    for (n = 0; n < 2; ++n)
    {
        assert_int_equal(fdi_diag_config_default(&cfg, (n == 0) ? &fdi_romo_table : &rev), FDI_OK);
        cfg.gen_param[FDI_ROMO_KIN_PARAM_D_X] = (float)VEH_DX;
        cfg.gen_param[FDI_ROMO_KIN_PARAM_D_Y] = (float)VEH_DY;
        cfg.warmup_steps = 300U;
        cfg.reentry_steps = 50U;
        cfg.estimate = 0U; /* the order of the slots, not what an estimator makes of them */
        cfg.sensitivities = true;
        assert_int_equal(fdi_diag_init((n == 0) ? &d0 : &d1, &cfg), FDI_OK);
    }
    for (n = 0; n < 500; ++n)
    {
        frame(&in, 12.0f + (0.5f * sinf(0.01f * (float)n)));
        in.value[ROMO_SIG_PSIDOT_M] = 0.3f + (0.05f * cosf(0.02f * (float)n));
        in.value[ROMO_SIG_DELTA1_M] = 0.02f;
        in.value[ROMO_SIG_ITM1_M] = 15.0f;
        /* a restart of some slots: vy_m invalid for a while */
        assert_int_equal(fdi_diag_step(&d0, &in, ((n >= 100) && (n < 110)) ? (ROMO_SIGM_ALL & ~ROMO_SIGM_VY_M)
                                                                             : ROMO_SIGM_ALL), FDI_OK);
        assert_int_equal(fdi_diag_step(&d1, &in, ((n >= 100) && (n < 110)) ? (ROMO_SIGM_ALL & ~ROMO_SIGM_VY_M)
                                                                             : ROMO_SIGM_ALL), FDI_OK);
        assert_int_equal(fdi_diag_result(&d0, &r0), FDI_OK);
        assert_int_equal(fdi_diag_result(&d1, &r1), FDI_OK);
        assert_int_equal(r0.iso.candidates, r1.iso.candidates);
        for (i = 0U; i < (uint32_t)NT; ++i)
        {
            const uint32_t k = (uint32_t)NT - 1U - i; /* test i of rev is test k of the table */
            assert_int_equal((r1.evaluable_mask >> i) & 1U, (r0.evaluable_mask >> k) & 1U);
            assert_int_equal((r1.alarm_mask >> i) & 1U, (r0.alarm_mask >> k) & 1U);
            assert_true(memcmp(&r1.residual[i], &r0.residual[k], sizeof(float)) == 0);
            assert_int_equal((uint32_t)r1.sens_offset[i + 1U] - (uint32_t)r1.sens_offset[i],
                             (uint32_t)r0.sens_offset[k + 1U] - (uint32_t)r0.sens_offset[k]);
            assert_true(memcmp(&r1.sens[r1.sens_offset[i]], &r0.sens[r0.sens_offset[k]],
                               sizeof(float) * ((uint32_t)r0.sens_offset[k + 1U] - (uint32_t)r0.sens_offset[k])) == 0);
        }
    }
    assert_int_equal(r1.evaluable_mask, ((uint32_t)1U << NT) - 1U);
}

static void test_observer_building_blocks(void **state)
{
    /* x' = J x + b with constant b: one predict step is the exact exp(J dt) solution, for a slow, a stiff
     * (J dt = -4, where forward Euler diverges) and a zero pole (then phi = dt) */
    const float poles[3] = {-12.566f, -400.0f, 0.0f};
    const float b = 3.0f;
    fdi_gen_param_t p;
    fdi_obs_t o;
    uint32_t i;
    (void)state;
    params(&p);
    for (i = 0U; i < 3U; ++i)
    {
        const double jac = (double)poles[i];
        double x = 2.0;
        int n;
        o.xh = 2.0f;
        o.g_prev = (poles[i] * 2.0f) + b;
        for (n = 0; n < 50; ++n)
        {
            const float g1 = (poles[i] * o.xh) + b;
            const float xh = fdi_gen_obs_predict(&o, &p, g1, poles[i]);
            const double e = exp(jac * DT);
            x = (fabs(jac) > 0.0) ? ((e * x) + (((e - 1.0) / jac) * (double)b)) : (x + (DT * (double)b));
            assert_true(fabs((double)xh - x) < (1e-4 * (1.0 + fabs(x))));
            assert_int_equal(fdi_gen_obs_store(&o, xh, (poles[i] * xh) + b), FDI_OK);
        }
    }
    assert_true(fabs((double)fdi_gen_obs_predict(NULL, &p, 1.0f, -1.0f) - (double)0.0f) <= 0.0);
    assert_true(fabs((double)fdi_gen_obs_predict(&o, NULL, 1.0f, -1.0f) - (double)0.0f) <= 0.0);
    o.xh = 1.0f;
    assert_int_equal(fdi_gen_obs_store(&o, NAN, 0.0f), FDI_NOT_FINITE);
    assert_int_equal(fdi_gen_obs_store(&o, 0.0f, INFINITY), FDI_NOT_FINITE);
    assert_true(fabs((double)o.xh - (double)1.0f) <= 0.0); /* nothing stored */
    assert_int_equal(fdi_gen_obs_store(NULL, 0.0f, 0.0f), FDI_BAD_ARG);
    assert_true(fabs((double)fdi_gen_heaviside(0.5f) - (double)1.0f) <= 0.0);
    assert_true(fabs((double)fdi_gen_heaviside(0.0f) - (double)0.0f) <= 0.0);
    assert_true(fabs((double)fdi_gen_heaviside(-2.0f) - (double)0.0f) <= 0.0);
    assert_true(fabs((double)fdi_gen_sign(-3.0f) - (double)-1.0f) <= 0.0);
    assert_true(fabs((double)fdi_gen_sign(0.0f) - (double)0.0f) <= 0.0);
    assert_true(fabs((double)fdi_gen_sign(7.0f) - (double)1.0f) <= 0.0);
    assert_true(fabs((double)fdi_gen_max(2.0f, -1.0f) - 2.0) <= 0.0);
    assert_true(fabs((double)fdi_gen_max(-1.0f, 2.0f) - 2.0) <= 0.0);
    assert_true(fabs((double)fdi_gen_min(2.0f, -1.0f) + 1.0) <= 0.0);
    assert_true(fabs((double)fdi_gen_min(-1.0f, 2.0f) + 1.0) <= 0.0);
}

static void test_tanh(void **state)
{
    /* fdi_gen_tanh against the double tanh within 4 float ulp (relative 2.4e-7) over its three branches (the series
       near 0, e^-2|x| below 9.1, saturation), odd, and NaN / Inf */
    double x;
    (void)state;
    for (x = -12.0; x <= 12.0; x += 0.000731)
    {
        const float xf = (float)x;
        const double ref = tanh((double)xf);
        assert_true(fabs((double)fdi_gen_tanh(xf) - ref) <= (2.4e-7 * fabs(ref)));
        assert_true(fabs((double)fdi_gen_tanh(-xf) + (double)fdi_gen_tanh(xf)) <= 0.0);
    }
    assert_true(fabs((double)fdi_gen_tanh(1.0e-30f) - 1.0e-30) <= 1.0e-37);
    assert_true(fabs((double)fdi_gen_tanh(INFINITY) - 1.0) <= 0.0);
    assert_true(fabs((double)fdi_gen_tanh(-INFINITY) + 1.0) <= 0.0);
    assert_true(isnan(fdi_gen_tanh(NAN)));
}

/* |f - ref| in units of the float spacing at ref (its last place) */
static double ulps(float f, double ref)
{
    const float a = fabsf((float)ref);
    const double u = (double)(nextafterf(a, INFINITY) - a);
    return fabs((double)f - ref) / u;
}

static void test_sin_cos(void **state)
{
    /* fdi_gen_sin / fdi_gen_cos against the double sin / cos: within 1.6 ulp for |x| <= 13 (the polynomials alone
       up to pi/4, the quadrant reduction beyond), within 1e-7 absolute up to 2048 (near a zero of the result far
       out, the reduction's absolute error is many of the result's ulps); odd and even exactly; NaN beyond 2048 and
       for NaN and +-Inf */
    double x;
    (void)state;
    for (x = -13.0; x <= 13.0; x += 0.0000731)
    {
        const float xf = (float)x;
        assert_true(ulps(fdi_gen_sin(xf), sin((double)xf)) <= 1.6);
        assert_true(ulps(fdi_gen_cos(xf), cos((double)xf)) <= 1.6);
        assert_true(fabs((double)fdi_gen_sin(-xf) + (double)fdi_gen_sin(xf)) <= 0.0);
        assert_true(fabs((double)fdi_gen_cos(-xf) - (double)fdi_gen_cos(xf)) <= 0.0);
    }
    for (x = -2048.0; x <= 2048.0; x += 0.00917)
    {
        const float xf = (float)x;
        assert_true(fabs((double)fdi_gen_sin(xf) - sin((double)xf)) <= 1.0e-7);
        assert_true(fabs((double)fdi_gen_cos(xf) - cos((double)xf)) <= 1.0e-7);
    }
    assert_true(fabs((double)fdi_gen_sin(2048.0f) - sin(2048.0)) <= 1.0e-7);
    assert_true(isnan(fdi_gen_sin(2048.001f)) && isnan(fdi_gen_cos(-3000.0f)));
    assert_true(isnan(fdi_gen_sin(NAN)) && isnan(fdi_gen_cos(NAN)));
    assert_true(isnan(fdi_gen_sin(INFINITY)) && isnan(fdi_gen_cos(-INFINITY)));
}

static void test_observer_phi_accuracy(void **state)
{
    /* one predict step from xh = 0 with g_prev = g1 = 1 is phi = expm1(J dt) / J: within 4 float ulp of the double
       value for poles from -3000 1/s (J dt = -30, past the series and the table) to +100 1/s (unstable: expm1f) */
    fdi_gen_param_t p;
    fdi_obs_t o;
    double jac;
    (void)state;
    params(&p);
    for (jac = -3000.0; jac <= 100.0; jac += 0.0371)
    {
        const float jf = (float)jac;
        const double jd = (double)jf;
        const double jdt = jd * (double)(2.0f * p.svf.h);
        const double ref = (fabs(jdt) > 0.0) ? (expm1(jdt) / jd) : (double)(2.0f * p.svf.h);
        o.xh = 0.0f;
        o.g_prev = 1.0f;
        assert_true(fabs((double)fdi_gen_obs_predict(&o, &p, 1.0f, jf) - ref) <= (4.8e-7 * fabs(ref)));
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_slots_and_inputs),
        cmocka_unit_test(test_bad_descriptors_and_sets),
        cmocka_unit_test(test_derived_signals),
        cmocka_unit_test(test_bank),
        cmocka_unit_test(test_slots_run),
        cmocka_unit_test(test_operating_domain),
        cmocka_unit_test(test_sensitivities_leave_the_residual_alone),
        cmocka_unit_test(test_diag_sensitivities),
        cmocka_unit_test(test_diag_slots_out_of_order),
        cmocka_unit_test(test_observer_building_blocks),
        cmocka_unit_test(test_tanh),
        cmocka_unit_test(test_sin_cos),
        cmocka_unit_test(test_observer_phi_accuracy),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
