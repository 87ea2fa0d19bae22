/*
 * test_fdi_est.c - the on-line estimator (a Kalman filter on a test's uncertain quantities): arguments and non-finite
 * input (state unchanged); the prior (estimate, spread); an offset converges like the running mean of its samples
 * (exactly, to float rounding, with q = 0 and a prior far wider than the noise); the spread falls as sigma / sqrt(n);
 * two quantities with regressors 1 and a varying signal converge to their values on noise and their errors stay
 * within 4 of the filter's own standard deviations; the freeze keeps the estimate bit for bit while its uncertainty
 * grows by q, up to the prior variance; the bounds; a drift followed with the lag its declared rate allows; the
 * innovation is the sample minus the prediction before it.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "fdi_est.h"
#include "fdi_test_util.h"

static const fdi_est_param_t offset_only[1] = {{0.0f, 4.0f, 0.0f, -3.0f, 3.0f, 10.0f}};

static void test_bad_args(void **state)
{
    fdi_est_t e;
    float nu = 5.0f;
    float a = 5.0f;
    const float h[1] = {1.0f};
    const float bad_h[1] = {NAN};
    fdi_est_param_t p[2] = {{0.0f, 1.0f, 0.0f, -1.0f, 1.0f, 1.0f}, {0.0f, 1.0f, 0.0f, -1.0f, 1.0f, 1.0f}};
    (void)state;
    assert_int_equal(fdi_est_init(NULL, p, 1U), FDI_BAD_ARG);
    assert_int_equal(fdi_est_init(&e, NULL, 1U), FDI_BAD_ARG);
    assert_int_equal(fdi_est_init(&e, p, 0U), FDI_BAD_ARG);
    assert_int_equal(fdi_est_init(&e, p, FDI_EST_MAX_PARAMS + 1U), FDI_BAD_ARG);
    p[1].var = 0.0f;
    assert_int_equal(fdi_est_init(&e, p, 2U), FDI_BAD_ARG);
    p[1].var = 1.0f;
    p[1].q = -1.0f;
    assert_int_equal(fdi_est_init(&e, p, 2U), FDI_BAD_ARG);
    p[1].q = 0.0f;
    p[1].mean = 2.0f; /* outside its bounds */
    assert_int_equal(fdi_est_init(&e, p, 2U), FDI_BAD_ARG);
    p[1].mean = 0.0f;
    p[1].step = 0.0f;
    assert_int_equal(fdi_est_init(&e, p, 2U), FDI_BAD_ARG);
    p[1].step = 1.0f;
    p[1].mean = NAN;
    assert_int_equal(fdi_est_init(&e, p, 2U), FDI_NOT_FINITE);
    assert_int_equal(fdi_est_check(p, 1U), FDI_OK);
    assert_int_equal(fdi_est_check(p, 2U), FDI_NOT_FINITE);
    p[1].mean = 0.0f;
    assert_int_equal(fdi_est_init(&e, p, 2U), FDI_OK);
    assert_int_equal(fdi_est_update(NULL, p, 1U, h, 1.0f, 1.0f, 1.0f, false, &nu, &a), FDI_BAD_ARG);
    assert_int_equal(fdi_est_update(&e, NULL, 1U, h, 1.0f, 1.0f, 1.0f, false, &nu, &a), FDI_BAD_ARG);
    assert_int_equal(fdi_est_update(&e, p, 1U, NULL, 1.0f, 1.0f, 1.0f, false, &nu, &a), FDI_BAD_ARG);
    assert_int_equal(fdi_est_update(&e, p, 1U, h, 1.0f, 1.0f, 1.0f, false, NULL, &a), FDI_BAD_ARG);
    assert_int_equal(fdi_est_update(&e, p, 1U, h, 1.0f, 1.0f, 1.0f, false, &nu, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_est_update(&e, p, 0U, h, 1.0f, 1.0f, 1.0f, false, &nu, &a), FDI_BAD_ARG);
    assert_int_equal(fdi_est_update(&e, p, 1U, h, 1.0f, 0.0f, 1.0f, false, &nu, &a), FDI_BAD_ARG);
    assert_int_equal(fdi_est_update(&e, p, 1U, h, 1.0f, 1.0f, 0.5f, false, &nu, &a), FDI_BAD_ARG);
    assert_int_equal(fdi_est_update(&e, p, 1U, h, 1.0f, 1.0f, NAN, false, &nu, &a), FDI_NOT_FINITE);
    assert_int_equal(fdi_est_update(&e, p, 1U, h, NAN, 1.0f, 1.0f, false, &nu, &a), FDI_NOT_FINITE);
    assert_int_equal(fdi_est_update(&e, p, 1U, h, 1.0f, INFINITY, 1.0f, false, &nu, &a), FDI_NOT_FINITE);
    assert_int_equal(fdi_est_update(&e, p, 1U, bad_h, 1.0f, 1.0f, 1.0f, false, &nu, &a), FDI_NOT_FINITE);
    assert_near(nu, 5.0, 0.0); /* outputs untouched */
    assert_near(a, 5.0, 0.0);
    assert_near(fdi_est_value(&e, 0U), 0.0, 0.0); /* state untouched */
    assert_near(fdi_est_std(&e, 0U), 1.0, 1e-7);
    assert_near(fdi_est_value(NULL, 0U), 0.0, 0.0);
    assert_near(fdi_est_std(NULL, 0U), 0.0, 0.0);
    assert_near(fdi_est_value(&e, FDI_EST_MAX_PARAMS), 0.0, 0.0);
}

