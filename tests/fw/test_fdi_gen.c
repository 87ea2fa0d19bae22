/*
 * test_fdi_gen.c - residual generators through their descriptors (fdi_gen.h), with the hand-written kinematic
 * MSO1..MSO4 of the ROMO target (derivative and observer forms, fdi_romo_kin.h) on the analytic reference
 * vehicle of fdi_test_util.h: arguments, descriptors, input masks, non-finite inputs, residual ~ 0
 * on consistent signals (stated bounds), each additive fault moves exactly the residuals whose MSO
 * contains it (others stay bit-identical), 1e6-step run.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "fdi_gen.h"
#include "fdi_gen_impl.h"
#include "fdi_romo_generators.h"
#include "fdi_romo_kin.h"
#include "fdi_test_vehicle.h"

#define DT 0.01
#define N_KINDS 6

static const fdi_gen_desc_t *const kinds[N_KINDS] = {&fdi_romo_kin_x_deriv, &fdi_romo_kin_y_deriv, &fdi_romo_kin_arr3,
                                                    &fdi_romo_kin_arr4,    &fdi_romo_kin_x_obs,   &fdi_romo_kin_y_obs};
/* faults (bit j = f(j+1)) of the MSO each kind implements */
static const uint32_t kind_faults[N_KINDS] = {0x1DU, 0x1EU, 0x0FU, 0x17U, 0x1DU, 0x1EU};
/*
 * Bound on |r| for exact (noise-free) signals after 10 s, at 1 Hz derivative filters (the kinematic
 * table's design point). Delay matching makes the linear terms exact; what is left is the filtering of
 * products (w * vy, w * p', ...) with the manoeuvre (0.1-0.25 Hz) a decade below the cut-off: ~0.1 % of
 * the residual's natural scale (ax, ay ~ 1-5 m/s^2 for r1, r2; ay w^2 ~ 1.3 for r3, r4). Measured maxima
 * 5.3e-4, 8.8e-4, 2.06e-3, 1.83e-3, 2.0e-5, 7.5e-6; bounds ~30 % above. The observer forms only carry
 * the O(dt^2) error of the input hold.
 */
static const double consistent_bound[N_KINDS] = {7e-4, 1.2e-3, 2.7e-3, 2.4e-3, 3e-5, 1.2e-5};

/* Storage of a hand-written generator's instance (fdi_gen_t is a view on it). */
typedef struct
{
    fdi_svf_t filt[FDI_GEN_MAX_FILTERS];
    fdi_obs_t obs;
} gen_storage_t;

static fdi_status_t init(fdi_gen_t *g, const fdi_gen_desc_t *desc, gen_storage_t *m)
{
    return fdi_gen_init(g, desc, m->filt, FDI_GEN_MAX_FILTERS, &m->obs);
}

static void params(fdi_gen_param_t *p)
{
    const fdi_gen_config_t cfg = {(float)DT, 1.0f, 0.7071f, 2.0f, {(float)VEH_DX, (float)VEH_DY, 0.0f, 0.0f}};
    assert_int_equal(fdi_gen_param_init(p, &cfg), FDI_OK);
}

