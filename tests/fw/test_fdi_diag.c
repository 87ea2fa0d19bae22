/*
 * test_fdi_diag.c - the diagnoser on the kinematic table and the noisy reference vehicle: arguments,
 * warm-up and validity handling (exact step counts), non-finite signals, no false alarm in 10 min of
 * fault-free driving, isolation of each drifting sensor fault f1..f5 with and without exoneration,
 * a test without generator, a 1e6-step run, and the on-line estimation (convergence, bound, freeze).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "fdi_diag.h"
#include "fdi_kin_table.h"
#include "fdi_romo_kin.h"
#include "fdi_test_vehicle.h"

#define DT 0.01
#define WARMUP 320U /* >= 300 steps: max(2 stages * 6 / (zeta * 2 pi 1 Hz), 6 / L = 3 s) at 100 Hz */
#define EST_SETTLE 100U /* steps after the warm-up in which the estimators' threshold narrows (not counted) */

static const double sigma[5] = {0.02, 0.02, 0.001, 0.01, 0.01}; /* the table's noise assumption */

/* The kinematic table with every test's response_steps set to `steps` (1: memoryless isolation, a quiet test
   exonerates at once; the table's own 300 steps are the ECU's episode rule). */
static fdi_test_desc_t kin_tests_copy[4];
static fdi_table_t kin_copy;

static const fdi_table_t *kin_with_response(uint16_t steps)
{
    uint32_t i;
    (void)veh_kin_table(&kin_copy);
    for (i = 0U; i < 4U; ++i)
    {
        kin_tests_copy[i] = fdi_kin_table.tests[i];
        kin_tests_copy[i].response_steps = steps;
    }
    kin_copy.tests = kin_tests_copy;
    return &kin_copy;
}

static fdi_diag_config_t config(fdi_iso_mode_t mode)
{
    fdi_diag_config_t c;
    c.table = kin_with_response(1U); /* memoryless isolation unless a test sets the episode rules */
    c.gen_param[FDI_ROMO_KIN_PARAM_D_X] = (float)VEH_DX;
    c.gen_param[FDI_ROMO_KIN_PARAM_D_Y] = (float)VEH_DY;
    c.gen_param[2] = 0.0f;
    c.gen_param[3] = 0.0f;
    c.sensitivities = false;
    c.adaptive = false;
    c.estimate = 0U;
    c.estimate_kappa = 3.0f;
    c.estimate_decorrelation = 10.0f;
    c.estimate_startup = 100U;
    c.sens_every = 1U;
    /* The residuals are low-pass noise (correlation ~0.2 s), so the CUSUM needs a larger drift and
       threshold than for white noise: with k = 1.5 sigma the largest fault-free excursion in 1e6 steps
       was 71 (ARR3); h = 150 leaves a factor 2. */
    c.cusum_k = 1.5f;
    c.cusum_h = 150.0f;
    c.set_count = 10U;
    c.clear_count = 100U;
    c.warmup_steps = WARMUP;
    c.reentry_steps = 50U;
    c.mode = mode;
    c.episode_clear_steps = 1U;
    c.noise_allowance = 3.0f;
    return c;
}

static void noisy(veh_meas_cfg_t *mc)
{
    int i;
    for (i = 0; i < 5; ++i)
    {
        mc->f[i] = 0.0;
        mc->noise[i] = sigma[i];
    }
}

/* The layout signature: the library's is the one this test was compiled with; a caller compiled with another
   capacity or struct size is refused with FDI_BAD_LAYOUT and its instance is then refused by the step. */
