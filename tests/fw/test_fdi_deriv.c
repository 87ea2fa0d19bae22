/*
 * test_fdi_deriv.c - first-order filtered derivative: arguments, non-finite inputs, exact behaviour on
 * constants and ramps, the exact discrete frequency response on sines, noise attenuation, 1e6-step run.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "fdi_deriv.h"
#include "fdi_test_util.h"

#define DT 0.01f
#define FC 5.0f

static void design(fdi_deriv_coef_t *c)
{
    const fdi_deriv_config_t cfg = {DT, FC};
    assert_int_equal(fdi_deriv_design(c, &cfg), FDI_OK);
}

static void test_bad_args(void **state)
{
    fdi_deriv_coef_t c;
    fdi_deriv_t d;
    fdi_deriv_out_t o;
    const fdi_deriv_config_t nyq = {0.01f, 50.0f};
    const fdi_deriv_config_t neg = {-0.01f, 5.0f};
    const fdi_deriv_config_t zero_fc = {0.01f, 0.0f};
    const fdi_deriv_config_t nan_dt = {NAN, 5.0f};
    const fdi_deriv_config_t inf_fc = {0.01f, INFINITY};
    (void)state;
    assert_int_equal(fdi_deriv_design(NULL, &nyq), FDI_BAD_ARG);
    assert_int_equal(fdi_deriv_design(&c, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_deriv_design(&c, &nyq), FDI_BAD_ARG);
    assert_int_equal(fdi_deriv_design(&c, &neg), FDI_BAD_ARG);
    assert_int_equal(fdi_deriv_design(&c, &zero_fc), FDI_BAD_ARG);
    assert_int_equal(fdi_deriv_design(&c, &nan_dt), FDI_NOT_FINITE);
    assert_int_equal(fdi_deriv_design(&c, &inf_fc), FDI_NOT_FINITE);
    design(&c);
    assert_int_equal(fdi_deriv_reset(NULL, 0.0f), FDI_BAD_ARG);
    assert_int_equal(fdi_deriv_reset(&d, NAN), FDI_NOT_FINITE);
    assert_int_equal(fdi_deriv_reset(&d, 1.0f), FDI_OK);
    assert_int_equal(fdi_deriv_step(NULL, &c, 1.0f, &o), FDI_BAD_ARG);
    assert_int_equal(fdi_deriv_step(&d, NULL, 1.0f, &o), FDI_BAD_ARG);
    assert_int_equal(fdi_deriv_step(&d, &c, 1.0f, NULL), FDI_BAD_ARG);
}

/* NaN / Inf are rejected and leave the state and the output untouched. */
static void test_non_finite(void **state)
{
    fdi_deriv_coef_t c;
    fdi_deriv_t d;
    fdi_deriv_out_t o = {123.0f, 456.0f};
    fdi_deriv_out_t o2;
    (void)state;
    design(&c);
    assert_int_equal(fdi_deriv_reset(&d, 2.0f), FDI_OK);
    assert_int_equal(fdi_deriv_step(&d, &c, NAN, &o), FDI_NOT_FINITE);
    assert_int_equal(fdi_deriv_step(&d, &c, INFINITY, &o), FDI_NOT_FINITE);
    assert_int_equal(fdi_deriv_step(&d, &c, -INFINITY, &o), FDI_NOT_FINITE);
    assert_near(o.y, 123.0, 0.0);
    assert_near(o.dy, 456.0, 0.0);
    assert_int_equal(fdi_deriv_step(&d, &c, 2.0f, &o2), FDI_OK); /* still at rest: derivative exactly 0 */
    assert_near(o2.dy, 0.0, 0.0);
    assert_near(o2.y, 2.0, 0.0);
    /* a finite input whose derivative overflows is rejected too */
    assert_int_equal(fdi_deriv_step(&d, &c, 3.0e38f, &o2), FDI_NOT_FINITE);
}

/* Ramp u = s t: the derivative converges to s, the low-pass lags by tau * s (continuous-time values). */
static void test_ramp(void **state)
{
    fdi_deriv_coef_t c;
    fdi_deriv_t d;
    fdi_deriv_out_t o = {0.0f, 0.0f};
    const double s = 3.5;
    int k;
    (void)state;
    design(&c);
    assert_int_equal(fdi_deriv_reset(&d, 0.0f), FDI_OK);
    for (k = 1; k <= 200; ++k) /* 2 s = 63 time constants */
    {
        assert_int_equal(fdi_deriv_step(&d, &c, (float)(s * k * (double)DT), &o), FDI_OK);
    }
    assert_near(o.dy, s, 1e-4 * s);
    assert_near(o.y, s * 200.0 * (double)DT - (double)c.tau * s, 1e-4 * s);
}

