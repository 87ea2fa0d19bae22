/*
 * test_fdi_eval.c - residual evaluation: arguments, NaN rejection, the test ratio formula, gate with
 * set/clear hysteresis (exact step counts), two-sided CUSUM on a small bias (exact step counts from its
 * recursion), clamp-bounded clearing, false alarms on white noise; the adaptive threshold (allowance: its
 * arguments, the gate widened by exactly the allowance, no CUSUM from an offset the allowance explains, the fixed
 * gate bit for bit at allowance 0).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "fdi_eval.h"
#include "fdi_test_util.h"

/* sigma = 0.1, gate 4 sigma, CUSUM k = 0.5, h = 8, set after 3, clear after 5 */
static void init(fdi_eval_t *e)
{
    const fdi_eval_config_t cfg = {4.0f, 0.01f, 0.5f, 8.0f, 3U, 5U};
    assert_int_equal(fdi_eval_init(e, &cfg), FDI_OK);
}

static void test_bad_args(void **state)
{
    fdi_eval_t e;
    fdi_eval_out_t o;
    const fdi_eval_config_t ok = {4.0f, 0.01f, 0.5f, 8.0f, 3U, 5U};
    fdi_eval_config_t bad = ok;
    (void)state;
    assert_int_equal(fdi_eval_init(NULL, &ok), FDI_BAD_ARG);
    assert_int_equal(fdi_eval_init(&e, NULL), FDI_BAD_ARG);
    bad.variance = 0.0f;
    assert_int_equal(fdi_eval_init(&e, &bad), FDI_BAD_ARG);
    bad = ok;
    bad.gate = -1.0f;
    assert_int_equal(fdi_eval_init(&e, &bad), FDI_BAD_ARG);
    bad = ok;
    bad.set_count = 0U;
    assert_int_equal(fdi_eval_init(&e, &bad), FDI_BAD_ARG);
    bad = ok;
    bad.clear_count = 0U;
    assert_int_equal(fdi_eval_init(&e, &bad), FDI_BAD_ARG);
    bad = ok;
    bad.cusum_h = NAN;
    assert_int_equal(fdi_eval_init(&e, &bad), FDI_NOT_FINITE);
    bad = ok;
    bad.gate = 1e-30f; /* gate^2 underflows: 1 / gate^2 is not finite */
    assert_int_equal(fdi_eval_init(&e, &bad), FDI_BAD_ARG);
    init(&e);
    assert_int_equal(fdi_eval_reset(NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_eval_step(NULL, 0.0f, &o), FDI_BAD_ARG);
    assert_int_equal(fdi_eval_step(&e, 0.0f, NULL), FDI_BAD_ARG);
}

static void test_ratio_and_nan(void **state)
{
    fdi_eval_t e;
    fdi_eval_out_t o = {FDI_TEST_NOT_EVALUABLE, -1.0f};
    (void)state;
    init(&e);
    assert_int_equal(fdi_eval_step(&e, 0.2f, &o), FDI_OK);
    assert_near(o.ratio, 0.04 / (16.0 * 0.01), 1e-6); /* r^2 / (gate^2 variance) = 0.25 */
    assert_int_equal(o.status, FDI_TEST_OK);
    o.ratio = -1.0f;
    assert_int_equal(fdi_eval_step(&e, NAN, &o), FDI_NOT_FINITE);
    assert_int_equal(fdi_eval_step(&e, INFINITY, &o), FDI_NOT_FINITE);
    assert_near(o.ratio, -1.0, 0.0);
    assert_near(e.g_pos, 2.0 - 0.5, 1e-6); /* only the finite sample entered: z = 2 */
    /* a huge finite residual is an alarm sample (ratio may be +Inf) */
    assert_int_equal(fdi_eval_step(&e, 3.0e38f, &o), FDI_OK);
    assert_true(o.ratio > 1.0f);
}

/* Gate only (CUSUM out of reach): set after exactly 3 raw samples, clear after exactly 5 quiet ones. */
static void test_hysteresis(void **state)
{
    fdi_eval_t e;
    fdi_eval_out_t o = {FDI_TEST_OK, 0.0f};
    const fdi_eval_config_t cfg = {4.0f, 0.01f, 100.0f, 8.0f, 3U, 5U}; /* k = 100: CUSUM never grows */
    int k;
    (void)state;
    assert_int_equal(fdi_eval_init(&e, &cfg), FDI_OK);
    assert_int_equal(fdi_eval_step(&e, 0.5f, &o), FDI_OK); /* 5 sigma > gate */
    assert_int_equal(o.status, FDI_TEST_OK);
    assert_int_equal(fdi_eval_step(&e, 0.0f, &o), FDI_OK); /* interrupts the run */
    for (k = 1; k <= 3; ++k)
    {
        assert_int_equal(fdi_eval_step(&e, -0.5f, &o), FDI_OK);
        assert_int_equal(o.status, (k < 3) ? FDI_TEST_OK : FDI_TEST_ALARM);
    }
    for (k = 1; k <= 5; ++k)
    {
        assert_int_equal(fdi_eval_step(&e, 0.01f, &o), FDI_OK);
        assert_int_equal(o.status, (k < 5) ? FDI_TEST_ALARM : FDI_TEST_OK);
    }
    assert_int_equal(fdi_eval_step(&e, 0.5f, &o), FDI_OK);
    assert_int_equal(fdi_eval_reset(&e), FDI_OK);
    assert_int_equal(fdi_eval_step(&e, 0.5f, &o), FDI_OK);
    assert_int_equal(o.status, FDI_TEST_OK); /* reset forgot the earlier raw sample */
}

/*
 * A bias of 1.5 sigma (inside the 4-sigma gate): g grows by z - k = 1 per step, exceeds h = 8 at step 9,
 * the alarm sets at step 9 + 3 - 1 = 11. Negative bias likewise on g-. After the bias goes, g (clamped at
 * 2h = 16) falls by k = 0.5 per step: it is back below h after 17 quiet steps, clear 5 steps later.
 */
static void check_bias(float bias)
{
    fdi_eval_t e;
    fdi_eval_out_t o = {FDI_TEST_OK, 0.0f};
    int k;
    int set_at = -1;
    int clear_at = -1;
    init(&e);
    for (k = 1; k <= 40; ++k)
    {
        assert_int_equal(fdi_eval_step(&e, bias, &o), FDI_OK);
        if ((set_at < 0) && (o.status == FDI_TEST_ALARM))
        {
            set_at = k;
        }
    }
    assert_int_equal(set_at, 11);
    assert_near(fmax(e.g_pos, e.g_neg), 16.0, 1e-5);
    for (k = 1; k <= 60; ++k)
    {
        assert_int_equal(fdi_eval_step(&e, 0.0f, &o), FDI_OK);
        if ((clear_at < 0) && (o.status == FDI_TEST_OK))
        {
            clear_at = k;
        }
    }
    /* g = 16 - 0.5 n <= 8 first at n = 16 (not > h): quiet from step 16, clear at 16 + 5 - 1 = 20 */
    assert_int_equal(clear_at, 20);
}

static void test_cusum_small_bias(void **state)
{
    (void)state;
    check_bias(0.15f);
    check_bias(-0.15f);
}

/*
 * White Gaussian noise at the assumed variance: with gate 4 sigma and set after 3 samples a false alarm
 * needs 3 consecutive |z| > 4 (p ~ 2.5e-13 per step) and the CUSUM (k 0.5, h 8) has an in-control run
 * length of ~1e4 per side, so its excursions are the only expected alarms: fewer than 200 in 1e6 steps.
 * With k = 1.0, h = 10 (ARL > 1e8), none.
 */
static void test_false_alarms(void **state)
{
    fdi_eval_t e1;
    fdi_eval_t e2;
    fdi_eval_out_t o = {FDI_TEST_OK, 0.0f};
    const fdi_eval_config_t strict = {4.0f, 0.01f, 1.0f, 10.0f, 3U, 5U};
    test_rng_t rng = {2024ULL};
    int onsets1 = 0;
    int onsets2 = 0;
    bool prev1 = false;
    bool prev2 = false;
    long k;
    (void)state;
    init(&e1);
    assert_int_equal(fdi_eval_init(&e2, &strict), FDI_OK);
    for (k = 0; k < 1000000L; ++k)
    {
        const float r = (float)(0.1 * test_normal(&rng));
        assert_int_equal(fdi_eval_step(&e1, r, &o), FDI_OK);
        onsets1 += ((o.status == FDI_TEST_ALARM) && !prev1) ? 1 : 0;
        prev1 = (o.status == FDI_TEST_ALARM);
        assert_int_equal(fdi_eval_step(&e2, r, &o), FDI_OK);
        onsets2 += ((o.status == FDI_TEST_ALARM) && !prev2) ? 1 : 0;
        prev2 = (o.status == FDI_TEST_ALARM);
    }
    print_message("false alarm onsets in 1e6 steps: %d (k 0.5, h 8), %d (k 1, h 10)\n", onsets1, onsets2);
    assert_true(onsets1 < 200);
    assert_int_equal(onsets2, 0);
}

/*
 * Adaptive threshold: the allowance a widens the gate to 4 sigma + a = 0.4 + a. With a = 0.3, a residual of 0.69 is
 * quiet and 0.71 alarms after 3 samples (the fixed gate alarms on both); a constant offset of 0.3 + 2 sigma builds
 * the CUSUM of 2 sigma (g grows by 1.5 per step, exceeds h = 8 at step 6: the alarm at step 6 + 3 - 1 = 8), and 0.3
 * builds none in 1000 steps. Allowance 0 gives fdi_eval_step()'s states and ratios bit for bit on noise.
 */
static void test_adaptive(void **state)
{
    fdi_eval_t e;
    fdi_eval_t f;
    fdi_eval_out_t o = {FDI_TEST_OK, 0.0f};
    fdi_eval_out_t p = {FDI_TEST_OK, 0.0f};
    test_rng_t rng = {7ULL};
    int k;
    int set_at = -1;
    (void)state;
    init(&e);
    assert_int_equal(fdi_eval_step_adaptive(NULL, 0.0f, 0.0f, &o), FDI_BAD_ARG);
    assert_int_equal(fdi_eval_step_adaptive(&e, 0.0f, 0.0f, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_eval_step_adaptive(&e, 0.0f, -0.1f, &o), FDI_BAD_ARG);
    assert_int_equal(fdi_eval_step_adaptive(&e, 0.0f, NAN, &o), FDI_NOT_FINITE);
    assert_int_equal(fdi_eval_step_adaptive(&e, 0.0f, INFINITY, &o), FDI_NOT_FINITE);
    assert_int_equal(fdi_eval_step_adaptive(&e, NAN, 0.1f, &o), FDI_NOT_FINITE);
    /* inside the widened gate (the CUSUM is cleared between the two cases by the reset) */
    for (k = 0; k < 3; ++k)
    {
        assert_int_equal(fdi_eval_step_adaptive(&e, -0.69f, 0.3f, &o), FDI_OK);
        assert_int_equal(o.status, FDI_TEST_OK);
    }
    assert_near(o.ratio, (0.39 / 0.4) * (0.39 / 0.4), 1e-5);
    assert_int_equal(fdi_eval_reset(&e), FDI_OK);
    for (k = 0; k < 3; ++k)
    {
        assert_int_equal(fdi_eval_step_adaptive(&e, -0.71f, 0.3f, &o), FDI_OK);
    }
    assert_int_equal(o.status, FDI_TEST_ALARM);
    /* an offset the allowance explains builds no CUSUM; beyond it, the CUSUM of the excess */
    init(&e);
    for (k = 0; k < 1000; ++k)
    {
        assert_int_equal(fdi_eval_step_adaptive(&e, 0.3f, 0.3f, &o), FDI_OK);
        assert_int_equal(o.status, FDI_TEST_OK);
    }
    assert_true((e.g_pos <= 0.0f) && (e.g_neg <= 0.0f));
    init(&e);
    for (k = 1; k <= 40; ++k)
    {
        assert_int_equal(fdi_eval_step_adaptive(&e, 0.5f, 0.3f, &o), FDI_OK);
        if ((set_at < 0) && (o.status == FDI_TEST_ALARM))
        {
            set_at = k;
        }
    }
    assert_int_equal(set_at, 8);
    /* allowance 0: the fixed gate, bit for bit */
    init(&e);
    init(&f);
    for (k = 0; k < 20000; ++k)
    {
        const float r = (float)(0.3 * test_normal(&rng));
        assert_int_equal(fdi_eval_step_adaptive(&e, r, 0.0f, &o), FDI_OK);
        assert_int_equal(fdi_eval_step(&f, r, &p), FDI_OK);
        assert_int_equal(o.status, p.status);
        assert_memory_equal(&o.ratio, &p.ratio, sizeof(float));
        assert_memory_equal(&e.g_pos, &f.g_pos, sizeof(float));
        assert_memory_equal(&e.g_neg, &f.g_neg, sizeof(float));
        assert_int_equal(e.n_raw, f.n_raw);
        assert_int_equal(e.n_quiet, f.n_quiet);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_args),         cmocka_unit_test(test_ratio_and_nan),
        cmocka_unit_test(test_hysteresis),       cmocka_unit_test(test_cusum_small_bias),
        cmocka_unit_test(test_false_alarms),     cmocka_unit_test(test_adaptive),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