/* With q = 0 the filter of one offset (h = 1) is the Bayesian mean: theta_n = (m0 / v0 + sum r / R) / (1 / v0 + n / R)
   and P_n = 1 / (1 / v0 + n / R); the innovation is the sample minus the estimate before it. */
static void test_offset_is_the_running_mean(void **state)
{
    fdi_est_t e;
    const float h[1] = {1.0f};
    const double v0 = 4.0;
    const double noise = 0.01;
    double sum = 0.0;
    uint32_t n;
    (void)state;
    assert_int_equal(fdi_est_init(&e, offset_only, 1U), FDI_OK);
    assert_near(fdi_est_value(&e, 0U), 0.0, 0.0);
    assert_near(fdi_est_std(&e, 0U), 2.0, 1e-7);
    for (n = 1U; n <= 500U; ++n)
    {
        const float r = 0.7f + (0.05f * (float)((n * 37U) % 11U) - 0.25f);
        const float before = fdi_est_value(&e, 0U);
        const double p_before = 1.0 / ((1.0 / v0) + ((double)(n - 1U) / noise));
        float nu = 0.0f;
        float a = 0.0f;
        assert_int_equal(fdi_est_update(&e, offset_only, 1U, h, r, (float)noise, 1.0f, false, &nu, &a), FDI_OK);
        sum += (double)r;
        assert_near(nu, (double)(r - before), 1e-7);
        assert_near(a, sqrt(p_before), 1e-4 * sqrt(p_before) + 1e-7);
        assert_near(fdi_est_value(&e, 0U), (sum / noise) / ((1.0 / v0) + ((double)n / noise)), 1e-5);
        assert_near(fdi_est_std(&e, 0U), sqrt(1.0 / ((1.0 / v0) + ((double)n / noise))), 1e-4 * sqrt(noise));
    }
}

/* An offset and a gain on a varying regressor (an accelerometer's bias and its tilt with the acceleration): on white
   noise both converge, their errors within 4 of the filter's own standard deviations, and the innovations' spread
   ends near the noise's. */
