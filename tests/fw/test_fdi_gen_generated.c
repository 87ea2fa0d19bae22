/*
 * test_fdi_gen_generated.c - generated residual generators (fw/generated/fdi_romo_generators.c) through the
 * fdi_gen dispatch: slots and input masks, unlinked slots rejected by fdi_gen_init and fdi_table_check,
 * non-finite inputs, the exported table accepted, and the generated MSO3 generator equal to -r3 of the
 * hand-written FDI_GEN_KIN_ARR3 on the analytic reference vehicle (same filters, same relation times w^2),
 * and the operating domain: a tyre-law test is "not evaluable" in fdi_diag below its minimum speed and
 * restarts with a warm-up when the speed returns, while the kinematic tests stay evaluable; the observer
 * building blocks (fdi_gen_obs_predict/store, heaviside, sign) against the exact solution of x' = J x + b.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

#include <cmocka.h>

#include "fdi_diag.h"
#include "fdi_float.h"
#include "fdi_gen.h"
#include "fdi_romo_table.h"
#include "fdi_table.h"
#include "fdi_test_util.h"
#include "../../fw/src/fdi_gen_internal.h" /* observer building blocks of the generated generators */

#define DT 0.01

static void params(fdi_gen_param_t *p)
{
    const fdi_gen_config_t cfg = {(float)DT, 1.0f, 0.7071f, 2.0f, (float)VEH_DX, (float)VEH_DY};
    assert_int_equal(fdi_gen_param_init(p, &cfg), FDI_OK);
}

static void test_slots_and_inputs(void **state)
{
    uint32_t i;
    (void)state;
    for (i = 0U; i < (uint32_t)fdi_romo_table.n_tests; ++i)
    {
        const fdi_test_desc_t *d = &fdi_romo_table.tests[i];
        assert_int_equal((int)d->kind, (int)FDI_GEN_GENERATED_1 + (int)i);
        assert_true(fdi_gen_inputs(d->kind) != 0U);
        assert_int_equal(fdi_gen_inputs(d->kind), fdi_gen_generated_inputs(i));
        assert_int_equal(d->input_mask & fdi_gen_inputs(d->kind), fdi_gen_inputs(d->kind));
    }
    assert_int_equal(fdi_gen_generated_inputs(FDI_GEN_GENERATED_MAX - 1U), 0U);
    assert_int_equal(fdi_gen_inputs(FDI_GEN_GENERATED_16), 0U);
    assert_int_equal(fdi_table_check(&fdi_romo_table), FDI_OK);
}

static void test_unlinked_and_bad_inputs(void **state)
{
    fdi_gen_param_t p;
    fdi_gen_t g;
    fdi_inputs_t in;
    float r = 0.0f;
    veh_meas_cfg_t mc = {{0.0, 0.0, 0.0, 0.0, 0.0}, {0.0, 0.0, 0.0, 0.0, 0.0}};
    test_rng_t rng = {1ULL};
    fdi_test_desc_t tests_copy[FDI_TABLE_MAX_TESTS];
    fdi_table_t t = fdi_romo_table;
    uint32_t i;
    (void)state;
    params(&p);
    assert_int_equal(fdi_gen_init(&g, FDI_GEN_GENERATED_16), FDI_BAD_ARG);
    assert_int_equal(fdi_gen_generated_step(FDI_GEN_GENERATED_MAX, &g, &p, &in, false, &r), FDI_BAD_ARG);
    memcpy(tests_copy, fdi_romo_table.tests, sizeof(fdi_test_desc_t) * fdi_romo_table.n_tests);
    t.tests = tests_copy;
    tests_copy[0].kind = FDI_GEN_GENERATED_16; /* no generator linked in that slot */
    assert_int_equal(fdi_table_check(&t), FDI_BAD_TABLE);
    for (i = 0U; i < (uint32_t)fdi_romo_table.n_tests; ++i)
    {
        veh_measure(1.0, &mc, &rng, &in);
        in.iTM1_m = 10.0f;
        in.iTM2_m = 10.0f;
        in.iTM3_m = 10.0f;
        in.iTM4_m = 10.0f;
        in.omega1_m = 37.0f;
        in.omega2_m = 37.0f;
        in.omega3_m = 37.0f;
        in.omega4_m = 37.0f;
        in.P_f_m = 0.0f;
        in.P_r_m = 0.0f;
        in.delta1_m = 0.0f;
        in.delta2_m = 0.0f;
        in.delta3_m = 0.0f;
        in.delta4_m = 0.0f;
        assert_int_equal(fdi_gen_init(&g, fdi_romo_table.tests[i].kind), FDI_OK);
        assert_int_equal(fdi_gen_reset(&g, &p, &in), FDI_OK);
        assert_int_equal(fdi_gen_step(&g, &p, &in, &r), FDI_OK);
        assert_true(fdi_float_is_finite(r));
        in.psidot_m = NAN;
        in.omega1_m = INFINITY;
        in.omega2_m = INFINITY;
        in.omega3_m = INFINITY;
        in.omega4_m = INFINITY;
        assert_int_equal(fdi_gen_step(&g, &p, &in, &r), FDI_NOT_FINITE);
    }
}