/* Sine: after the transient the output equals the exact Tustin frequency response (float rounding only). */
static void test_sine_response(void **state)
{
    fdi_deriv_coef_t c;
    fdi_deriv_t d;
    fdi_deriv_out_t o = {0.0f, 0.0f};
    const double f = 1.0;
    const double w = 2.0 * TEST_PI * f;
    const double T = (double)DT;
    const double wc = (2.0 / T) * tan(TEST_PI * (double)FC * T); /* pre-warped */
    const double om = (2.0 / T) * tan(w * T / 2.0);              /* warped signal frequency */
    /* H(j om) = j om / (1 + j om / wc): gain and phase of the derivative */
    const double mag = om / sqrt(1.0 + (om / wc) * (om / wc));
    const double ph = TEST_PI / 2.0 - atan(om / wc);
    double max_err_exact = 0.0;
    double max_err_true = 0.0;
    int k;
    (void)state;
    design(&c);
    assert_int_equal(fdi_deriv_reset(&d, 0.0f), FDI_OK);
    for (k = 1; k <= 1000; ++k)
    {
        const double t = k * T;
        assert_int_equal(fdi_deriv_step(&d, &c, (float)sin(w * t), &o), FDI_OK);
        if (t > 1.0) /* transient e^(-t/tau), tau = 32 ms, gone */
        {
            const double exact = mag * sin(w * t + ph);
            const double truth = w * cos(w * t);
            max_err_exact = fmax(max_err_exact, fabs((double)o.dy - exact));
            max_err_true = fmax(max_err_true, fabs((double)o.dy - truth));
        }
    }
    /* against the exact discrete response: float rounding, 1e-4 of the amplitude w */
    assert_true(max_err_exact <= 1e-4 * w);
    /* against the true derivative: the filter's own error |H - j w| (1.2 % of w at f/fc = 0.2) + rounding */
    assert_true(max_err_true <= fabs(w - mag) + mag * fabs(ph - TEST_PI / 2.0) + 1e-4 * w);
    assert_true(max_err_true <= 0.25 * w);
}

/*
 * White noise of variance s2: the exact variance gains of the Tustin filters are (1 - a) / 2 for the
 * low-pass and 2 b^2 / (1 + a) for the derivative (sums of squared impulse responses). 2e5 samples give a
 * relative standard error of ~0.3 %; the tolerance is 3 %. The derivative must be far quieter than the
 * raw difference quotient (variance 2 s2 / dt^2).
 */
static void test_noise_attenuation(void **state)
{
    fdi_deriv_coef_t c;
    fdi_deriv_t d;
    fdi_deriv_out_t o = {0.0f, 0.0f};
    test_rng_t rng = {0x1234567ULL};
    const int n = 200000;
    double sy = 0.0;
    double sdy = 0.0;
    int k;
    (void)state;
    design(&c);
    assert_int_equal(fdi_deriv_reset(&d, 0.0f), FDI_OK);
    for (k = 0; k < n; ++k)
    {
        assert_int_equal(fdi_deriv_step(&d, &c, (float)test_normal(&rng), &o), FDI_OK);
        sy += (double)o.y * (double)o.y;
        sdy += (double)o.dy * (double)o.dy;
    }
    {
        const double a = (double)c.a;
        const double b = (double)c.b;
        const double vy = sy / n;
        const double vdy = sdy / n;
        const double gain_lp = (1.0 - a) / 2.0;
        const double gain_d = 2.0 * b * b / (1.0 + a);
        assert_near(vy / gain_lp, 1.0, 0.03);
        assert_near(vdy / gain_d, 1.0, 0.03);
        assert_true(vdy < 0.2 * 2.0 / ((double)DT * (double)DT));
        assert_true(vy < 0.2);
    }
}

/* 1e6 steps of a slow sine: no drift, still the exact response at the end. */
static void test_long_run(void **state)
{
    fdi_deriv_coef_t c;
    fdi_deriv_t d;
    fdi_deriv_out_t o = {0.0f, 0.0f};
    const double w = 2.0 * TEST_PI * 0.2;
    const double T = (double)DT;
    const double wc = (2.0 / T) * tan(TEST_PI * (double)FC * T);
    const double om = (2.0 / T) * tan(w * T / 2.0);
    const double mag = om / sqrt(1.0 + (om / wc) * (om / wc));
    const double ph = TEST_PI / 2.0 - atan(om / wc);
    double max_err = 0.0;
    long k;
    (void)state;
    design(&c);
    assert_int_equal(fdi_deriv_reset(&d, 0.0f), FDI_OK);
    for (k = 1; k <= 1000000L; ++k)
    {
        const double t = (double)k * T;
        assert_int_equal(fdi_deriv_step(&d, &c, (float)(10.0 * sin(w * t)), &o), FDI_OK);
        if (k > 999000L)
        {
            max_err = fmax(max_err, fabs((double)o.dy - 10.0 * mag * sin(w * t + ph)));
        }
    }
    assert_true(max_err <= 1e-4 * 10.0 * w);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_args),   cmocka_unit_test(test_non_finite),
        cmocka_unit_test(test_ramp),       cmocka_unit_test(test_sine_response),
        cmocka_unit_test(test_noise_attenuation), cmocka_unit_test(test_long_run),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