static void test_two_quantities_converge(void **state)
{
    static const fdi_est_param_t p[2] = {{0.0f, 0.03f, 1e-8f, -0.3f, 0.3f, 1.0f}, {0.03f, 3e-4f, 0.0f, 0.0f, 0.06f, 1.0f}};
    const float sigma = 0.02f;
    const float bias = -0.12f;
    const float tilt = 0.045f;
    fdi_est_t e;
    test_rng_t rng = {12345U};
    uint32_t k;
    double sq = 0.0;
    uint32_t late = 0U;
    (void)state;
    assert_int_equal(fdi_est_init(&e, p, 2U), FDI_OK);
    for (k = 0U; k < 6000U; ++k)
    {
        const float ax = 3.0f * sinf(0.01f * (float)k * 1.3f); /* +-3 m/s^2 of acceleration */
        const float h[2] = {1.0f, ax};
        const float r = bias + (tilt * ax) + (sigma * (float)test_normal(&rng));
        float nu = 0.0f;
        float a = 0.0f;
        assert_int_equal(fdi_est_update(&e, p, 2U, h, r, sigma * sigma, 1.0f, false, &nu, &a), FDI_OK);
        if (k >= 3000U)
        {
            sq += (double)nu * (double)nu;
            late++;
        }
    }
    assert_near(fdi_est_value(&e, 0U), bias, 4.0 * (double)fdi_est_std(&e, 0U));
    assert_near(fdi_est_value(&e, 1U), tilt, 4.0 * (double)fdi_est_std(&e, 1U));
    assert_true(fdi_est_std(&e, 0U) < 0.01f);
    assert_true(fdi_est_std(&e, 1U) < 0.005f);
    assert_near(sqrt(sq / (double)late), sigma, 0.15 * (double)sigma);
}

/* Frozen: the estimate stays bit for bit, the spread grows by q per step up to the prior variance; bounds clamp. */
static void test_freeze_and_bounds(void **state)
{
    static const fdi_est_param_t p[1] = {{0.0f, 1.0f, 1e-4f, -0.5f, 0.5f, 10.0f}};
    const float h[1] = {1.0f};
    fdi_est_t e;
    float nu = 0.0f;
    float a = 0.0f;
    float held;
    float var;
    uint32_t k;
    (void)state;
    assert_int_equal(fdi_est_init(&e, p, 1U), FDI_OK);
    for (k = 0U; k < 200U; ++k)
    {
        assert_int_equal(fdi_est_update(&e, p, 1U, h, 0.3f, 0.01f, 1.0f, false, &nu, &a), FDI_OK);
    }
    held = fdi_est_value(&e, 0U);
    assert_near(held, 0.3, 1e-3);
    var = fdi_est_std(&e, 0U) * fdi_est_std(&e, 0U);
    for (k = 0U; k < 100U; ++k)
    {
        assert_int_equal(fdi_est_update(&e, p, 1U, h, 5.0f, 0.01f, 1.0f, true, &nu, &a), FDI_OK);
        assert_memory_equal(&(float){fdi_est_value(&e, 0U)}, &held, sizeof(float));
        assert_near(nu, 5.0 - (double)held, 1e-6);
    }
    assert_near((double)(fdi_est_std(&e, 0U) * fdi_est_std(&e, 0U)), (double)var + (100.0 * 1e-4), 1e-6);
    for (k = 0U; k < 20000U; ++k) /* the variance grows back to the prior's, never beyond */
    {
        assert_int_equal(fdi_est_update(&e, p, 1U, h, 5.0f, 0.01f, 1.0f, true, &nu, &a), FDI_OK);
    }
    assert_near(fdi_est_std(&e, 0U), 1.0, 1e-6);
    for (k = 0U; k < 50U; ++k) /* far beyond the bound: clamped at it */
    {
        assert_int_equal(fdi_est_update(&e, p, 1U, h, 5.0f, 0.01f, 1.0f, false, &nu, &a), FDI_OK);
        assert_true(fdi_est_value(&e, 0U) <= 0.5f);
    }
    assert_near(fdi_est_value(&e, 0U), 0.5, 0.0);
    for (k = 0U; k < 50U; ++k)
    {
        assert_int_equal(fdi_est_update(&e, p, 1U, h, -5.0f, 0.01f, 1.0f, false, &nu, &a), FDI_OK);
    }
    assert_near(fdi_est_value(&e, 0U), -0.5, 0.0);
}

