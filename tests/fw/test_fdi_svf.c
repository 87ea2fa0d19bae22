/*
 * test_fdi_svf.c - second-order state-variable filter: arguments, non-finite inputs, constants and
 * ramps (exact), sines against the exact Tustin response and the true derivative, noise attenuation
 * against continuous-time theory, derivative of a derivative by chaining, 1e6-step run.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "fdi_svf.h"
#include "fdi_test_util.h"

#define DT 0.01f
#define FC 2.0f
#define ZETA 0.7071f

static void design(fdi_svf_coef_t *c)
{
    const fdi_svf_config_t cfg = {DT, FC, ZETA};
    assert_int_equal(fdi_svf_design(c, &cfg), FDI_OK);
}

/* Exact steady-state response of the discrete filter to sin(w t): x1 gain/phase and x2 = j*Om*x1. */
typedef struct
{
    double g1, p1, g2, p2;
} resp_t;

static resp_t response(double w)
{
    const double T = (double)DT;
    const double W = (2.0 / T) * tan(TEST_PI * (double)FC * T);
    const double om = (2.0 / T) * tan(w * T / 2.0);
    const double re = W * W - om * om;
    const double im = 2.0 * (double)ZETA * W * om;
    resp_t r;
    r.g1 = W * W / sqrt(re * re + im * im);
    r.p1 = -atan2(im, re);
    r.g2 = r.g1 * om;
    r.p2 = r.p1 + TEST_PI / 2.0;
    return r;
}