/* The test of the table whose MSO is Table II's MSO3 (equations K1 K2 D1 D2 S1 S2 S3 S4), -1 if none. */
static int arr3_test(void)
{
    int found = -1;
    uint32_t i;
    for (i = 0U; i < (uint32_t)fdi_romo_table.n_tests; ++i)
    {
        if (strcmp(fdi_romo_table_equations[i], "K1 K2 D1 D2 S1 S2 S3 S4") == 0)
        {
            found = (int)i;
        }
    }
    return found;
}

static void test_generated_mso3_equals_handwritten_arr3(void **state)
{
    fdi_gen_param_t p;
    fdi_gen_t gen;
    fdi_gen_t hand;
    fdi_inputs_t in;
    veh_meas_cfg_t mc = {{0.0, 0.0, 0.0, 0.0, 0.0}, {0.0, 0.0, 0.0, 0.0, 0.0}};
    test_rng_t rng = {7ULL};
    const int k = arr3_test();
    double worst = 0.0;
    double scale = 0.0;
    int n;
    (void)state;
    if (k < 0)
    {
        skip(); /* MSO3 not in the current selection */
    }
    params(&p);
    assert_int_equal(fdi_gen_init(&gen, fdi_romo_table.tests[k].kind), FDI_OK);
    assert_int_equal(fdi_gen_init(&hand, FDI_GEN_KIN_ARR3), FDI_OK);
    veh_measure(0.0, &mc, &rng, &in);
    assert_int_equal(fdi_gen_reset(&gen, &p, &in), FDI_OK);
    assert_int_equal(fdi_gen_reset(&hand, &p, &in), FDI_OK);
    for (n = 1; n < 3000; ++n)
    {
        float rg = 0.0f;
        float rh = 0.0f;
        veh_measure((double)n * DT, &mc, &rng, &in);
        if (n == 1500)
        {
            mc.f[3] = 0.5; /* f4: vx sensor offset, the residuals must move together */
        }
        assert_int_equal(fdi_gen_step(&gen, &p, &in, &rg), FDI_OK);
        assert_int_equal(fdi_gen_step(&hand, &p, &in, &rh), FDI_OK);
        if (fabs((double)rh) > scale)
        {
            scale = fabs((double)rh);
        }
        if (fabs((double)rg + (double)rh) > worst)
        {
            worst = fabs((double)rg + (double)rh);
        }
    }
    print_message("generated MSO3 vs FDI_GEN_KIN_ARR3: max |r_gen + r3| = %.3g, max |r3| = %.3g\n", worst, scale);
    assert_true(scale > 0.0);
    assert_true(worst < 1e-3 * scale);
}

static void frame(fdi_inputs_t *in, float vx)
{
    veh_meas_cfg_t mc = {{0.0, 0.0, 0.0, 0.0, 0.0}, {0.0, 0.0, 0.0, 0.0, 0.0}};
    test_rng_t rng = {3ULL};
    veh_measure(1.0, &mc, &rng, in);
    in->iTM1_m = 0.0f;
    in->iTM2_m = 0.0f;
    in->iTM3_m = 0.0f;
    in->iTM4_m = 0.0f;
    in->P_f_m = 0.0f;
    in->P_r_m = 0.0f;
    in->delta1_m = 0.0f;
    in->delta2_m = 0.0f;
    in->delta3_m = 0.0f;
    in->delta4_m = 0.0f;
    in->psidot_m = 0.0f;
    in->ax_m = 0.0f;
    in->ay_m = 0.0f;
    in->vy_m = 0.0f;
    in->vx_m = vx;
    in->omega1_m = vx / 0.27f;
    in->omega2_m = vx / 0.27f;
    in->omega3_m = vx / 0.27f;
    in->omega4_m = vx / 0.27f;
}

/* Bitmask of the table's tests whose generator is outside its operating domain at frame `in`. */
static uint32_t out_of_domain(const fdi_inputs_t *in)
{
    uint32_t m = 0U;
    uint32_t i;
    for (i = 0U; i < (uint32_t)fdi_romo_table.n_tests; ++i)
    {
        m |= fdi_gen_in_domain(fdi_romo_table.tests[i].kind, in) ? 0U : ((uint32_t)1U << i);
    }
    return m;
}