static void test_layout_signature(fdi_diag_t *d, const fdi_diag_config_t *c)
{
    const fdi_diag_layout_t here = fdi_diag_layout_here();
    fdi_diag_layout_t own;
    fdi_diag_layout_t other;
    fdi_frame_t in;
    memset(&in, 0, sizeof in);
    assert_int_equal(fdi_diag_layout(NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_diag_layout(&own), FDI_OK);
    assert_memory_equal(&own, &here, sizeof own);
    assert_int_equal(own.max_tests, FDI_DIAG_MAX_TESTS);
    assert_int_equal(own.size_diag, sizeof(fdi_diag_t));
    assert_int_equal(fdi_diag_init_layout(d, c, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_diag_init_layout(NULL, c, &here), FDI_BAD_ARG);
    assert_int_equal(fdi_diag_init_layout(d, NULL, &here), FDI_BAD_ARG);
    assert_int_equal(fdi_diag_init_layout(d, c, &here), FDI_OK);
    other = here;
    other.max_tests = FDI_DIAG_MAX_TESTS + 8U; /* a caller built with -DFDI_DIAG_MAX_TESTS=24 */
    assert_int_equal(fdi_diag_init_layout(d, c, &other), FDI_BAD_LAYOUT);
    assert_int_equal(fdi_diag_step(d, &in, ROMO_SIGM_ALL), FDI_BAD_ARG); /* refused after the failed init */
    other = here;
    other.est_max_params = here.est_max_params + 1U;
    assert_int_equal(fdi_diag_init_layout(d, c, &other), FDI_BAD_LAYOUT);
    other = here;
    other.size_diag = here.size_diag + 4U; /* same capacities, another struct layout */
    assert_int_equal(fdi_diag_init_layout(d, c, &other), FDI_BAD_LAYOUT);
    other = here;
    other.size_gen_desc = 0U;
    assert_int_equal(fdi_diag_init_layout(d, c, &other), FDI_BAD_LAYOUT);
    assert_int_equal(fdi_diag_init(d, c), FDI_OK);
}

static void test_bad_args(void **state)
{
    fdi_diag_t d;
    fdi_diag_result_t res;
    fdi_frame_t in;
    fdi_diag_config_t c = config(FDI_ISO_EXONERATION);
    fdi_table_t bad_table = fdi_kin_table;
    (void)state;
    memset(&in, 0, sizeof in);
    assert_int_equal(fdi_diag_init(NULL, &c), FDI_BAD_ARG);
    assert_int_equal(fdi_diag_init(&d, NULL), FDI_BAD_ARG);
    c.warmup_steps = 299U; /* shorter than the settling time */
    assert_int_equal(fdi_diag_init(&d, &c), FDI_BAD_ARG);
    assert_int_equal(fdi_diag_step(&d, &in, ROMO_SIGM_ALL), FDI_BAD_ARG); /* failed init: refused */
    assert_int_equal(fdi_diag_result(&d, &res), FDI_BAD_ARG);
    c = config((fdi_iso_mode_t)3);
    assert_int_equal(fdi_diag_init(&d, &c), FDI_BAD_ARG);
    c = config(FDI_ISO_EXONERATION);
    c.cusum_k = NAN;
    assert_int_equal(fdi_diag_init(&d, &c), FDI_NOT_FINITE);
    c = config(FDI_ISO_EXONERATION);
    c.set_count = 0U;
    assert_int_equal(fdi_diag_init(&d, &c), FDI_BAD_ARG);
    c = config(FDI_ISO_EXONERATION);
    c.episode_clear_steps = 0U;
    assert_int_equal(fdi_diag_init(&d, &c), FDI_BAD_ARG);
    c = config(FDI_ISO_EXONERATION);
    c.sens_every = (uint16_t)(FDI_DIAG_MAX_SENS_EVERY + 1U);
    assert_int_equal(fdi_diag_init(&d, &c), FDI_BAD_ARG);
    c = config(FDI_ISO_EXONERATION);
    bad_table.format_version = 0U;
    c.table = &bad_table;
    assert_int_equal(fdi_diag_init(&d, &c), FDI_BAD_TABLE);
    c.table = NULL;
    assert_int_equal(fdi_diag_init(&d, &c), FDI_BAD_ARG);
    c = config(FDI_ISO_EXONERATION);
    assert_int_equal(fdi_diag_init(&d, &c), FDI_OK);
    assert_int_equal(fdi_diag_step(NULL, &in, 0U), FDI_BAD_ARG);
    test_layout_signature(&d, &c);
    assert_int_equal(fdi_diag_step(&d, NULL, 0U), FDI_BAD_ARG);
    assert_int_equal(fdi_diag_result(NULL, &res), FDI_BAD_ARG);
    assert_int_equal(fdi_diag_result(&d, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
    assert_int_equal(res.evaluable_mask, 0U);
    assert_int_equal(res.status[0], FDI_TEST_NOT_EVALUABLE);
}

static uint32_t step_eval_mask(fdi_diag_t *d, double t, veh_meas_cfg_t *mc, test_rng_t *rng, uint32_t validity,
                               fdi_frame_t *in)
{
    fdi_diag_result_t res;
    veh_measure(t, mc, rng, in);
    assert_int_equal(fdi_diag_step(d, in, validity), FDI_OK);
    assert_int_equal(fdi_diag_result(d, &res), FDI_OK);
    assert_int_equal(res.alarm_mask, 0U);
    return res.evaluable_mask;
}

/*
 * Steps 1..WARMUP are not evaluable, step WARMUP + 1 is. Invalid vx_m: MSO1..3 (which read it) become
 * not evaluable at once, MSO4 stays evaluable; when vx_m returns they need WARMUP steps again. A NaN in a
 * signal flagged valid counts as invalid; a NaN in a signal no test reads changes nothing.
 */
static void test_warmup_and_validity(void **state)
{
    fdi_diag_t d;
    fdi_frame_t in;
    const fdi_diag_config_t c = config(FDI_ISO_EXONERATION);
    veh_meas_cfg_t mc;
    test_rng_t rng = {11ULL};
    uint32_t k;
    uint32_t n = 0U;
    (void)state;
    noisy(&mc);
    assert_int_equal(fdi_diag_init(&d, &c), FDI_OK);
    for (k = 1U; k <= WARMUP; ++k)
    {
        assert_int_equal(step_eval_mask(&d, (++n) * DT, &mc, &rng, ROMO_SIGM_ALL, &in), 0U);
    }
    assert_int_equal(step_eval_mask(&d, (++n) * DT, &mc, &rng, ROMO_SIGM_ALL, &in), 0xFU);
    for (k = 1U; k <= 20U; ++k)
    {
        assert_int_equal(step_eval_mask(&d, (++n) * DT, &mc, &rng, ROMO_SIGM_ALL & ~ROMO_SIGM_VX_M, &in), 0x8U);
    }
    for (k = 1U; k <= WARMUP; ++k)
    {
        assert_int_equal(step_eval_mask(&d, (++n) * DT, &mc, &rng, ROMO_SIGM_ALL, &in), 0x8U);
    }
    assert_int_equal(step_eval_mask(&d, (++n) * DT, &mc, &rng, ROMO_SIGM_ALL, &in), 0xFU);
    /* NaN in vy_m (flagged valid): MSO1, MSO2, MSO4 drop out; stale omega signals do not matter */
    veh_measure((++n) * DT, &mc, &rng, &in);
    in.value[ROMO_SIG_VY_M] = NAN;
    in.value[ROMO_SIG_OMEGA3_M] = INFINITY;
    assert_int_equal(fdi_diag_step(&d, &in, ROMO_SIGM_ALL & ~ROMO_SIGM_OMEGA1_M), FDI_OK);
    {
        fdi_diag_result_t res;
        assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
        assert_int_equal(res.evaluable_mask, 0x4U);
        assert_int_equal(res.status[0], FDI_TEST_NOT_EVALUABLE);
        assert_int_equal(res.status[2], FDI_TEST_OK);
        assert_int_equal(res.status[3], FDI_TEST_NOT_EVALUABLE);
    }
}

/* Run one diagnoser pair (exoneration / none) for t_end seconds with fault j drifting from t_fault. */
typedef struct
{
    uint32_t alarm_steps_before; /* steps with any alarm before the fault (after warm-up) */
    fdi_diag_result_t end_ex;    /* results at t_end */
    fdi_diag_result_t end_ne;
    double first_detect; /* time of the first alarm after the fault, -1 if none */
} run_t;

static run_t run(int j, double rate, double t_fault, double t_end, uint64_t seed)
{
    fdi_diag_t dx;
    fdi_diag_t dn;
    fdi_frame_t in;
    const fdi_diag_config_t cx = config(FDI_ISO_EXONERATION);
    const fdi_diag_config_t cn = config(FDI_ISO_NO_EXONERATION);
    veh_meas_cfg_t mc;
    test_rng_t rng = {seed};
    run_t out;
    long k;
    const long n = (long)(t_end / DT + 0.5);
    out.alarm_steps_before = 0U;
    out.first_detect = -1.0;
    noisy(&mc);
    assert_int_equal(fdi_diag_init(&dx, &cx), FDI_OK);
    assert_int_equal(fdi_diag_init(&dn, &cn), FDI_OK);
    for (k = 1; k <= n; ++k)
    {
        const double t = (double)k * DT;
        if ((j >= 0) && (t > t_fault))
        {
            mc.f[j] = rate * (t - t_fault);
        }
        veh_measure(t, &mc, &rng, &in);
        assert_int_equal(fdi_diag_step(&dx, &in, ROMO_SIGM_ALL), FDI_OK);
        assert_int_equal(fdi_diag_step(&dn, &in, ROMO_SIGM_ALL), FDI_OK);
        assert_int_equal(fdi_diag_result(&dx, &out.end_ex), FDI_OK);
        if ((j < 0) || (t <= t_fault))
        {
            out.alarm_steps_before += (out.end_ex.alarm_mask != 0U) ? 1U : 0U;
        }
        else if ((out.first_detect < 0.0) && (out.end_ex.alarm_mask != 0U))
        {
            out.first_detect = t - t_fault;
        }
    }
    assert_int_equal(fdi_diag_result(&dn, &out.end_ne), FDI_OK);
    return out;
}

/* 10 minutes of noisy fault-free driving, two noise seeds: no alarm at all, every test evaluable. */
static void test_no_false_alarm(void **state)
{
    uint64_t seed;
    (void)state;
    for (seed = 1U; seed <= 2U; ++seed)
    {
        const run_t r = run(-1, 0.0, 0.0, 600.0, seed);
        assert_int_equal(r.alarm_steps_before, 0U);
        assert_int_equal(r.end_ex.evaluable_mask, 0xFU);
        assert_false(r.end_ex.iso.detected);
    }
}

/*
 * Drifting sensor faults from t = 30 s (rates: f1, f2 0.05 m/s^2 per s; f3 0.01 rad/s per s, so that it
 * passes MSO1's reaction size 0.15 rad/s of fdi_kin_calibration.h; f4, f5 0.05 m/s per s), observed at
 * t = 60 s. Every test of the fault's signature alarms. With exoneration the fault is isolated exactly
 * (every fault has a unique signature in Table II's kinematic rows), except f2: its alarms {MSO2, MSO3,
 * MSO4} are also those of a yaw rate offset f3 below MSO1's reaction size (MSO1 sees f3 only as vy * f3),
 * so the quiet MSO1 does not clear f3 and the candidates are {f2, f3} (never f3 alone: no wrong class).
 * Without exoneration the fault is among the candidates and every candidate explains the alarms.
 * Detection within 10 s of the fault start.
 */
static void test_isolation_of_each_fault(void **state)
{
    static const double rate[5] = {0.05, 0.05, 0.01, 0.05, 0.05};
    static const uint32_t expect[5] = {0x01U, 0x06U, 0x04U, 0x08U, 0x10U};
    int j;
    (void)state;
    for (j = 0; j < 5; ++j)
    {
        const run_t r = run(j, rate[j], 30.0, 60.0, 5U);
        print_message("f%d: detected after %.2f s, alarms 0x%X, candidates ex 0x%X, no-ex 0x%X\n", j + 1,
                      r.first_detect, r.end_ex.alarm_mask, r.end_ex.iso.candidates, r.end_ne.iso.candidates);
        assert_int_equal(r.alarm_steps_before, 0U);
        assert_true((r.first_detect >= 0.0) && (r.first_detect < 10.0));
        assert_int_equal(r.end_ex.alarm_mask, fdi_kin_table.fault_signature[j]);
        assert_int_equal(r.end_ex.iso.candidates, expect[j]);
        assert_true(r.end_ex.iso.isolated == (expect[j] == (1U << j)));
        assert_int_equal(r.end_ne.iso.candidates & (1U << j), 1U << j);
    }
}

/*
 * Isolation episodes (settle 200 steps, episode end after 300 quiet steps): each sensor fault as a 0.5 s
 * burst of a large offset from t = 20 s, then healthy again. At every step: the accused tests contain the
 * alarmed ones and only grow within an episode; the true fault is never exonerated; `detected` equals
 * "episode active". Within the settle window no quiet test clears anything (candidates = no-exoneration
 * candidates of the accused tests); after it the candidates narrow to the fault ({f2, f3} for the f2 burst),
 * and stay so after the burst (the accused tests are latched) until 300
 * steps after the last alarm, when the episode ends.
 */
static void test_isolation_episodes(void **state)
{
    static const double size[5] = {1.0, 1.0, 0.3, 1.0, 1.0}; /* f3 above MSO1's reaction size (0.15 rad/s) */
    /* f2: its alarms also fit a yaw rate offset f3 below MSO1's reaction size (test_isolation_of_each_fault) */
    static const uint32_t expect[5] = {0x01U, 0x06U, 0x04U, 0x08U, 0x10U};
    int j;
    (void)state;
    for (j = 0; j < 5; ++j)
    {
        fdi_diag_t d;
        fdi_diag_result_t res;
        fdi_frame_t in;
        fdi_diag_config_t c = config(FDI_ISO_EXONERATION);
        veh_meas_cfg_t mc;
        test_rng_t rng = {11ULL};
        uint32_t prev_accused = 0U;
        long k;
        long episode_start = -1L;
        long last_alarm = -1L;
        long episode_end = -1L;
        long first_exact = -1L;
        c.table = kin_with_response(200U);
        c.episode_clear_steps = 300U;
        noisy(&mc);
        assert_int_equal(fdi_diag_init(&d, &c), FDI_OK);
        for (k = 1L; k <= 5000L; ++k)
        {
            const double t = (double)k * DT;
            fdi_iso_result_t ne;
            mc.f[j] = ((t > 20.0) && (t <= 20.5)) ? size[j] : 0.0;
            veh_measure(t, &mc, &rng, &in);
            assert_int_equal(fdi_diag_step(&d, &in, ROMO_SIGM_ALL), FDI_OK);
            assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
            assert_int_equal(res.alarm_mask & ~res.accused_mask, 0U);
            assert_true(res.iso.detected == (res.accused_mask != 0U));
            if (res.alarm_mask != 0U)
            {
                last_alarm = k;
            }
            if ((res.accused_mask != 0U) && (prev_accused == 0U))
            {
                assert_true(t > 20.0); /* no fault-free episode */
                assert_int_equal(episode_start, -1L); /* one episode per burst */
                episode_start = k;
            }
            if ((res.accused_mask == 0U) && (prev_accused != 0U))
            {
                episode_end = k;
                assert_int_equal(k - last_alarm, 300L);
            }
            if (res.accused_mask != 0U)
            {
                assert_int_equal(res.accused_mask & prev_accused, prev_accused);
                assert_true((res.iso.candidates >> j) & 1U);
                assert_int_equal(fdi_iso_run(&fdi_kin_table, res.accused_mask, res.accused_mask,
                                             FDI_ISO_NO_EXONERATION, &ne), FDI_OK);
                if ((k - episode_start) < 199L)
                {
                    assert_int_equal(res.iso.candidates, ne.candidates);
                }
                else if (res.iso.candidates == expect[j])
                {
                    first_exact = (first_exact < 0L) ? k : first_exact;
                }
                else
                {
                    /* the accused set may still grow */
                }
            }
            prev_accused = res.accused_mask;
        }
        print_message("f%d burst: episode %ld..%ld steps, last alarm %ld, exact from %ld\n", j + 1, episode_start,
                      episode_end, last_alarm, first_exact);
        assert_true(episode_start > 0L);
        assert_true(episode_end > last_alarm);
        assert_true((first_exact > 0L) && (first_exact < episode_end));
        assert_true(first_exact > 2050L); /* after the burst: the latched accusations isolate it */
    }
}

/* A table whose MSO4 has no generator yet: MSO4 is never evaluable, the others work as before. */
static void test_kind_none(void **state)
{
    fdi_test_desc_t tests[4];
    fdi_table_t t = fdi_kin_table;
    fdi_diag_t d;
    fdi_diag_config_t c = config(FDI_ISO_EXONERATION);
    fdi_frame_t in;
    veh_meas_cfg_t mc;
    test_rng_t rng = {3ULL};
    uint32_t k;
    (void)state;
    memcpy(tests, kin_with_response(1U)->tests, sizeof tests);
    tests[3].gen = NULL;
    t.tests = tests;
    c.table = &t;
    noisy(&mc);
    assert_int_equal(fdi_diag_init(&d, &c), FDI_OK);
    for (k = 1U; k <= WARMUP + 5U; ++k)
    {
        (void)step_eval_mask(&d, k * DT, &mc, &rng, ROMO_SIGM_ALL, &in);
    }
    assert_int_equal(step_eval_mask(&d, k * DT, &mc, &rng, ROMO_SIGM_ALL, &in), 0x7U);
}

/* 1e6 steps (2.8 h) of fault-free, noisy driving: no alarm, results stay finite. */
static void test_long_run(void **state)
{
    const run_t r = run(-1, 0.0, 0.0, 10000.0, 9U);
    int i;
    (void)state;
    assert_int_equal(r.alarm_steps_before, 0U);
    for (i = 0; i < 4; ++i)
    {
        assert_true(isfinite(r.end_ex.residual[i]));
        assert_true(fabs((double)r.end_ex.residual[i]) < 0.1);
    }
}

/*
 * On-line estimation (fdi_diag.h, fdi_est.h) on the kinematic table, whose hand-written generators declare no
 * estimable quantity of their own: the test gives each an offset (regressor 1) declared within +-`bound`, uniform,
 * drifting at most 0.01 per second (q = (drift dt / 2)^2, fdi_analysis.residuals.estimation). A vx sensor bias of
 * 0.2 m/s (20 sigma of the sensor, f4 as a constant from t = 0) makes the fixed gates alarm. With every test's offset
 * estimated (bound 0.5: wider than what the bias does): no alarm over 40 s once the filters have seen a second of
 * data, and the tests that alarmed carry an offset > 1 sigma. A step fault f1 of 1 m/s^2 at t = 40 s is detected
 * within 1 s and isolated exactly (candidates {f1}); from the detection on, the estimate of every test the episode
 * accuses is frozen bit for bit from its accusation while the episode is open (the tests that see f1: at least two
 * of them), and before it the estimates moved by less than 5 % of the fault's residual plus half a sigma. Declared
 * within about one sigma, the bias is not absorbed: the tests alarm.
 */
static fdi_est_param_t est_offset[1];
static fdi_gen_desc_t est_gens[4];

static const fdi_table_t *kin_estimable(float bound)
{
    const fdi_table_t *t = kin_with_response(200U);
    uint32_t i;
    est_offset[0].mean = 0.0f;
    est_offset[0].lo = -bound;
    est_offset[0].hi = bound;
    est_offset[0].var = (4.0f * bound * bound) / 12.0f;
    est_offset[0].q = (0.01f * (float)DT / 2.0f) * (0.01f * (float)DT / 2.0f); /* a 0.01 / s drift lags 2 sigma */
    est_offset[0].step = 2.0f * bound * (float)DT / 10.0f; /* the range in 10 s */
    for (i = 0U; i < 4U; ++i)
    {
        est_gens[i] = *fdi_kin_table.tests[i].gen;
        est_gens[i].n_est = 1U;
        est_gens[i].est = est_offset;
        kin_tests_copy[i].gen = &est_gens[i];
    }
    return t;
}

typedef struct
{
    uint32_t alarm_steps_before; /* steps with an alarm before t_fault, after the filters settled */
    uint32_t alarmed_before;     /* the tests that alarmed then */
    double first_detect;         /* after t_fault, -1: none */
    bool frozen;                 /* every accused test's estimate unchanged from its accusation while the episode is
                                    open */
    uint32_t accused;            /* the tests the fault's episode accused */
    fdi_diag_result_t at_onset;
    fdi_diag_result_t at_detect;
    fdi_diag_result_t end;
} est_run_t;

static est_run_t est_run(uint32_t estimate, float bound, double t_fault, double t_end)
{
    fdi_diag_t d;
    fdi_frame_t in;
    fdi_diag_config_t c = config(FDI_ISO_EXONERATION);
    veh_meas_cfg_t mc;
    test_rng_t rng = {23ULL};
    est_run_t out;
    long k;
    uint32_t accused = 0U; /* tests accused so far in the fault's episode, their estimates when first accused */
    float held[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    const long n = (long)(t_end / DT + 0.5);
    const long settle = (long)WARMUP + (long)EST_SETTLE; /* the warm-up, then a second of the estimators */
    memset(&out, 0, sizeof out);
    out.first_detect = -1.0;
    out.frozen = true;
    c.table = (estimate != 0U) ? kin_estimable(bound) : kin_with_response(200U);
    c.episode_clear_steps = 300U;
    c.estimate = estimate;
    noisy(&mc);
    mc.f[3] = 0.2;
    assert_int_equal(fdi_diag_init(&d, &c), FDI_OK);
    for (k = 1L; k <= n; ++k)
    {
        const double t = (double)k * DT;
        fdi_diag_result_t res;
        mc.f[0] = (t > t_fault) ? 1.0 : 0.0;
        veh_measure(t, &mc, &rng, &in);
        assert_int_equal(fdi_diag_step(&d, &in, ROMO_SIGM_ALL), FDI_OK);
        assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
        if (t <= t_fault)
        {
            out.alarm_steps_before += ((k > settle) && (res.alarm_mask != 0U)) ? 1U : 0U;
            out.alarmed_before |= (k > settle) ? res.alarm_mask : 0U;
            out.at_onset = res;
        }
        else if (out.first_detect < 0.0)
        {
            if (res.alarm_mask != 0U)
            {
                out.first_detect = t - t_fault;
                out.at_detect = res;
            }
        }
        else if (res.accused_mask != 0U)
        {
            /* an accused test's estimate stays where it was when the episode first accused it; the others go on */
            uint32_t i;
            for (i = 0U; i < 4U; ++i)
            {
                const uint32_t bit = 1UL << i;
                if ((res.accused_mask & bit) == 0U)
                {
                    /* not accused: free */
                }
                else if ((accused & bit) == 0U)
                {
                    accused |= bit;
                    held[i] = res.estimate[i][0];
                }
                else
                {
                    out.frozen = out.frozen && (memcmp(&res.estimate[i][0], &held[i], sizeof(float)) == 0);
                }
            }
            out.accused |= res.accused_mask;
        }
        else
        {
            /* the episode ended */
        }
        out.end = res;
    }
    return out;
}

static void test_offset_estimation(void **state)
{
    uint32_t biased; /* the tests the bias makes alarm at the fixed gates */
    est_run_t r;
    uint32_t i;
    fdi_diag_t d;
    fdi_diag_config_t c = config(FDI_ISO_EXONERATION);
    (void)state;
    c.estimate = 0x1U; /* the kinematic table's generators declare nothing to estimate: refused */
    assert_int_equal(fdi_diag_init(&d, &c), FDI_BAD_ARG);
    c.table = kin_estimable(0.5f);
    c.estimate_kappa = -1.0f;
    assert_int_equal(fdi_diag_init(&d, &c), FDI_BAD_ARG);
    c.estimate_kappa = NAN;
    assert_int_equal(fdi_diag_init(&d, &c), FDI_NOT_FINITE);
    c.estimate_kappa = 3.0f;
    c.estimate_decorrelation = 10.0f;
    c.estimate_startup = 100U;
    c.estimate = 0x10U; /* beyond the table's tests */
    assert_int_equal(fdi_diag_init(&d, &c), FDI_BAD_ARG);
    r = est_run(0U, 0.5f, 40.0, 40.0);
    print_message("no estimation: %u alarm steps of %ld\n", r.alarm_steps_before,
                  4000L - (long)WARMUP - (long)EST_SETTLE);
    assert_true(r.alarm_steps_before > 1000U);
    biased = r.alarmed_before;
    r = est_run(0xFU, 0.5f, 40.0, 60.0);
    print_message("estimated: %u alarm steps; f1 detected after %.2f s, candidates 0x%X\n", r.alarm_steps_before,
                  r.first_detect, r.end.iso.candidates);
    assert_int_equal(r.alarm_steps_before, 0U);
    for (i = 0U; i < 4U; ++i)
    {
        const double sd = sqrt((double)fdi_kin_table.tests[i].variance);
        const double b = fabs((double)r.at_onset.offset[i]);
        const double moved = fabs((double)r.at_detect.offset[i] - (double)r.at_onset.offset[i]);
        print_message("  test %u: offset %.4f (%.1f sigma), moved %.5f before the detection, residual %.4f\n", i,
                      (double)r.at_onset.offset[i], b / sd, moved, (double)r.end.residual[i]);
        if ((biased & (1U << i)) != 0U)
        {
            assert_true(b > 1.0 * sd); /* at or beyond the CUSUM drift (1.5 sigma) that made it alarm */
        }
        assert_true(moved <= 0.05 * fabs((double)r.end.residual[i]) + 0.5 * sd);
    }
    assert_true((r.first_detect >= 0.0) && (r.first_detect < 1.0));
    print_message("accused 0x%X, their estimates frozen: %d\n", r.accused, r.frozen ? 1 : 0);
    assert_true(r.frozen);
    assert_true((r.accused & 0xDU) == r.accused); /* f1's tests: MSO1, MSO3, MSO4 */
    assert_true(((r.accused & 0x1U) != 0U) && ((r.accused & 0xCU) != 0U)); /* MSO1 and one of MSO3/MSO4 */
    assert_int_equal(r.end.iso.candidates, 0x01U);
    r = est_run(0xFU, (float)sqrt((double)fdi_kin_table.tests[1].variance), 40.0, 40.0);
    print_message("bound 1 sigma: %u alarm steps\n", r.alarm_steps_before);
    assert_true(r.alarm_steps_before > 1000U);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_args),          cmocka_unit_test(test_warmup_and_validity),
        cmocka_unit_test(test_no_false_alarm),    cmocka_unit_test(test_isolation_of_each_fault),
        cmocka_unit_test(test_kind_none),         cmocka_unit_test(test_long_run),
        cmocka_unit_test(test_isolation_episodes), cmocka_unit_test(test_offset_estimation),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