static void test_bad_args(void **state)
{
    fdi_svf_coef_t c;
    fdi_svf_t s;
    fdi_svf_out_t o;
    const fdi_svf_config_t nyq = {0.01f, 60.0f, ZETA};
    const fdi_svf_config_t dt0 = {0.0f, 2.0f, ZETA};
    const fdi_svf_config_t z_low = {0.01f, 2.0f, 0.01f};
    const fdi_svf_config_t z_high = {0.01f, 2.0f, 5.0f};
    const fdi_svf_config_t z_nan = {0.01f, 2.0f, NAN};
    const fdi_svf_config_t fc_nan = {0.01f, NAN, ZETA};
    (void)state;
    assert_int_equal(fdi_svf_design(NULL, &nyq), FDI_BAD_ARG);
    assert_int_equal(fdi_svf_design(&c, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_svf_design(&c, &nyq), FDI_BAD_ARG);
    assert_int_equal(fdi_svf_design(&c, &dt0), FDI_BAD_ARG);
    assert_int_equal(fdi_svf_design(&c, &z_low), FDI_BAD_ARG);
    assert_int_equal(fdi_svf_design(&c, &z_high), FDI_BAD_ARG);
    assert_int_equal(fdi_svf_design(&c, &z_nan), FDI_NOT_FINITE);
    assert_int_equal(fdi_svf_design(&c, &fc_nan), FDI_NOT_FINITE);
    design(&c);
    assert_int_equal(fdi_svf_reset(NULL, 0.0f), FDI_BAD_ARG);
    assert_int_equal(fdi_svf_reset(&s, INFINITY), FDI_NOT_FINITE);
    assert_int_equal(fdi_svf_reset(&s, 0.0f), FDI_OK);
    assert_int_equal(fdi_svf_step(NULL, &c, 0.0f, &o), FDI_BAD_ARG);
    assert_int_equal(fdi_svf_step(&s, NULL, 0.0f, &o), FDI_BAD_ARG);
    assert_int_equal(fdi_svf_step(&s, &c, 0.0f, NULL), FDI_BAD_ARG);
}

static void test_non_finite(void **state)
{
    fdi_svf_coef_t c;
    fdi_svf_t s;
    fdi_svf_out_t o = {7.0f, 8.0f};
    (void)state;
    design(&c);
    assert_int_equal(fdi_svf_reset(&s, -4.0f), FDI_OK);
    assert_int_equal(fdi_svf_step(&s, &c, NAN, &o), FDI_NOT_FINITE);
    assert_int_equal(fdi_svf_step(&s, &c, -INFINITY, &o), FDI_NOT_FINITE);
    assert_near(o.y, 7.0, 0.0);
    assert_near(o.dy, 8.0, 0.0);
    assert_int_equal(fdi_svf_step(&s, &c, -4.0f, &o), FDI_OK);
    assert_near(o.y, -4.0, 0.0);
    assert_near(o.dy, 0.0, 0.0);
    assert_int_equal(fdi_svf_reset(&s, -3.0e38f), FDI_OK);
    assert_int_equal(fdi_svf_step(&s, &c, 3.0e38f, &o), FDI_NOT_FINITE); /* u - x1 overflows */
    assert_int_equal(fdi_svf_step(&s, &c, -3.0e38f, &o), FDI_OK);     /* state was kept */
    assert_near(o.y, (double)-3.0e38f, 0.0);
    assert_int_equal(fdi_svf_reset(&s, -4.0f), FDI_OK);
    assert_int_equal(fdi_svf_step(&s, &c, -4.0f, &o), FDI_OK);
    assert_near(o.y, -4.0, 0.0);
    assert_near(o.dy, 0.0, 0.0);
}

/* Ramp: x2 -> slope exactly (up to rounding), x1 lags by 2 zeta / W * slope. Constant: exact. */
static void test_ramp_and_constant(void **state)
{
    fdi_svf_coef_t c;
    fdi_svf_t s;
    fdi_svf_out_t o = {0.0f, 0.0f};
    const double slope = -2.5;
    const double W = (2.0 / (double)DT) * tan(TEST_PI * (double)FC * (double)DT);
    int k;
    (void)state;
    design(&c);
    assert_int_equal(fdi_svf_reset(&s, 20.0f), FDI_OK);
    for (k = 0; k < 100000; ++k)
    {
        assert_int_equal(fdi_svf_step(&s, &c, 20.0f, &o), FDI_OK);
    }
    assert_near(o.y, 20.0, 0.0);
    assert_near(o.dy, 0.0, 0.0);
    assert_int_equal(fdi_svf_reset(&s, 0.0f), FDI_OK);
    for (k = 1; k <= 500; ++k) /* 5 s = 39 time constants 1 / (zeta W) */
    {
        assert_int_equal(fdi_svf_step(&s, &c, (float)(slope * k * (double)DT), &o), FDI_OK);
    }
    assert_near(o.dy, slope, 1e-4 * fabs(slope));
    assert_near(o.y, slope * 5.0 - 2.0 * (double)ZETA / W * slope, 1e-4 * fabs(slope) * 5.0);
}

static void check_sine(double f, double amp)
{
    fdi_svf_coef_t c;
    fdi_svf_t s;
    fdi_svf_out_t o = {0.0f, 0.0f};
    const double w = 2.0 * TEST_PI * f;
    const resp_t r = response(w);
    double e1 = 0.0;
    double e2 = 0.0;
    double e_true = 0.0;
    int k;
    design(&c);
    assert_int_equal(fdi_svf_reset(&s, 0.0f), FDI_OK);
    for (k = 1; k <= 1500; ++k)
    {
        const double t = k * (double)DT;
        assert_int_equal(fdi_svf_step(&s, &c, (float)(amp * sin(w * t)), &o), FDI_OK);
        if (t > 5.0)
        {
            e1 = fmax(e1, fabs((double)o.y - amp * r.g1 * sin(w * t + r.p1)));
            e2 = fmax(e2, fabs((double)o.dy - amp * r.g2 * sin(w * t + r.p2)));
            e_true = fmax(e_true, fabs((double)o.dy - amp * w * cos(w * t)));
        }
    }
    /* exact discrete response: float rounding, 1e-4 of the amplitudes */
    assert_true(e1 <= 1e-4 * amp);
    assert_true(e2 <= 1e-4 * amp * w);
    /* true derivative: bounded by the filter's own error |H2(jw) - jw| * amp + rounding */
    {
        const double re = r.g2 * cos(r.p2) - 0.0;
        const double im = r.g2 * sin(r.p2) - w;
        assert_true(e_true <= amp * sqrt(re * re + im * im) + 1e-4 * amp * w);
    }
}

/* Sines well below, near and above the cut-off. */
static void test_sines(void **state)
{
    (void)state;
    check_sine(0.1, 3.0);
    check_sine(1.0, 1.0);
    check_sine(2.0, 1.0);
    check_sine(10.0, 0.5);
}

/* At f / fc = 0.05 the filtered derivative is within 8 % of the true derivative (delay 2 zeta / W). */
static void test_slow_sine_close_to_truth(void **state)
{
    fdi_svf_coef_t c;
    fdi_svf_t s;
    fdi_svf_out_t o = {0.0f, 0.0f};
    const double w = 2.0 * TEST_PI * 0.1;
    const double delay = 2.0 * (double)ZETA / (2.0 * TEST_PI * (double)FC);
    double e_true = 0.0;
    double e_delayed = 0.0;
    int k;
    (void)state;
    design(&c);
    assert_int_equal(fdi_svf_reset(&s, 0.0f), FDI_OK);
    for (k = 1; k <= 3000; ++k)
    {
        const double t = k * (double)DT;
        assert_int_equal(fdi_svf_step(&s, &c, (float)sin(w * t), &o), FDI_OK);
        if (t > 5.0)
        {
            e_true = fmax(e_true, fabs((double)o.dy - w * cos(w * t)));
            e_delayed = fmax(e_delayed, fabs((double)o.dy - w * cos(w * (t - delay))));
        }
    }
    assert_true(e_true <= 0.08 * w);
    assert_true(e_delayed <= 0.005 * w); /* the error is almost all the pure delay the generators match */
}

/* Parseval: variance gain = (dt / pi) * integral over (0, pi/dt) of |H(e^{jw dt})|^2 dw (Simpson). */
static void noise_gains(double *g1, double *g2)
{
    const int n = 20000;
    const double top = TEST_PI / (double)DT * (1.0 - 1e-9);
    const double hstep = top / n;
    double a1 = 0.0;
    double a2 = 0.0;
    int i;
    for (i = 0; i <= n; ++i)
    {
        const resp_t r = response(i * hstep);
        const double wgt = (i == 0 || i == n) ? 1.0 : ((i % 2) ? 4.0 : 2.0);
        a1 += wgt * r.g1 * r.g1;
        a2 += wgt * r.g2 * r.g2;
    }
    *g1 = (double)DT / TEST_PI * a1 * hstep / 3.0;
    *g2 = (double)DT / TEST_PI * a2 * hstep / 3.0;
}

/*
 * White noise, variance 1: output variances equal the Parseval integrals of the exact discrete response
 * (continuous theory dt W / (4 zeta), dt W^3 / (4 zeta) as a cross-check within 10 %: Tustin compresses the
 * high-frequency tail). Tolerance 3 % (sampling error of 4e5 correlated samples ~1 %).
 */
static void test_noise_attenuation(void **state)
{
    fdi_svf_coef_t c;
    fdi_svf_t s;
    fdi_svf_out_t o = {0.0f, 0.0f};
    test_rng_t rng = {987654321ULL};
    const int n = 400000;
    const double W = (2.0 / (double)DT) * tan(TEST_PI * (double)FC * (double)DT);
    double s1 = 0.0;
    double s2 = 0.0;
    int k;
    (void)state;
    design(&c);
    assert_int_equal(fdi_svf_reset(&s, 0.0f), FDI_OK);
    for (k = 0; k < n; ++k)
    {
        assert_int_equal(fdi_svf_step(&s, &c, (float)test_normal(&rng), &o), FDI_OK);
        s1 += (double)o.y * (double)o.y;
        s2 += (double)o.dy * (double)o.dy;
    }
    {
        double g1 = 0.0;
        double g2 = 0.0;
        noise_gains(&g1, &g2);
        assert_near((s1 / n) / g1, 1.0, 0.03);
        assert_near((s2 / n) / g2, 1.0, 0.03);
        assert_near(g1 / ((double)DT * W / (4.0 * (double)ZETA)), 1.0, 0.10);
        assert_near(g2 / ((double)DT * W * W * W / (4.0 * (double)ZETA)), 1.0, 0.10);
    }
    /* far below the raw difference quotient's 2 / dt^2 = 20000 */
    assert_true(s2 / n < 0.01 * 2.0 / ((double)DT * (double)DT));
}

/* Chained filters give d/dt of a derivative: u = sin -> d2/dt2 = -w^2 sin (through two delays). */
static void test_second_derivative_by_chaining(void **state)
{
    fdi_svf_coef_t c;
    fdi_svf_t s1;
    fdi_svf_t s2;
    fdi_svf_out_t o1 = {0.0f, 0.0f};
    fdi_svf_out_t o2 = {0.0f, 0.0f};
    const double w = 2.0 * TEST_PI * 0.1;
    const resp_t r = response(w);
    double e = 0.0;
    int k;
    (void)state;
    design(&c);
    assert_int_equal(fdi_svf_reset(&s1, 0.0f), FDI_OK);
    assert_int_equal(fdi_svf_reset(&s2, 0.0f), FDI_OK);
    for (k = 1; k <= 3000; ++k)
    {
        const double t = k * (double)DT;
        assert_int_equal(fdi_svf_step(&s1, &c, (float)sin(w * t), &o1), FDI_OK);
        assert_int_equal(fdi_svf_step(&s2, &c, o1.dy, &o2), FDI_OK);
        if (t > 10.0)
        {
            /* two filters in series: x2 of x2 has the response (j Om H)^2 */
            const double exact = r.g2 * r.g2 * sin(w * t + r.p2 + r.p2);
            e = fmax(e, fabs((double)o2.dy - exact));
        }
    }
    assert_true(e <= 1e-4 * w * w + 1e-5);
}

/* 1e6 steps: a slow sine on a large offset stays on the exact response (no drift of x1 accumulation). */
static void test_long_run(void **state)
{
    fdi_svf_coef_t c;
    fdi_svf_t s;
    fdi_svf_out_t o = {0.0f, 0.0f};
    const double w = 2.0 * TEST_PI * 0.05;
    const resp_t r = response(w);
    double e1 = 0.0;
    double e2 = 0.0;
    long k;
    (void)state;
    design(&c);
    assert_int_equal(fdi_svf_reset(&s, 30.0f), FDI_OK);
    for (k = 1; k <= 1000000L; ++k)
    {
        const double t = (double)k * (double)DT;
        assert_int_equal(fdi_svf_step(&s, &c, (float)(30.0 + 2.0 * sin(w * t)), &o), FDI_OK);
        if (k > 990000L)
        {
            e1 = fmax(e1, fabs((double)o.y - (30.0 + 2.0 * r.g1 * sin(w * t + r.p1))));
            e2 = fmax(e2, fabs((double)o.dy - 2.0 * r.g2 * sin(w * t + r.p2)));
        }
    }
    assert_true(e1 <= 1e-4 * 30.0);
    assert_true(e2 <= 2e-3 * 2.0 * w);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_args),
        cmocka_unit_test(test_non_finite),
        cmocka_unit_test(test_ramp_and_constant),
        cmocka_unit_test(test_sines),
        cmocka_unit_test(test_slow_sine_close_to_truth),
        cmocka_unit_test(test_noise_attenuation),
        cmocka_unit_test(test_second_derivative_by_chaining),
        cmocka_unit_test(test_long_run),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
