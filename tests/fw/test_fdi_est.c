/*
 * test_fdi_est.c - the offset estimator: arguments and non-finite input (state unchanged), the start-up mean (the
 * running average of the first `startup` samples, exactly; a short start-up followed at once by the gain dt / tau), the forgetting after it (a step reaches 1 - 1/e of its
 * size after tau, to the recursion's value), the lag behind a slow drift (rate * tau), the freeze (bit for bit),
 * the bound, the corrected residual (the sample minus the estimate before it), convergence on noise.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "fdi_est.h"
#include "fdi_test_util.h"

#define DT 0.01f
#define TAU 1.0f /* 100 samples */
#define STARTUP 100U /* the longest start-up at TAU */

static void test_bad_args(void **state)
{
    fdi_est_t e;
    float c = 5.0f;
    (void)state;
    assert_int_equal(fdi_est_init(NULL, DT, TAU, STARTUP), FDI_BAD_ARG);
    assert_int_equal(fdi_est_init(&e, 0.0f, TAU, STARTUP), FDI_BAD_ARG);
    assert_int_equal(fdi_est_init(&e, DT, 0.5f * DT, STARTUP), FDI_BAD_ARG);
    assert_int_equal(fdi_est_init(&e, DT, TAU, 0U), FDI_BAD_ARG);
    assert_int_equal(fdi_est_init(&e, DT, TAU, STARTUP + 2U), FDI_BAD_ARG); /* longer than tau */
    assert_int_equal(fdi_est_init(&e, NAN, TAU, STARTUP), FDI_NOT_FINITE);
    assert_int_equal(fdi_est_init(&e, DT, INFINITY, STARTUP), FDI_NOT_FINITE);
    assert_int_equal(fdi_est_init(&e, DT, TAU, STARTUP), FDI_OK);
    assert_int_equal(fdi_est_update(NULL, 1.0f, 1.0f, false, &c), FDI_BAD_ARG);
    assert_int_equal(fdi_est_update(&e, 1.0f, 1.0f, false, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_est_update(&e, 1.0f, -1.0f, false, &c), FDI_BAD_ARG);
    assert_int_equal(fdi_est_update(&e, NAN, 1.0f, false, &c), FDI_NOT_FINITE);
    assert_int_equal(fdi_est_update(&e, 1.0f, INFINITY, false, &c), FDI_NOT_FINITE);
    assert_near(c, 5.0, 0.0); /* *corrected unchanged */
    assert_int_equal(fdi_est_samples(&e), 0U);
    assert_near(fdi_est_offset(&e), 0.0, 0.0);
    assert_near(fdi_est_offset(NULL), 0.0, 0.0);
    assert_int_equal(fdi_est_samples(NULL), 0U);
    assert_false(fdi_est_ready(NULL));
}

/* Start-up: after n <= tau / dt samples the estimate is their mean; the corrected residual is the sample minus the
   estimate before it (the first sample: itself). */
static void test_startup_mean(void **state)
{
    fdi_est_t e;
    double sum = 0.0;
    uint32_t n;
    (void)state;
    assert_int_equal(fdi_est_init(&e, DT, TAU, STARTUP), FDI_OK);
    for (n = 1U; n <= 100U; ++n)
    {
        const float r = 0.5f + (0.01f * (float)(n % 7U));
        const float before = fdi_est_offset(&e);
        float c = 0.0f;
        assert_int_equal(fdi_est_update(&e, r, 10.0f, false, &c), FDI_OK);
        assert_near(c, (double)(r - before), 0.0);
        sum += (double)r;
        assert_near(fdi_est_offset(&e), sum / (double)n, 1e-5);
        assert_int_equal(fdi_est_samples(&e), n);
        assert_true(fdi_est_ready(&e) == (n >= STARTUP));
    }
}

/* A start-up shorter than tau / dt: the mean of its samples, then at once the gain dt / tau (a step right after the
   start-up is followed to 1 - (1 - g)^k, not absorbed at 1 / n). */
static void test_short_startup(void **state)
{
    fdi_est_t e;
    uint32_t k;
    float c;
    const float g = DT / TAU;
    (void)state;
    assert_int_equal(fdi_est_init(&e, DT, TAU, 10U), FDI_OK);
    for (k = 1U; k <= 10U; ++k)
    {
        assert_false(fdi_est_ready(&e));
        assert_int_equal(fdi_est_update(&e, 0.2f, 10.0f, false, &c), FDI_OK);
    }
    assert_true(fdi_est_ready(&e));
    assert_near(fdi_est_offset(&e), 0.2, 1e-6);
    for (k = 1U; k <= 30U; ++k)
    {
        assert_int_equal(fdi_est_update(&e, 1.2f, 10.0f, false, &c), FDI_OK);
        assert_near(fdi_est_offset(&e), 0.2 + 1.0 - pow(1.0 - (double)g, (double)k), 1e-5);
    }
}

/* After the start-up: exponential forgetting with gain dt / tau; a step of 1 is followed to 1 - (1 - g)^k, which
   is 1 - 1/e within 0.5 % after tau / dt samples; a drift of rate a is followed with the lag a * tau. */
static void test_forgetting_and_drift(void **state)
{
    fdi_est_t e;
    uint32_t k;
    float c;
    const float g = DT / TAU;
    (void)state;
    assert_int_equal(fdi_est_init(&e, DT, TAU, STARTUP), FDI_OK);
    for (k = 0U; k < 100U; ++k)
    {
        assert_int_equal(fdi_est_update(&e, 0.0f, 10.0f, false, &c), FDI_OK);
    }
    for (k = 1U; k <= 100U; ++k)
    {
        assert_int_equal(fdi_est_update(&e, 1.0f, 10.0f, false, &c), FDI_OK);
        assert_near(fdi_est_offset(&e), 1.0 - pow(1.0 - (double)g, (double)k), 1e-5);
    }
    assert_near(fdi_est_offset(&e), 1.0 - exp(-1.0), 0.005);
    assert_int_equal(fdi_est_init(&e, DT, TAU, STARTUP), FDI_OK); /* forgets */
    for (k = 1U; k <= 2000U; ++k) /* a drift of 0.2 per s from 0: after 20 tau the lag is 0.2 * tau */
    {
        const float r = 0.2f * DT * (float)k;
        assert_int_equal(fdi_est_update(&e, r, 10.0f, false, &c), FDI_OK);
    }
    assert_near(c, 0.2 * (double)TAU, 0.01);
}

/* Frozen: the estimate and the sample count stay bit for bit, the corrected residual carries the whole change; the
   bound clamps the estimate at +-limit. */
static void test_freeze_and_bound(void **state)
{
    fdi_est_t e;
    uint32_t k;
    float c;
    float held;
    uint32_t n_held;
    (void)state;
    assert_int_equal(fdi_est_init(&e, DT, TAU, STARTUP), FDI_OK);
    for (k = 0U; k < 300U; ++k)
    {
        assert_int_equal(fdi_est_update(&e, 0.3f, 10.0f, false, &c), FDI_OK);
    }
    held = fdi_est_offset(&e);
    n_held = fdi_est_samples(&e);
    for (k = 0U; k < 1000U; ++k)
    {
        assert_int_equal(fdi_est_update(&e, 2.3f, 10.0f, true, &c), FDI_OK);
        assert_memory_equal(&held, &e.offset, sizeof held);
        assert_near(c, (double)(2.3f - held), 0.0);
    }
    assert_int_equal(fdi_est_samples(&e), n_held);
    for (k = 0U; k < 1000U; ++k)
    {
        assert_int_equal(fdi_est_update(&e, 2.3f, 0.5f, false, &c), FDI_OK);
        assert_true(fdi_est_offset(&e) <= 0.5f);
    }
    assert_near(fdi_est_offset(&e), 0.5, 0.0);
    for (k = 0U; k < 1000U; ++k)
    {
        assert_int_equal(fdi_est_update(&e, -2.3f, 0.5f, false, &c), FDI_OK);
    }
    assert_near(fdi_est_offset(&e), -0.5, 0.0);
}

/* On white noise (sigma 1) around an offset of 3: the estimate's error after 20 tau is within 4 standard deviations
   of an exponential average's, sigma * sqrt(g / (2 - g)). */
static void test_convergence_on_noise(void **state)
{
    fdi_est_t e;
    test_rng_t rng = {7ULL};
    uint32_t k;
    float c;
    const double g = (double)(DT / TAU);
    (void)state;
    assert_int_equal(fdi_est_init(&e, DT, TAU, STARTUP), FDI_OK);
    for (k = 0U; k < 2000U; ++k)
    {
        assert_int_equal(fdi_est_update(&e, 3.0f + (float)test_normal(&rng), 10.0f, false, &c), FDI_OK);
    }
    assert_near(fdi_est_offset(&e), 3.0, 4.0 * sqrt(g / (2.0 - g)));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_args),         cmocka_unit_test(test_startup_mean),
        cmocka_unit_test(test_short_startup),    cmocka_unit_test(test_forgetting_and_drift),
        cmocka_unit_test(test_freeze_and_bound), cmocka_unit_test(test_convergence_on_noise),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