/* A drift at the declared rate (q = (rate dt / 2)^2, fdi_analysis.residuals.estimation) is followed with a lag of about
   2 noise sigmas; a zero regressor leaves the estimate alone. */
static void test_drift_and_no_excitation(void **state)
{
    const float dt = 0.01f;
    const float rate = 0.2f; /* per second */
    const float sd_q = rate * dt / 2.0f;
    const fdi_est_param_t p[1] = {{0.0f, 1.0f, sd_q * sd_q, -10.0f, 10.0f, 10.0f}};
    const float h[1] = {1.0f};
    const float zero[1] = {0.0f};
    const float sigma = 0.02f;
    fdi_est_t e;
    test_rng_t rng = {99U};
    float nu = 0.0f;
    float a = 0.0f;
    float held;
    uint32_t k;
    (void)state;
    assert_int_equal(fdi_est_init(&e, p, 1U), FDI_OK);
    for (k = 0U; k < 1000U; ++k)
    {
        const float truth = rate * dt * (float)k;
        assert_int_equal(
            fdi_est_update(&e, p, 1U, h, truth + (sigma * (float)test_normal(&rng)), sigma * sigma, 1.0f, false, &nu, &a), FDI_OK);
    }
    assert_near(fdi_est_value(&e, 0U), rate * dt * 999.0f, 3.0 * (double)sigma);
    assert_true(fdi_est_value(&e, 0U) < rate * dt * 999.0f); /* behind the ramp */
    held = fdi_est_value(&e, 0U);
    for (k = 0U; k < 100U; ++k)
    {
        assert_int_equal(fdi_est_update(&e, p, 1U, zero, 7.0f, sigma * sigma, 1.0f, false, &nu, &a), FDI_OK);
        assert_near(a, 0.0, 0.0);
    }
    assert_memory_equal(&(float){fdi_est_value(&e, 0U)}, &held, sizeof(float));
}

/* The step limit: from the prior (variance 1), a residual of 1.0 that the filter would follow at once: the estimate
   moves by its step per sample and no more, and the variance keeps what it could not follow, so the threshold's
   spread stays as wide as the prior's instead of the estimate swallowing the offset (or a fault) at once; once within
   reach, the filter settles on it. */
static void test_step_limit(void **state)
{
    static const fdi_est_param_t p[1] = {{0.0f, 1.0f, 0.0f, -2.0f, 2.0f, 0.001f}};
    const float h[1] = {1.0f};
    fdi_est_t e;
    float nu = 0.0f;
    float a = 0.0f;
    uint32_t k;
    (void)state;
    assert_int_equal(fdi_est_init(&e, p, 1U), FDI_OK);
    for (k = 1U; k <= 50U; ++k)
    {
        assert_int_equal(fdi_est_update(&e, p, 1U, h, 1.0f, 0.01f, 1.0f, false, &nu, &a), FDI_OK);
        assert_near(fdi_est_value(&e, 0U), 0.001 * (double)k, 1e-6);
        assert_true(a > 0.9f); /* the prior's spread, 1, kept */
        assert_near(nu, 1.0 - 0.001 * (double)(k - 1U), 1e-6);
    }
    for (k = 0U; k < 3000U; ++k)
    {
        assert_int_equal(fdi_est_update(&e, p, 1U, h, 1.0f, 0.01f, 1.0f, false, &nu, &a), FDI_OK);
    }
    assert_near(fdi_est_value(&e, 0U), 1.0, 0.01);
    assert_true(a < 0.05f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_args),          cmocka_unit_test(test_offset_is_the_running_mean),
        cmocka_unit_test(test_two_quantities_converge), cmocka_unit_test(test_freeze_and_bounds),
        cmocka_unit_test(test_drift_and_no_excitation), cmocka_unit_test(test_step_limit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
