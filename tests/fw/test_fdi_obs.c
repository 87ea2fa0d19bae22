/*
 * test_fdi_obs.c - constant-gain scalar observer: arguments, non-finite inputs, zero residual on an exact
 * first-order system, analytic decay of an initial error, analytic steady residual of an input fault,
 * 1e6-step stability.
 *
 * Reference system x' = a x + b sin(w t), x(0) on the periodic solution:
 *   x(t) = A sin(w t) + B cos(w t),  A = -a b / (w^2 + a^2),  B = -b w / (w^2 + a^2).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "fdi_obs.h"
#include "fdi_test_util.h"

#define DT 0.01
#define A_SYS (-0.5)
#define B_SYS 2.0
#define W_IN 1.3
#define GAIN 3.0

static double x_exact(double t)
{
    const double den = W_IN * W_IN + A_SYS * A_SYS;
    return (-A_SYS * B_SYS / den) * sin(W_IN * t) + (-B_SYS * W_IN / den) * cos(W_IN * t);
}

static void design(fdi_obs_coef_t *c)
{
    const fdi_obs_config_t cfg = {(float)DT, (float)A_SYS, (float)GAIN};
    assert_int_equal(fdi_obs_design(c, &cfg), FDI_OK);
}

static void test_bad_args(void **state)
{
    fdi_obs_coef_t c;
    fdi_obs_t o;
    float r = 0.0f;
    const fdi_obs_config_t unstable = {0.01f, 1.0f, 0.5f}; /* a - L = +0.5 */
    const fdi_obs_config_t marginal = {0.01f, 0.0f, 0.0f}; /* a - L = 0: open loop, drifts */
    const fdi_obs_config_t dt_neg = {-0.01f, 0.0f, 1.0f};
    const fdi_obs_config_t gain_nan = {0.01f, 0.0f, NAN};
    (void)state;
    assert_int_equal(fdi_obs_design(NULL, &unstable), FDI_BAD_ARG);
    assert_int_equal(fdi_obs_design(&c, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_obs_design(&c, &unstable), FDI_BAD_ARG);
    assert_int_equal(fdi_obs_design(&c, &marginal), FDI_BAD_ARG);
    assert_int_equal(fdi_obs_design(&c, &dt_neg), FDI_BAD_ARG);
    assert_int_equal(fdi_obs_design(&c, &gain_nan), FDI_NOT_FINITE);
    design(&c);
    assert_int_equal(fdi_obs_reset(NULL, &c, 0.0f, 0.0f), FDI_BAD_ARG);
    assert_int_equal(fdi_obs_reset(&o, NULL, 0.0f, 0.0f), FDI_BAD_ARG);
    assert_int_equal(fdi_obs_reset(&o, &c, NAN, 0.0f), FDI_NOT_FINITE);
    assert_int_equal(fdi_obs_reset(&o, &c, 0.0f, INFINITY), FDI_NOT_FINITE);
    assert_int_equal(fdi_obs_reset(&o, &c, 0.0f, 1.0f), FDI_OK);
    assert_int_equal(fdi_obs_step(NULL, &c, 0.0f, 1.0f, &r), FDI_BAD_ARG);
    assert_int_equal(fdi_obs_step(&o, NULL, 0.0f, 1.0f, &r), FDI_BAD_ARG);
    assert_int_equal(fdi_obs_step(&o, &c, 0.0f, 1.0f, NULL), FDI_BAD_ARG);
}

static void test_non_finite(void **state)
{
    fdi_obs_coef_t c;
    fdi_obs_t o;
    float r = 42.0f;
    (void)state;
    design(&c);
    assert_int_equal(fdi_obs_reset(&o, &c, 0.0f, 1.0f), FDI_OK);
    assert_int_equal(fdi_obs_step(&o, &c, NAN, 1.0f, &r), FDI_NOT_FINITE);
    assert_int_equal(fdi_obs_step(&o, &c, 0.0f, -INFINITY, &r), FDI_NOT_FINITE);
    assert_near(r, 42.0, 0.0);
    assert_near(o.xh, 1.0, 0.0);
    /* consistent continuation from rest (x' = a x = -0.5 with f = 0.5 keeps x = 1): residual 0 */
    assert_int_equal(fdi_obs_reset(&o, &c, 0.5f, 1.0f), FDI_OK);
    assert_int_equal(fdi_obs_step(&o, &c, 0.5f, 1.0f, &r), FDI_OK);
    assert_near(r, 0.0, 1e-6);
}

