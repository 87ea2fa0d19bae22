/*
 * test_fdi_gen_generated.c - the generated residual generators of the ROMO target
 * (fw/vehicles/romo/generated/fdi_romo_generators.c) through their descriptors: descriptors and input masks,
 * bad descriptors rejected by fdi_gen_init and fdi_table_check, non-finite inputs, the exported table accepted,
 * the sensitivities (finite, zero cost when not requested: the residual is the same), and the generated MSO3
 * generator equal to -r3 of the hand-written fdi_romo_kin_arr3 on the analytic reference vehicle (same filters,
 * same relation times w^2),
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
#include "fdi_gen_impl.h" /* observer building blocks of the generated generators */
#include "fdi_romo_generators.h"
#include "fdi_romo_kin.h"
#include "fdi_romo_table.h"
#include "fdi_table.h"
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
    (void)state;
    assert_int_equal((uint32_t)fdi_romo_table.n_tests, FDI_ROMO_N_GENERATORS);
    for (i = 0U; i < (uint32_t)fdi_romo_table.n_tests; ++i)
    {
        const fdi_test_desc_t *d = &fdi_romo_table.tests[i];
        assert_ptr_equal(d->gen, &fdi_romo_generators[i]);
        assert_int_equal(fdi_gen_desc_check(d->gen), FDI_OK);
        assert_true(d->gen->input_mask != 0U);
        assert_int_equal(d->input_mask & d->gen->input_mask, d->gen->input_mask);
        assert_int_equal(d->gen->sens_mask & ~d->fault_mask, 0U); /* sensitivities within the signature */
        assert_true(d->gen->n_filters <= FDI_GEN_MAX_FILTERS);
    }
    assert_int_equal(fdi_table_check(&fdi_romo_table), FDI_OK);
}