static void test_bad_args(void **state)
{
    fdi_gen_param_t p;
    fdi_gen_t g;
    gen_storage_t m;
    fdi_frame_t in;
    float r = 0.0f;
    veh_meas_cfg_t mc = {{0.0, 0.0, 0.0, 0.0, 0.0}, {0.0, 0.0, 0.0, 0.0, 0.0}};
    test_rng_t rng = {1ULL};
    const fdi_gen_config_t bad_fc = {0.01f, 80.0f, 0.7071f, 2.0f, {1.0f, 0.0f, 0.0f, 0.0f}};
    const fdi_gen_config_t bad_gain = {0.01f, 0.5f, 0.7071f, -1.0f, {1.0f, 0.0f, 0.0f, 0.0f}};
    const fdi_gen_config_t nan_dx = {0.01f, 0.5f, 0.7071f, 2.0f, {NAN, 0.0f, 0.0f, 0.0f}};
    fdi_gen_desc_t bad = fdi_romo_kin_arr3;
    (void)state;
    assert_int_equal(fdi_gen_param_init(NULL, &bad_fc), FDI_BAD_ARG);
    assert_int_equal(fdi_gen_param_init(&p, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_gen_param_init(&p, &bad_fc), FDI_BAD_ARG);
    assert_int_equal(fdi_gen_param_init(&p, &bad_gain), FDI_BAD_ARG);
    assert_int_equal(fdi_gen_param_init(&p, &nan_dx), FDI_NOT_FINITE);
    params(&p);
    veh_measure(0.0, &mc, &rng, &in);
    assert_int_equal(init(NULL, &fdi_romo_kin_arr3, &m), FDI_BAD_ARG);
    assert_int_equal(init(&g, NULL, &m), FDI_BAD_ARG);
    bad.step = NULL; /* no step function */
    assert_int_equal(init(&g, &bad, &m), FDI_BAD_ARG);
    bad = fdi_romo_kin_arr3;
    bad.name = NULL;
    assert_int_equal(init(&g, &bad, &m), FDI_BAD_ARG);
    bad = fdi_romo_kin_arr3;
    bad.input_mask = 0U;
    assert_int_equal(init(&g, &bad, &m), FDI_BAD_ARG);
    bad = fdi_romo_kin_arr3;
    bad.n_filters = (uint8_t)(FDI_GEN_MAX_FILTERS + 1U);
    assert_int_equal(init(&g, &bad, &m), FDI_BAD_ARG);
    bad = fdi_romo_kin_arr3;
    bad.n_obs = 2U;
    assert_int_equal(init(&g, &bad, &m), FDI_BAD_ARG);
    bad = fdi_romo_kin_arr3;
    bad.set = &fdi_romo_gen_set; /* a step and a set: neither kind */
    assert_int_equal(init(&g, &bad, &m), FDI_BAD_ARG);
    assert_int_equal(fdi_gen_init(&g, &fdi_romo_kin_arr3, m.filt, 7U, &m.obs), FDI_BAD_ARG); /* needs 8 filters */
    assert_int_equal(fdi_gen_init(&g, &fdi_romo_kin_arr3, NULL, 8U, &m.obs), FDI_BAD_ARG);
    assert_int_equal(fdi_gen_init(&g, &fdi_romo_kin_x_obs, m.filt, 0U, NULL), FDI_BAD_ARG); /* needs its observer */
    assert_int_equal(fdi_gen_init(&g, &fdi_romo_kin_arr3, m.filt, 8U, NULL), FDI_OK);     /* no observer needed */
    assert_int_equal(fdi_gen_init(&g, &fdi_romo_generators[0], m.filt, 8U, &m.obs), FDI_BAD_ARG); /* a set's slot */
    assert_int_equal(fdi_gen_desc_check(NULL), FDI_BAD_ARG);
    assert_int_equal(init(&g, &fdi_romo_kin_arr3, &m), FDI_OK);
    assert_int_equal(fdi_gen_reset(NULL, &p, &in), FDI_BAD_ARG);
    assert_int_equal(fdi_gen_reset(&g, NULL, &in), FDI_BAD_ARG);
    assert_int_equal(fdi_gen_reset(&g, &p, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_gen_reset(&g, &p, &in), FDI_OK);
    assert_int_equal(fdi_gen_step(&g, &p, &in, NULL, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_gen_step(NULL, &p, &in, &r, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_gen_sens_count(NULL), 0U);
    assert_int_equal(fdi_gen_sens_count(&fdi_romo_kin_arr3), 0U);
    assert_false(fdi_gen_in_domain(NULL, &in));
    assert_false(fdi_gen_in_domain(&fdi_romo_kin_arr3, NULL));
    assert_true(fdi_gen_in_domain(&fdi_romo_kin_arr3, &in)); /* no domain function: always */
    assert_int_equal(fdi_gen_sens_finish(FDI_OK, NULL, 1U), FDI_BAD_ARG);
}

static void test_input_masks(void **state)
{
    (void)state;
    uint32_t i;
    assert_int_equal(fdi_romo_kin_x_deriv.input_mask,
                     ROMO_SIGM_AX_M | ROMO_SIGM_PSIDOT_M | ROMO_SIGM_VX_M | ROMO_SIGM_VY_M);
    assert_int_equal(fdi_romo_kin_y_obs.input_mask, ROMO_SIGM_AY_M | ROMO_SIGM_PSIDOT_M | ROMO_SIGM_VX_M | ROMO_SIGM_VY_M);
    assert_int_equal(fdi_romo_kin_arr3.input_mask, ROMO_SIGM_AX_M | ROMO_SIGM_AY_M | ROMO_SIGM_PSIDOT_M | ROMO_SIGM_VX_M);
    assert_int_equal(fdi_romo_kin_arr4.input_mask, ROMO_SIGM_AX_M | ROMO_SIGM_AY_M | ROMO_SIGM_PSIDOT_M | ROMO_SIGM_VY_M);
    for (i = 0U; i < (uint32_t)N_KINDS; ++i)
    {
        assert_int_equal(fdi_gen_desc_check(kinds[i]), FDI_OK);
    }
}

/* A NaN in a signal the kind reads is rejected; a NaN in a signal it does not read is ignored. */
static void test_non_finite(void **state)
{
    fdi_gen_param_t p;
    fdi_gen_t g;
    gen_storage_t m;
    fdi_frame_t in;
    float r = 5.0f;
    veh_meas_cfg_t mc = {{0.0, 0.0, 0.0, 0.0, 0.0}, {0.0, 0.0, 0.0, 0.0, 0.0}};
    test_rng_t rng = {1ULL};
    (void)state;
    params(&p);
    veh_measure(0.0, &mc, &rng, &in);
    assert_int_equal(init(&g, &fdi_romo_kin_arr3, &m), FDI_OK);
    assert_int_equal(fdi_gen_reset(&g, &p, &in), FDI_OK);
    in.value[ROMO_SIG_VY_M] = NAN; /* ARR3 does not use vy_m */
    in.value[ROMO_SIG_OMEGA2_M] = INFINITY;
    assert_int_equal(fdi_gen_step(&g, &p, &in, &r, NULL), FDI_OK);
    in.value[ROMO_SIG_AY_M] = NAN;
    r = 5.0f;
    assert_int_equal(fdi_gen_step(&g, &p, &in, &r, NULL), FDI_NOT_FINITE);
    assert_int_equal(fdi_gen_reset(&g, &p, &in), FDI_NOT_FINITE);
    assert_near(r, 5.0, 0.0);
}

/*
 * Run one kind over [0, t_end] with fault j (or none: j < 0) active from 20 s as offset + drift
 * f = size * (1 + 0.1 (t - 20)); write the residual sequence from 10 s on into out[].
 */
#define T_END 40.0
#define N_OUT 3001
static void run(const fdi_gen_desc_t *kind, int j, double size, double noise_scale, float *out)
{
    static const double sigma[5] = {0.02, 0.02, 0.001, 0.01, 0.01};
    fdi_gen_param_t p;
    fdi_gen_t g;
    gen_storage_t m;
    fdi_frame_t in;
    veh_meas_cfg_t mc = {{0.0, 0.0, 0.0, 0.0, 0.0}, {0.0, 0.0, 0.0, 0.0, 0.0}};
    test_rng_t rng = {42ULL};
    int k;
    int i;
    for (i = 0; i < 5; ++i)
    {
        mc.noise[i] = noise_scale * sigma[i];
    }
    params(&p);
    assert_int_equal(init(&g, kind, &m), FDI_OK);
    veh_measure(0.0, &mc, &rng, &in);
    assert_int_equal(fdi_gen_reset(&g, &p, &in), FDI_OK);
    for (k = 1; k <= (int)(T_END / DT + 0.5); ++k)
    {
        const double t = k * DT;
        float r = 0.0f;
        if ((j >= 0) && (t >= 20.0))
        {
            mc.f[j] = size * (1.0 + 0.1 * (t - 20.0));
        }
        veh_measure(t, &mc, &rng, &in);
        assert_int_equal(fdi_gen_step(&g, &p, &in, &r, NULL), FDI_OK);
        if (k >= 1000)
        {
            out[k - 1000] = r;
        }
    }
}

static void test_consistent_signals(void **state)
{
    static float r[N_OUT];
    int n;
    (void)state;
    for (n = 0; n < N_KINDS; ++n)
    {
        double max_r = 0.0;
        int k;
        run(kinds[n], -1, 0.0, 0.0, r);
        for (k = 0; k < N_OUT; ++k)
        {
            max_r = fmax(max_r, fabs((double)r[k]));
        }
        print_message("%s %u: max |r| = %g (bound %g)\n", kinds[n]->name, (unsigned)n, max_r, consistent_bound[n]);
        if (!(max_r <= consistent_bound[n]))
        {
            print_error("%s %u: max |r| = %g > %g\n", kinds[n]->name, (unsigned)n, max_r, consistent_bound[n]);
        }
        assert_true(max_r <= consistent_bound[n]);
    }
}

/*
 * Fault sizes: 0.3 m/s^2 (f1, f2), 0.03 rad/s (f3), 0.2 m/s (f4, f5), growing 10 %/s. A fault in the MSO
 * must move the residual by more than 5x its consistency bound; a fault outside must not change a bit.
 */
static void test_fault_sensitivity(void **state)
{
    static const double size[5] = {0.3, 0.3, 0.03, 0.2, 0.2};
    static float r0[N_OUT];
    static float rf[N_OUT];
    int n;
    int j;
    (void)state;
    for (n = 0; n < N_KINDS; ++n)
    {
        run(kinds[n], -1, 0.0, 1.0, r0);
        for (j = 0; j < 5; ++j)
        {
            double dev = 0.0;
            int k;
            run(kinds[n], j, size[j], 1.0, rf);
            for (k = 0; k < N_OUT; ++k)
            {
                dev = fmax(dev, fabs((double)rf[k] - (double)r0[k]));
            }
            print_message("%s %u fault f%d: deviation %g\n", kinds[n]->name, (unsigned)n, j + 1, dev);
            if ((kind_faults[n] & (1U << j)) != 0U)
            {
                if (!(dev > 5.0 * consistent_bound[n]))
                {
                    print_error("%s %u fault f%d: deviation %g too small\n", kinds[n]->name, (unsigned)n, j + 1, dev);
                }
                assert_true(dev > 5.0 * consistent_bound[n]);
            }
            else
            {
                assert_near(dev, 0.0, 0.0);
            }
        }
    }
}

/* 1e6 steps (2.8 h of driving, time kept in double): the ARR3 residual stays within its bound. */
static void test_long_run(void **state)
{
    fdi_gen_param_t p;
    fdi_gen_t g;
    gen_storage_t m;
    fdi_frame_t in;
    veh_meas_cfg_t mc = {{0.0, 0.0, 0.0, 0.0, 0.0}, {0.0, 0.0, 0.0, 0.0, 0.0}};
    test_rng_t rng = {7ULL};
    double max_r = 0.0;
    long k;
    (void)state;
    params(&p);
    assert_int_equal(init(&g, &fdi_romo_kin_arr3, &m), FDI_OK);
    veh_measure(0.0, &mc, &rng, &in);
    assert_int_equal(fdi_gen_reset(&g, &p, &in), FDI_OK);
    for (k = 1; k <= 1000000L; ++k)
    {
        float r = 0.0f;
        veh_measure((double)k * DT, &mc, &rng, &in);
        assert_int_equal(fdi_gen_step(&g, &p, &in, &r, NULL), FDI_OK);
        if (k > 1000L)
        {
            max_r = fmax(max_r, fabs((double)r));
        }
    }
    print_message("long run max |r| = %g\n", max_r);
    assert_true(max_r <= consistent_bound[2]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_args),           cmocka_unit_test(test_input_masks),
        cmocka_unit_test(test_non_finite),         cmocka_unit_test(test_consistent_signals),
        cmocka_unit_test(test_fault_sensitivity),  cmocka_unit_test(test_long_run),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