/* Exact first-order system: residual stays below 1e-4 of the state amplitude. */
static void run_consistent(long steps, double tol)
{
    fdi_obs_coef_t c;
    fdi_obs_t o;
    float r = 0.0f;
    double max_r = 0.0;
    long k;
    design(&c);
    assert_int_equal(fdi_obs_reset(&o, &c, (float)(B_SYS * sin(0.0)), (float)x_exact(0.0)), FDI_OK);
    for (k = 1; k <= steps; ++k)
    {
        const double t = (double)k * DT;
        assert_int_equal(fdi_obs_step(&o, &c, (float)(B_SYS * sin(W_IN * t)), (float)x_exact(t), &r), FDI_OK);
        max_r = fmax(max_r, fabs((double)r));
    }
    if (!(max_r <= tol)) { print_error("max_r %g tol %g\n", max_r, tol); }
    assert_true(max_r <= tol);
}

static void test_consistent_zero_residual(void **state)
{
    (void)state;
    run_consistent(2000L, 1e-4 * 1.44); /* 1e-4 of the amplitude |x| = b / sqrt(w^2 + a^2) = 1.44 */
}

/* An initial estimate error e0 decays as e0 * exp((a - L) t), the rate fixed by the gain. */
static void test_initial_error_decay(void **state)
{
    fdi_obs_coef_t c;
    fdi_obs_t o;
    float r = 0.0f;
    const double lambda = A_SYS - GAIN;
    int k;
    (void)state;
    design(&c);
    assert_int_equal(fdi_obs_reset(&o, &c, 0.0f, (float)x_exact(0.0)), FDI_OK);
    o.xh += 1.0f; /* white-box: the estimate starts 1 too high */
    for (k = 1; k <= 200; ++k)
    {
        const double t = k * DT;
        assert_int_equal(fdi_obs_step(&o, &c, (float)(B_SYS * sin(W_IN * t)), (float)x_exact(t), &r), FDI_OK);
        if ((k == 50) || (k == 100) || (k == 200))
        {
            assert_near(r, -exp(lambda * t), 2e-4);
        }
    }
}

/* An additive input fault F (true x' = a x + b u + F) gives the steady residual F / (L - a). */
static void test_input_fault_steady_residual(void **state)
{
    fdi_obs_coef_t c;
    fdi_obs_t o;
    float r = 0.0f;
    const double F = 0.7;
    double x = 0.0;
    int k;
    (void)state;
    design(&c);
    assert_int_equal(fdi_obs_reset(&o, &c, 0.0f, 0.0f), FDI_OK);
    for (k = 1; k <= 1000; ++k) /* constant input u = 0: x' = a x + F, x(0) = 0, exact */
    {
        const double t = k * DT;
        x = (F / -A_SYS) * (1.0 - exp(A_SYS * t));
        assert_int_equal(fdi_obs_step(&o, &c, 0.0f, (float)x, &r), FDI_OK);
    }
    /* after 10 s the error pole (3.5/s) has settled but x itself still moves (pole 0.5/s): the residual
       obeys e' = (a - L) e + F exactly, so e = F/(L - a) (1 - exp((a - L) t)) */
    assert_near(r, F / (GAIN - A_SYS) * (1.0 - exp((A_SYS - GAIN) * 10.0)), 1e-3 * F);
}

static void test_long_run(void **state)
{
    (void)state;
    run_consistent(1000000L, 1e-4 * 1.44);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_args),
        cmocka_unit_test(test_non_finite),
        cmocka_unit_test(test_consistent_zero_residual),
        cmocka_unit_test(test_initial_error_decay),
        cmocka_unit_test(test_input_fault_steady_residual),
        cmocka_unit_test(test_long_run),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