static void test_unlinked_and_bad_inputs(void **state)
{
    fdi_gen_param_t p;
    fdi_gen_t g;
    fdi_frame_t in;
    float r = 0.0f;
    veh_meas_cfg_t mc = {{0.0, 0.0, 0.0, 0.0, 0.0}, {0.0, 0.0, 0.0, 0.0, 0.0}};
    test_rng_t rng = {1ULL};
    fdi_test_desc_t tests_copy[FDI_TABLE_MAX_TESTS];
    fdi_gen_desc_t bad = fdi_romo_generators[0];
    fdi_table_t t = fdi_romo_table;
    float sens[32];
    uint32_t i;
    (void)state;
    params(&p);
    memcpy(tests_copy, fdi_romo_table.tests, sizeof(fdi_test_desc_t) * fdi_romo_table.n_tests);
    t.tests = tests_copy;
    bad.step = NULL; /* no step function */
    tests_copy[0].gen = &bad;
    assert_int_equal(fdi_table_check(&t), FDI_BAD_TABLE);
    bad = fdi_romo_generators[0];
    bad.sens_mask = ~fdi_romo_table.tests[0].fault_mask; /* sensitivities outside the signature */
    assert_int_equal(fdi_table_check(&t), FDI_BAD_TABLE);
    bad = fdi_romo_generators[0];
    bad.input_mask |= ROMO_SIGM_ALL & ~fdi_romo_table.tests[0].input_mask; /* reads more than the test's signals */
    assert_int_equal(fdi_table_check(&t), FDI_BAD_TABLE);
    bad = fdi_romo_generators[0];
    assert_int_equal(fdi_table_check(&t), FDI_OK);
    for (i = 0U; i < (uint32_t)fdi_romo_table.n_tests; ++i)
    {
        veh_measure(1.0, &mc, &rng, &in);
        in.value[ROMO_SIG_ITM1_M] = 10.0f;
        in.value[ROMO_SIG_ITM2_M] = 10.0f;
        in.value[ROMO_SIG_ITM3_M] = 10.0f;
        in.value[ROMO_SIG_ITM4_M] = 10.0f;
        in.value[ROMO_SIG_OMEGA1_M] = 37.0f;
        in.value[ROMO_SIG_OMEGA2_M] = 37.0f;
        in.value[ROMO_SIG_OMEGA3_M] = 37.0f;
        in.value[ROMO_SIG_OMEGA4_M] = 37.0f;
        in.value[ROMO_SIG_P_F_M] = 0.0f;
        in.value[ROMO_SIG_P_R_M] = 0.0f;
        in.value[ROMO_SIG_DELTA1_M] = 0.0f;
        in.value[ROMO_SIG_DELTA2_M] = 0.0f;
        in.value[ROMO_SIG_DELTA3_M] = 0.0f;
        in.value[ROMO_SIG_DELTA4_M] = 0.0f;
        assert_int_equal(fdi_gen_init(&g, fdi_romo_table.tests[i].gen), FDI_OK);
        assert_int_equal(fdi_gen_reset(&g, &p, &in), FDI_OK);
        assert_int_equal(fdi_gen_step(&g, &p, &in, &r, sens), FDI_OK);
        assert_true(fdi_float_is_finite(r));
        assert_true(fdi_gen_sens_count(fdi_romo_table.tests[i].gen) <= 32U);
        in.value[ROMO_SIG_PSIDOT_M] = NAN;
        in.value[ROMO_SIG_OMEGA1_M] = INFINITY;
        in.value[ROMO_SIG_OMEGA2_M] = INFINITY;
        in.value[ROMO_SIG_OMEGA3_M] = INFINITY;
        in.value[ROMO_SIG_OMEGA4_M] = INFINITY;
        assert_int_equal(fdi_gen_step(&g, &p, &in, &r, NULL), FDI_NOT_FINITE);
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

static void test_operating_domain(void **state)
{
    fdi_frame_t in;
    fdi_diag_t d;
    fdi_diag_result_t res;
    const fdi_diag_config_t cfg = {.table = &fdi_romo_table,
                                   .gen_param = {(float)VEH_DX, (float)VEH_DY, 0.0f, 0.0f},
                                   .cusum_k = 1.5f, .cusum_h = 150.0f, .set_count = 1U, .clear_count = 1U,
                                   .warmup_steps = 300U, .mode = FDI_ISO_EXONERATION, .episode_clear_steps = 1U,
                                   .noise_allowance = 3.0f, .sensitivities = false};
    const uint32_t all = ((uint32_t)1U << fdi_romo_table.n_tests) - 1U;
    uint32_t low;
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
    for (n = 0; n < 300; ++n)
    {
        assert_int_equal(fdi_diag_step(&d, &in, ROMO_SIGM_ALL), FDI_OK);
        assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
        assert_int_equal(res.evaluable_mask & low, 0U);
    }
    assert_int_equal(fdi_diag_step(&d, &in, ROMO_SIGM_ALL), FDI_OK);
    assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
    assert_int_equal(res.evaluable_mask, all);
}

/* With sensitivities requested every generated generator computes the same residual, bit for bit, as without,
   and its sensitivities are finite: the sensitivity code runs after the residual and only when asked. */
static void test_sensitivities_leave_the_residual_alone(void **state)
{
    fdi_gen_param_t p;
    uint32_t i;
    (void)state;
    params(&p);
    for (i = 0U; i < (uint32_t)fdi_romo_table.n_tests; ++i)
    {
        const fdi_gen_desc_t *desc = fdi_romo_table.tests[i].gen;
        const uint32_t n_sens = fdi_gen_sens_count(desc);
        fdi_gen_t a;
        fdi_gen_t b;
        fdi_frame_t in;
        float sens[32];
        int n;
        assert_true(n_sens <= 32U);
        assert_int_equal(fdi_gen_init(&a, desc), FDI_OK);
        assert_int_equal(fdi_gen_init(&b, desc), FDI_OK);
        frame(&in, 12.0f);
        assert_int_equal(fdi_gen_reset(&a, &p, &in), FDI_OK);
        assert_int_equal(fdi_gen_reset(&b, &p, &in), FDI_OK);
        for (n = 1; n < 400; ++n)
        {
            float ra = 0.0f;
            float rb = 0.0f;
            uint32_t k;
            frame(&in, 12.0f + (0.5f * sinf(0.01f * (float)n)));
            in.value[ROMO_SIG_PSIDOT_M] = 0.3f;
            in.value[ROMO_SIG_DELTA1_M] = 0.02f;
            in.value[ROMO_SIG_ITM1_M] = 15.0f;
            assert_int_equal(fdi_gen_step(&a, &p, &in, &ra, NULL), FDI_OK);
            assert_int_equal(fdi_gen_step(&b, &p, &in, &rb, sens), FDI_OK);
            assert_true(memcmp(&ra, &rb, sizeof ra) == 0);
            for (k = 0U; k < n_sens; ++k)
            {
                assert_true(fdi_float_is_finite(sens[k]));
            }
        }
    }
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
    assert_int_equal(fdi_gen_init(&g, &fdi_romo_kin_x_deriv), FDI_OK);
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
        cmocka_unit_test(test_operating_domain),
        cmocka_unit_test(test_sensitivities_leave_the_residual_alone),
        cmocka_unit_test(test_observer_building_blocks),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