static void test_operating_domain(void **state)
{
    fdi_inputs_t in;
    fdi_diag_t d;
    fdi_diag_result_t res;
    const fdi_diag_config_t cfg = {&fdi_romo_table, (float)VEH_DX, (float)VEH_DY, 1.5f, 150.0f, 1U, 1U, 300U,
                                   FDI_ISO_EXONERATION, 0U, 1U};
    const uint32_t all = ((uint32_t)1U << fdi_romo_table.n_tests) - 1U;
    uint32_t low;
    int n;
    (void)state;
    frame(&in, 0.5f);
    low = out_of_domain(&in);
    assert_true(low != 0U);   /* the tyre-law tests need speed */
    assert_true(low != all);  /* the kinematic ones do not */
    assert_false(fdi_gen_in_domain(fdi_romo_table.tests[0].kind, NULL));
    assert_true(fdi_gen_in_domain(FDI_GEN_KIN_ARR3, &in)); /* hand-written kinds: always */
    in.vx_m = -0.5f;
    assert_int_equal(out_of_domain(&in), low);
    in.vx_m = NAN;
    assert_int_equal(out_of_domain(&in), low); /* a non-finite domain signal is outside */
    frame(&in, 20.0f);
    assert_int_equal(out_of_domain(&in), 0U);
    in.vx_m = -20.0f; /* reversing: |vx| counts */
    assert_int_equal(out_of_domain(&in), 0U);

    assert_int_equal(fdi_diag_init(&d, &cfg), FDI_OK);
    frame(&in, 20.0f);
    for (n = 0; n < 301; ++n)
    {
        assert_int_equal(fdi_diag_step(&d, &in, FDI_SIGM_ALL), FDI_OK);
    }
    assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
    assert_int_equal(res.evaluable_mask, all);
    frame(&in, 0.5f);
    assert_int_equal(fdi_diag_step(&d, &in, FDI_SIGM_ALL), FDI_OK);
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
    for (n = 0; n < 300; ++n)
    {
        assert_int_equal(fdi_diag_step(&d, &in, FDI_SIGM_ALL), FDI_OK);
        assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
        assert_int_equal(res.evaluable_mask & low, 0U);
    }
    assert_int_equal(fdi_diag_step(&d, &in, FDI_SIGM_ALL), FDI_OK);
    assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
    assert_int_equal(res.evaluable_mask, all);
}

static void test_observer_building_blocks(void **state)
{
    /* x' = J x + b with constant b: one predict step is the exact exp(J dt) solution, for a slow, a stiff
     * (J dt = -4, where forward Euler diverges) and a zero pole (then phi = dt) */
    const float poles[3] = {-12.566f, -400.0f, 0.0f};
    const float b = 3.0f;
    fdi_gen_param_t p;
    fdi_gen_t g;
    uint32_t i;
    (void)state;
    params(&p);
    assert_int_equal(fdi_gen_init(&g, FDI_GEN_KIN_X_DERIV), FDI_OK);
    for (i = 0U; i < 3U; ++i)
    {
        const double jac = (double)poles[i];
        double x = 2.0;
        int n;
        g.obs.xh = 2.0f;
        g.obs.g_prev = (poles[i] * 2.0f) + b;
        for (n = 0; n < 50; ++n)
        {
            const float g1 = (poles[i] * g.obs.xh) + b;
            const float xh = fdi_gen_obs_predict(&g, &p, g1, poles[i]);
            const double e = exp(jac * DT);
            x = (fabs(jac) > 0.0) ? ((e * x) + (((e - 1.0) / jac) * (double)b)) : (x + (DT * (double)b));
            assert_true(fabs((double)xh - x) < (1e-4 * (1.0 + fabs(x))));
            assert_int_equal(fdi_gen_obs_store(&g, xh, (poles[i] * xh) + b), FDI_OK);
        }
    }
    assert_true(fabs((double)fdi_gen_obs_predict(NULL, &p, 1.0f, -1.0f) - (double)0.0f) <= 0.0);
    assert_true(fabs((double)fdi_gen_obs_predict(&g, NULL, 1.0f, -1.0f) - (double)0.0f) <= 0.0);
    g.obs.xh = 1.0f;
    assert_int_equal(fdi_gen_obs_store(&g, NAN, 0.0f), FDI_NOT_FINITE);
    assert_int_equal(fdi_gen_obs_store(&g, 0.0f, INFINITY), FDI_NOT_FINITE);
    assert_true(fabs((double)g.obs.xh - (double)1.0f) <= 0.0); /* nothing stored */
    assert_int_equal(fdi_gen_obs_store(NULL, 0.0f, 0.0f), FDI_BAD_ARG);
    assert_true(fabs((double)fdi_gen_heaviside(0.5f) - (double)1.0f) <= 0.0);
    assert_true(fabs((double)fdi_gen_heaviside(0.0f) - (double)0.0f) <= 0.0);
    assert_true(fabs((double)fdi_gen_heaviside(-2.0f) - (double)0.0f) <= 0.0);
    assert_true(fabs((double)fdi_gen_sign(-3.0f) - (double)-1.0f) <= 0.0);
    assert_true(fabs((double)fdi_gen_sign(0.0f) - (double)0.0f) <= 0.0);
    assert_true(fabs((double)fdi_gen_sign(7.0f) - (double)1.0f) <= 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_slots_and_inputs),
        cmocka_unit_test(test_unlinked_and_bad_inputs),
        cmocka_unit_test(test_generated_mso3_equals_handwritten_arr3),
        cmocka_unit_test(test_operating_domain),
        cmocka_unit_test(test_observer_building_blocks),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
