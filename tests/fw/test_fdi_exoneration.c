/*
 * test_fdi_exoneration.c - the diagnoser's on-line exoneration rule (fw/include/fdi_diag.h) on a hand-made
 * table whose two generators output their residual and sensitivities straight from the frame, so every quantity
 * of the rule is set by the test:
 *   test 0 sees faults a (bit 0) and b (bit 1), r0 = frame[0], d r0 / d a = frame[1], d r0 / d b = frame[2];
 *   test 1 sees fault b only,                   r1 = frame[3], d r1 / d b = frame[4];
 *   test 2 sees fault a only,                   r2 = frame[5], d r2 / d a = frame[6].
 * All have sigma 1 and gate 5; the table's sensitivity margin is 1.5 and the response time 20 steps (+ the
 * evaluators' set count of 2). With test 0 in alarm at a settled residual R and test 1 quiet, the alarms imply
 * b >= (R - 3) / |d r0 / d b| (noise allowance 3 sigma), and test 1 clears b when |d r1 / d b| times that size
 * reaches 1.5 * 5 = 7.5 for 10 steps (0.1 s) in a row. Test 2 stays quiet and weak (d r2 / d a = 0.1) unless a
 * case says otherwise. In table_zero_b, test 0's generator lists d r0 / d a only: b is in its signature with a
 * steady-state sensitivity of exactly zero (as a fault that enters through a filtered derivative: a drift of b
 * explains a settled alarm of test 0). In
 * table_two_quiet, test 2 sees b instead of a (d r2 / d b = frame[6]): two quiet tests that may clear b together.
 * table_envelope is `table` with an operating envelope on frame[7] (|v| <= 1) and frame[8] (|w| <= 1), 2 votes.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "fdi_diag.h"

#define RESP 20U
#define SET 2U

static fdi_status_t gen0_step(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_frame_t *in, bool reset, float *r,
                              float *sens)
{
    (void)g;
    (void)par;
    *r = reset ? 0.0f : in->value[0];
    if (sens != NULL)
    {
        sens[0] = in->value[1];
        sens[1] = in->value[2];
    }
    return FDI_OK;
}

static uint32_t gen1_sens_calls = 0U; /* steps at which the diagnoser asked test 1 for its sensitivities */
static uint32_t gen1_calls = 0U;      /* steps test 1 ran (not resetting) */
static uint32_t gen1_last_sens = 0U;  /* gen1_calls at the last sensitivity request */
static uint32_t gen1_max_gap = 0U;    /* the longest run of steps between two requests */

static fdi_status_t gen1_step(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_frame_t *in, bool reset, float *r,
                              float *sens)
{
    (void)g;
    (void)par;
    *r = reset ? 0.0f : in->value[3];
    gen1_calls += reset ? 0U : 1U;
    if (sens != NULL)
    {
        sens[0] = in->value[4];
        if ((gen1_sens_calls > 0U) && ((gen1_calls - gen1_last_sens) > gen1_max_gap))
        {
            gen1_max_gap = gen1_calls - gen1_last_sens;
        }
        gen1_last_sens = gen1_calls;
        ++gen1_sens_calls;
    }
    return FDI_OK;
}

static fdi_status_t gen2_step(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_frame_t *in, bool reset, float *r,
                              float *sens)
{
    (void)g;
    (void)par;
    *r = reset ? 0.0f : in->value[5];
    if (sens != NULL)
    {
        sens[0] = in->value[6];
    }
    return FDI_OK;
}

static const fdi_gen_desc_t gen0 = {"t0", gen0_step, NULL, 0x07U, 0x3U, 0U, 0U, NULL, 0U, 0U, NULL, 0U, NULL, NULL};
static const fdi_gen_desc_t gen1 = {"t1", gen1_step, NULL, 0x18U, 0x2U, 0U, 0U, NULL, 0U, 0U, NULL, 0U, NULL, NULL};
static const fdi_gen_desc_t gen2 = {"t2", gen2_step, NULL, 0x60U, 0x1U, 0U, 0U, NULL, 0U, 0U, NULL, 0U, NULL, NULL};
static const fdi_test_desc_t tests[3] = {
    {&gen0, "t0", 1U, 0x3U, 0x07U, 5.0f, 1.0f, RESP},
    {&gen1, "t1", 2U, 0x2U, 0x18U, 5.0f, 1.0f, RESP},
    {&gen2, "t2", 3U, 0x1U, 0x60U, 5.0f, 1.0f, RESP},
};
static const char *const signal_names[7] = {"r0", "s0a", "s0b", "r1", "s1b", "r2", "s2a"};
static const char *const fault_names[2] = {"a", "b"};
static const uint32_t signature[2] = {0x5U, 0x3U};
static const uint32_t iso_class[2] = {0x1U, 0x2U};
static const float test_size[2 * 3] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f}; /* no reaction sizes: on-line rule */
static const fdi_table_t table = {FDI_TABLE_FORMAT_VERSION, {0.01f, 1.0f, 0.7071f, 2.0f}, 7U, 2U, 3U, signal_names,
                                  fault_names, tests, signature, iso_class, test_size, 2.0f, 1.5f, NULL};
/* test 0 of table_zero_b: the same residual, a sensitivity to a only */
static fdi_status_t gen0z_step(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_frame_t *in, bool reset, float *r,
                               float *sens)
{
    (void)g;
    (void)par;
    *r = reset ? 0.0f : in->value[0];
    if (sens != NULL)
    {
        sens[0] = in->value[1];
    }
    return FDI_OK;
}

/* test 0 of table_no_sens: the same residual, no sensitivities at all (nothing is known about b's) */
static fdi_status_t gen0n_step(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_frame_t *in, bool reset, float *r,
                               float *sens)
{
    (void)g;
    (void)par;
    (void)sens;
    *r = reset ? 0.0f : in->value[0];
    return FDI_OK;
}

static const fdi_gen_desc_t gen0z = {"t0z", gen0z_step, NULL, 0x07U, 0x1U, 0U, 0U, NULL, 0U, 0U, NULL, 0U, NULL, NULL};
static const fdi_gen_desc_t gen0n = {"t0n", gen0n_step, NULL, 0x07U, 0x0U, 0U, 0U, NULL, 0U, 0U, NULL, 0U, NULL, NULL};
static const fdi_test_desc_t tests_zero_b[3] = {
    {&gen0z, "t0", 1U, 0x3U, 0x07U, 5.0f, 1.0f, RESP},
    {&gen1, "t1", 2U, 0x2U, 0x18U, 5.0f, 1.0f, RESP},
    {&gen2, "t2", 3U, 0x1U, 0x60U, 5.0f, 1.0f, RESP},
};
static const fdi_test_desc_t tests_no_sens[3] = {
    {&gen0n, "t0", 1U, 0x3U, 0x07U, 5.0f, 1.0f, RESP},
    {&gen1, "t1", 2U, 0x2U, 0x18U, 5.0f, 1.0f, RESP},
    {&gen2, "t2", 3U, 0x1U, 0x60U, 5.0f, 1.0f, RESP},
};
static const fdi_table_t table_zero_b = {FDI_TABLE_FORMAT_VERSION, {0.01f, 1.0f, 0.7071f, 2.0f}, 7U, 2U, 3U,
                                         signal_names, fault_names, tests_zero_b, signature, iso_class, test_size,
                                         2.0f, 1.5f, NULL};
static const fdi_table_t table_no_sens = {FDI_TABLE_FORMAT_VERSION, {0.01f, 1.0f, 0.7071f, 2.0f}, 7U, 2U, 3U,
                                          signal_names, fault_names, tests_no_sens, signature, iso_class, test_size,
                                          2.0f, 1.5f, NULL};
/* table_rate_b: test 0 as in table_zero_b, and b's rate gain listed (d r0 / d (db/dt) = -0.5): each step of its
   alarm bounds how far b has moved */
static const float rate_gain_b[1] = {-0.5f};
static const fdi_gen_desc_t gen0r = {"t0r", gen0z_step, NULL, 0x07U, 0x1U, 0U, 0U, NULL, 0U, 0x2U, rate_gain_b, 0U, NULL, NULL};
static const fdi_test_desc_t tests_rate_b[3] = {
    {&gen0r, "t0", 1U, 0x3U, 0x07U, 5.0f, 1.0f, RESP},
    {&gen1, "t1", 2U, 0x2U, 0x18U, 5.0f, 1.0f, RESP},
    {&gen2, "t2", 3U, 0x1U, 0x60U, 5.0f, 1.0f, RESP},
};
static const fdi_table_t table_rate_b = {FDI_TABLE_FORMAT_VERSION, {0.01f, 1.0f, 0.7071f, 2.0f}, 7U, 2U, 3U,
                                         signal_names, fault_names, tests_rate_b, signature, iso_class, test_size,
                                         2.0f, 1.5f, NULL};
/* table_two_quiet: test 2 sees b instead of a (r2 = frame[5], d r2 / d b = frame[6]): two quiet tests of b */
static const fdi_gen_desc_t gen2b = {"t2b", gen2_step, NULL, 0x60U, 0x2U, 0U, 0U, NULL, 0U, 0U, NULL, 0U, NULL, NULL};
static const fdi_test_desc_t tests_two_quiet[3] = {
    {&gen0, "t0", 1U, 0x3U, 0x07U, 5.0f, 1.0f, RESP},
    {&gen1, "t1", 2U, 0x2U, 0x18U, 5.0f, 1.0f, RESP},
    {&gen2b, "t2", 3U, 0x2U, 0x60U, 5.0f, 1.0f, RESP},
};
static const uint32_t signature_two_quiet[2] = {0x1U, 0x7U};
static const fdi_table_t table_two_quiet = {FDI_TABLE_FORMAT_VERSION, {0.01f, 1.0f, 0.7071f, 2.0f}, 7U, 2U, 3U,
                                            signal_names, fault_names, tests_two_quiet, signature_two_quiet,
                                            iso_class, test_size, 2.0f, 1.5f, NULL};
/* table_envelope: the frame has two more signals, v = frame[7] and w = frame[8], the envelope's */
static const char *const signal_names_env[9] = {"r0", "s0a", "s0b", "r1", "s1b", "r2", "s2a", "v", "w"};
static const uint8_t env_signals[2] = {7U, 8U};
static const float env_limits[2] = {1.0f, 1.0f};
static const fdi_table_envelope_t envelope = {2U, 2U, env_signals, env_limits};
static const fdi_table_t table_envelope = {FDI_TABLE_FORMAT_VERSION, {0.01f, 1.0f, 0.7071f, 2.0f}, 9U, 2U, 3U,
                                           signal_names_env, fault_names, tests, signature, iso_class, test_size,
                                           2.0f, 1.5f, &envelope};
static const fdi_table_t *active = &table; /* the table init() uses */
static float v_now = 0.0f; /* the envelope signals of table_envelope */
static float w_now = 0.0f;
static float s2a = 0.1f; /* test 2's sensitivity to a (weak unless a case raises it) */
static float r1_now = 0.0f; /* test 1's residual (quiet unless a case raises it) */
static float r2_now = 0.0f; /* test 2's residual */

static uint16_t sens_every = 1U; /* the rule at every step unless a case sets the default's turns */

static void init(fdi_diag_t *d, fdi_iso_mode_t mode)
{
    fdi_diag_config_t c;
    assert_int_equal(fdi_diag_config_default(&c, active), FDI_OK);
    c.set_count = (uint16_t)SET;
    c.clear_count = 1U;
    c.mode = mode;
    c.episode_clear_steps = 5U;
    if (sens_every == 0U)
    {
        assert_int_equal(c.sens_every, 4U); /* the default: a test's sensitivities every 4th step of an episode */
    }
    else
    {
        c.sens_every = sens_every;
    }
    assert_int_equal(c.noise_allowance, 3.0f);
    assert_int_equal(fdi_diag_init(d, &c), FDI_OK);
}

/* Steps with the frame {r0, s0a, s0b, r1, s1b, 0, s2a}; returns the candidates of the last one. */
static uint32_t run(fdi_diag_t *d, uint32_t steps, float r0, float s0a, float s0b, float r1, float s1b)
{
    fdi_frame_t in;
    fdi_diag_result_t res;
    uint32_t k;
    uint32_t i;
    for (i = 0U; i < FDI_FRAME_MAX_SIGNALS; ++i)
    {
        in.value[i] = 0.0f;
    }
    in.value[0] = r0;
    in.value[1] = s0a;
    in.value[2] = s0b;
    in.value[3] = r1 + r1_now;
    in.value[4] = s1b;
    in.value[5] = r2_now;
    in.value[6] = s2a;
    in.value[7] = v_now;
    in.value[8] = w_now;
    for (k = 0U; k < steps; ++k)
    {
        assert_int_equal(fdi_diag_step(d, &in, 0x1FFU), FDI_OK);
    }
    assert_int_equal(fdi_diag_result(d, &res), FDI_OK);
    return res.iso.candidates;
}

/* Warm up fault-free, then the alarm: test 0 at r0 = 20 (b implied >= (20 - 3) / 1 = 17), test 1 quiet. */
static void warm(fdi_diag_t *d, fdi_iso_mode_t mode)
{
    s2a = 0.1f;
    r1_now = 0.0f;
    r2_now = 0.0f;
    init(d, mode);
    assert_int_equal(run(d, 400U, 0.0f, 1.0f, 1.0f, 0.0f, 1.0f), 0U);
}

static void test_quiet_test_clears_where_it_would_have_seen_the_fault(void **state)
{
    fdi_diag_t d;
    uint32_t k;
    uint32_t first = 0U;
    (void)state;
    warm(&d, FDI_ISO_EXONERATION);
    /* |d r1 / d b| = 0.5: at b = 17 test 1 would show 8.5 >= 7.5: b is cleared, once the alarm has settled and
       the quiet test has been quiet (and the episode old) for RESP + SET steps; before, both explain it */
    for (k = 1U; (k <= 200U) && (first == 0U); ++k)
    {
        const uint32_t c = run(&d, 1U, 20.0f, 1.0f, 1.0f, 0.0f, 0.5f);
        assert_true((c == 0U) || ((c & 0x1U) != 0U)); /* a is never cleared: test 1 does not see it */
        first = (c == 0x1U) ? k : 0U;
    }
    /* the response time, or the 0.3 s average coming within a fifth of the residual (~41 steps after the step) */
    assert_true(first >= (RESP + SET));
    assert_true(first <= 50U);
}

static void test_weak_quiet_test_does_not_clear(void **state)
{
    fdi_diag_t d;
    (void)state;
    warm(&d, FDI_ISO_EXONERATION);
    /* |d r1 / d b| = 0.4: 0.4 * 17 = 6.8 < 7.5 (it would cross its gate, but not with the margin) */
    assert_int_equal(run(&d, 300U, 20.0f, 1.0f, 1.0f, 0.0f, 0.4f), 0x3U);
    /* the sensitivity grows at another operating point: now it clears, once it has for 10 steps in a row */
    assert_int_equal(run(&d, 5U, 20.0f, 1.0f, 1.0f, 0.0f, 0.5f), 0x3U);
    assert_int_equal(run(&d, 6U, 20.0f, 1.0f, 1.0f, 0.0f, 0.5f), 0x1U);
}

/* fdi_diag_explain reads out the rule's evidence: the implied sizes, the confirmation runs, each quiet test's
   decision, the latched class. */
static void test_explain_shows_the_evidence_of_the_rule(void **state)
{
    fdi_diag_t d;
    fdi_diag_evidence_t ev;
    (void)state;
    assert_int_equal(fdi_diag_explain(NULL, &ev), FDI_BAD_ARG);
    warm(&d, FDI_ISO_EXONERATION);
    assert_int_equal(fdi_diag_explain(&d, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_diag_explain(&d, &ev), FDI_OK);
    assert_int_equal(ev.episode_age, 0U); /* no episode: nothing to show */
    assert_int_equal(ev.undecided, 0U);
    assert_float_equal(ev.implied[0], 0.0f, 0.0f);
    assert_float_equal(ev.implied[1], 0.0f, 0.0f);
    assert_int_equal(ev.clears[1], 0U);
    /* test 0 alarms at 20 with d r0 / d a = 2 and d r0 / d b = 1: a >= (20 - 3) / 2 = 8.5, b >= 17; test 1, quiet,
       sees b with 0.4: 0.4 * 17 = 6.8 < 7.5, it clears nothing */
    assert_int_equal(run(&d, 300U, 20.0f, 2.0f, 1.0f, 0.0f, 0.4f), 0x3U);
    assert_int_equal(fdi_diag_explain(&d, &ev), FDI_OK);
    assert_true((ev.episode_age > 250U) && (ev.episode_age <= 300U));
    assert_int_equal(ev.undecided, 0x3U);
    assert_int_equal(ev.latched, 0U);
    assert_float_equal(ev.implied[0], 8.5f, 0.01f);
    assert_float_equal(ev.implied[1], 17.0f, 0.01f);
    assert_int_equal(ev.cleared_run[1], 0U);
    assert_int_equal(ev.clears[1], 0U);
    /* with 0.5 test 1 clears b (8.5 >= 7.5): 5 steps of the 10 that confirm it */
    assert_int_equal(run(&d, 5U, 20.0f, 2.0f, 1.0f, 0.0f, 0.5f), 0x3U);
    assert_int_equal(fdi_diag_explain(&d, &ev), FDI_OK);
    assert_int_equal(ev.clears[1], 0x2U);
    assert_int_equal(ev.cleared_run[1], 5U);
    assert_int_equal(ev.cleared, 0U); /* not yet confirmed */
    assert_int_equal(ev.clears[0], 0U); /* in alarm: it clears nothing */
    /* confirmed: {a} isolated and latched; b, cleared, can still come back (undecided), a is decided */
    assert_int_equal(run(&d, 6U, 20.0f, 2.0f, 1.0f, 0.0f, 0.5f), 0x1U);
    assert_int_equal(fdi_diag_explain(&d, &ev), FDI_OK);
    assert_int_equal(ev.latched, 0x1U);
    assert_int_equal(ev.undecided, 0x2U);
    assert_int_equal(ev.cleared, 0x2U);
    assert_float_equal(ev.implied[0], 0.0f, 0.0f);
    assert_float_equal(ev.implied[1], 17.0f, 0.01f);
    /* the episode ends (no alarm for 5 steps, once the CUSUM has drained): nothing to show again */
    assert_int_equal(run(&d, 400U, 0.0f, 2.0f, 1.0f, 0.0f, 0.5f), 0U);
    assert_int_equal(fdi_diag_explain(&d, &ev), FDI_OK);
    assert_int_equal(ev.episode_age, 0U);
    assert_int_equal(ev.latched, 0U);
    assert_float_equal(ev.implied[1], 0.0f, 0.0f);
}

static void test_a_weak_spell_resets_the_confirmation(void **state)
{
    fdi_diag_t d;
    (void)state;
    warm(&d, FDI_ISO_EXONERATION);
    assert_int_equal(run(&d, 300U, 20.0f, 1.0f, 1.0f, 0.0f, 0.4f), 0x3U);
    assert_int_equal(run(&d, 8U, 20.0f, 1.0f, 1.0f, 0.0f, 0.5f), 0x3U);
    assert_int_equal(run(&d, 1U, 20.0f, 1.0f, 1.0f, 0.0f, 0.1f), 0x3U); /* the count starts again */
    assert_int_equal(run(&d, 8U, 20.0f, 1.0f, 1.0f, 0.0f, 0.5f), 0x3U);
    assert_int_equal(run(&d, 3U, 20.0f, 1.0f, 1.0f, 0.0f, 0.5f), 0x1U);
}

static void test_implied_size_needs_a_settled_residual(void **state)
{
    fdi_diag_t d;
    uint32_t k;
    (void)state;
    warm(&d, FDI_ISO_EXONERATION);
    /* a decaying kick (a step through a filtered derivative): r0 falls from 400 by 5 % per step, never settled
       against its 0.2 s average, so it implies nothing however large it is */
    for (k = 0U; k < 60U; ++k)
    {
        const float r0 = (400.0f * powf(0.95f, (float)k)) + 6.0f;
        const uint32_t c = run(&d, 1U, r0, 1.0f, 1.0f, 0.0f, 0.5f);
        assert_true((c == 0U) || (c == 0x3U)); /* 0 until the alarm is confirmed */
    }
    /* it settles at 8: implies b >= 5, test 1 would see 2.5 < 7.5: b stays a candidate */
    assert_int_equal(run(&d, 200U, 8.0f, 1.0f, 1.0f, 0.0f, 0.5f), 0x3U);
}

static void test_no_exoneration_mode_never_clears(void **state)
{
    fdi_diag_t d;
    (void)state;
    warm(&d, FDI_ISO_NO_EXONERATION);
    assert_int_equal(run(&d, 300U, 20.0f, 1.0f, 1.0f, 0.0f, 5.0f), 0x3U);
}

static void test_implied_size_follows_recent_evidence(void **state)
{
    fdi_diag_t d;
    (void)state;
    warm(&d, FDI_ISO_EXONERATION);
    assert_int_equal(run(&d, 100U, 20.0f, 1.0f, 1.0f, 0.0f, 0.5f), 0x1U);
    /* the alarmed residual falls back to 9 (still in alarm): the implied size of b (17) is forgotten with a 1 s
       time constant, and b is a candidate again once 0.5 * F_b < 7.5 (after ~12 steps), with a */
    assert_int_equal(run(&d, 5U, 9.0f, 1.0f, 1.0f, 0.0f, 0.5f), 0x1U);
    assert_int_equal(run(&d, 100U, 9.0f, 1.0f, 1.0f, 0.0f, 0.5f), 0x3U);
    /* the episode ends (no alarm for 5 steps, once the CUSUM has drained) and a new one starts at 9: b implied
       >= 6, 0.5 * 6 < 7.5 */
    assert_int_equal(run(&d, 400U, 0.0f, 1.0f, 1.0f, 0.0f, 0.5f), 0U);
    assert_int_equal(run(&d, 200U, 9.0f, 1.0f, 1.0f, 0.0f, 0.5f), 0x3U);
}

static void test_a_settled_alarm_does_not_bound_a_fault_it_sees_only_through_its_rate(void **state)
{
    fdi_diag_t d;
    uint32_t k;
    (void)state;
    /* test 0 lists no sensitivity to b although b is in its signature: b reaches r0 only through a filtered
       derivative, so a drift of b explains r0's settled alarm at any size. Test 0 bounds a only (a >= 17, and
       test 2 with d r2 / d a = 0.1 does not clear it), b gets no bound and stays a candidate however strongly
       the quiet test 1 would see it (d r1 / d b = 1.0, or 0.001): {a, b} */
    active = &table_zero_b;
    warm(&d, FDI_ISO_EXONERATION);
    assert_int_equal(run(&d, 300U, 20.0f, 1.0f, 1.0f, 0.0f, 1.0f), 0x3U);
    assert_true(d.implied[1] <= 0.0f);
    assert_true(d.implied[0] > 16.0f); /* 17, forgotten a little between fresh sensitivities */
    warm(&d, FDI_ISO_EXONERATION);
    assert_int_equal(run(&d, 300U, 20.0f, 1.0f, 1.0f, 0.0f, 0.001f), 0x3U);
    /* a decaying kick (as in test_implied_size_needs_a_settled_residual) clears nothing either */
    warm(&d, FDI_ISO_EXONERATION);
    for (k = 0U; k < 60U; ++k)
    {
        const uint32_t c = run(&d, 1U, (400.0f * powf(0.95f, (float)k)) + 6.0f, 1.0f, 1.0f, 0.0f, 1.0f);
        assert_true((c == 0U) || (c == 0x3U));
    }
    /* with test 0's sensitivity to b listed (table), the same alarm bounds b >= 17 and test 1 clears it: {a} */
    active = &table;
    warm(&d, FDI_ISO_EXONERATION);
    assert_int_equal(run(&d, 100U, 20.0f, 1.0f, 1.0f, 0.0f, 1.0f), 0x1U);
    /* a generator that lists no sensitivities at all says nothing about b's: b stays a candidate */
    active = &table_no_sens;
    warm(&d, FDI_ISO_EXONERATION);
    assert_int_equal(run(&d, 300U, 20.0f, 1.0f, 1.0f, 0.0f, 1.0f), 0x3U);
    active = &table;
}

static void test_a_settled_alarm_bounds_the_drift_of_a_fault_it_sees_through_its_rate(void **state)
{
    fdi_diag_t d;
    float before;
    float after;
    (void)state;
    /* test 0 (r0 = 20 sigma) lists b's rate gain -0.5: under b alone, b moves at least at (20 - 3) / 0.5 = 34
       per second, so every alarmed step moves it by at least 0.34 (dt 0.01) */
    active = &table_rate_b;
    warm(&d, FDI_ISO_EXONERATION);
    /* a weak quiet test 1 (d r1 / d b = 0.001) needs b >= 7,500 to clear it: b stays, and its bound grows */
    assert_int_equal(run(&d, 100U, 20.0f, 1.0f, 1.0f, 0.0f, 0.001f), 0x3U);
    before = d.implied[1];
    assert_int_equal(run(&d, 100U, 20.0f, 1.0f, 1.0f, 0.0f, 0.001f), 0x3U);
    after = d.implied[1];
    assert_true(before > 0.0f);
    assert_float_equal(after - before, 34.0f, 0.01f); /* 100 alarmed steps of 0.34 */
    assert_true(d.drift[1] < 0.0f);                   /* r0 / gain < 0: the drift runs downwards */
    /* a strong quiet test 1 (d r1 / d b = 1.0) clears b once it must have moved past 7.5 (23 alarmed steps) and
       test 1 has settled, confirmed for 10 steps (without the gain, below: {a, b} for good) */
    warm(&d, FDI_ISO_EXONERATION);
    assert_int_equal(run(&d, 300U, 20.0f, 1.0f, 1.0f, 0.0f, 1.0f), 0x1U);
    /* the sign turns (r0 = +20, then -20): the moves cancel, the bound shrinks (b up and back down) */
    warm(&d, FDI_ISO_EXONERATION);
    (void)run(&d, 100U, 20.0f, 1.0f, 1.0f, 0.0f, 0.001f);
    before = fabsf(d.drift[1]);
    (void)run(&d, 150U, -20.0f, 1.0f, 1.0f, 0.0f, 0.001f);
    assert_true(fabsf(d.drift[1]) < before);
    /* without the rate gain (table_zero_b) the same alarm leaves b unbounded and a candidate */
    active = &table_zero_b;
    warm(&d, FDI_ISO_EXONERATION);
    assert_int_equal(run(&d, 300U, 20.0f, 1.0f, 1.0f, 0.0f, 1.0f), 0x3U);
    assert_true(d.implied[1] <= 0.0f);
    active = &table;
}

static void test_the_first_isolation_is_latched(void **state)
{
    fdi_diag_t d;
    (void)state;
    warm(&d, FDI_ISO_EXONERATION);
    assert_int_equal(run(&d, 100U, 20.0f, 1.0f, 1.0f, 0.0f, 0.5f), 0x1U); /* {a}: isolated */
    /* test 2 now looks as if it should have seen a (1.0 * 17 >= 7.5): a was isolated, it stays */
    s2a = 1.0f;
    assert_int_equal(run(&d, 100U, 20.0f, 1.0f, 1.0f, 0.0f, 0.5f), 0x1U);
    /* test 1 alarms: a does not explain it; b would, but the episode's isolation is contradicted: "detected,
       not isolated" (no candidate) until the episode ends */
    r1_now = 20.0f;
    assert_int_equal(run(&d, 100U, 20.0f, 1.0f, 1.0f, 0.0f, 0.5f), 0U);
    r1_now = 0.0f;
    assert_int_equal(run(&d, 400U, 0.0f, 1.0f, 1.0f, 0.0f, 0.5f), 0U); /* the episode ends */
    s2a = 0.1f;
    assert_int_equal(run(&d, 200U, 9.0f, 1.0f, 1.0f, 0.0f, 0.5f), 0x3U); /* a new one starts afresh */
}

static void test_quiet_tests_clear_together_what_each_misses(void **state)
{
    fdi_diag_t d;
    (void)state;
    active = &table_two_quiet;
    /* b implied >= 17; tests 1 and 2 with |d r / d b| = 0.35 would show 0.35 * 17 = 5.95 < 7.5 each: neither
       clears b alone; together, at 17 / 1.5 each lacks (5.95 / 1.5) / 5 = 0.79 gates, 0.63 + 0.63 >= 1: {a} */
    warm(&d, FDI_ISO_EXONERATION);
    s2a = 0.35f;
    assert_int_equal(run(&d, 100U, 20.0f, 1.0f, 1.0f, 0.0f, 0.35f), 0x1U);
    /* one of them alone (test 2 blind to b now): 0.63 < 1, b stays */
    warm(&d, FDI_ISO_EXONERATION);
    s2a = 0.0f;
    assert_int_equal(run(&d, 300U, 20.0f, 1.0f, 1.0f, 0.0f, 0.35f), 0x3U);
    /* both, but their residuals (quiet, at 1 sigma) already show part of the response: each lacks
       (3.97 - 1) / 5 = 0.59 gates, 0.35 + 0.35 < 1: b stays */
    warm(&d, FDI_ISO_EXONERATION);
    s2a = 0.35f;
    r1_now = 1.0f;
    r2_now = 1.0f;
    assert_int_equal(run(&d, 300U, 20.0f, 1.0f, 1.0f, 0.0f, 0.35f), 0x3U);
    active = &table;
}

static void test_sensitivities_in_turn(void **state)
{
    /* the default (sens_every 4): during an episode test 1's sensitivities are asked for every 4th step only,
       never outside an episode; its decision holds in between, so the case of test_weak_quiet_test_does_not_clear
       clears b no earlier (10 steps of confirmation) and at most 3 steps later than with the rule at every step */
    fdi_diag_t d;
    uint32_t k;
    uint32_t first = 0U;
    (void)state;
    sens_every = 0U;
    gen1_sens_calls = 0U;
    gen1_max_gap = 0U;
    warm(&d, FDI_ISO_EXONERATION);
    assert_int_equal(gen1_sens_calls, 0U); /* no episode, no sensitivities */
    assert_int_equal(run(&d, 300U, 20.0f, 1.0f, 1.0f, 0.0f, 0.4f), 0x3U);
    /* test 1 is wanted from its response time on (RESP + SET of the 300 steps, ~278): a quarter of those */
    assert_true(gen1_sens_calls >= 66U);
    assert_true(gen1_sens_calls <= 72U);
    assert_int_equal(gen1_max_gap, 4U);
    for (k = 1U; (k <= 20U) && (first == 0U); ++k)
    {
        first = (run(&d, 1U, 20.0f, 1.0f, 1.0f, 0.0f, 0.5f) == 0x1U) ? k : 0U;
    }
    assert_true(first >= 11U);
    assert_true(first <= 14U);
    sens_every = 1U;
    gen1_sens_calls = 0U;
    gen1_max_gap = 0U;
    warm(&d, FDI_ISO_EXONERATION);
    assert_int_equal(run(&d, 40U, 20.0f, 1.0f, 1.0f, 0.0f, 0.4f), 0x3U);
    assert_int_equal(gen1_max_gap, 1U); /* every step once asked for */
}

static bool last_in_envelope(const fdi_diag_t *d, uint32_t *accused, uint32_t *evaluable)
{
    fdi_diag_result_t res;
    assert_int_equal(fdi_diag_result(d, &res), FDI_OK);
    *accused = res.accused_mask;
    *evaluable = res.evaluable_mask;
    return res.in_envelope;
}

static void test_outside_the_envelope_no_test_is_evaluable_and_the_isolation_holds(void **state)
{
    /* Test 0 in alarm accuses a and b; test 1 (blind to a) alarming too would leave b alone. One envelope signal
       beyond its limit is not enough (2 votes): test 1 accuses. With both beyond: no test is evaluable, the
       episode and its candidates hold (for longer than episode_clear_steps); back inside, the tests warm up
       before they alarm again (nothing of the time outside carries over) and test 1's alarm accuses. */
    fdi_diag_t d;
    uint32_t accused = 0U;
    uint32_t evaluable = 0U;
    uint32_t k;
    (void)state;
    active = &table_envelope;
    v_now = 0.0f;
    w_now = 0.0f;
    warm(&d, FDI_ISO_EXONERATION);
    assert_true(last_in_envelope(&d, &accused, &evaluable));
    assert_int_equal(run(&d, 10U, 20.0f, 1.0f, 1.0f, 0.0f, 0.1f), 0x3U); /* test 1 weak (0.1): clears nothing */
    v_now = 5.0f; /* one vote: still inside */
    r1_now = 20.0f;
    assert_int_equal(run(&d, 5U, 20.0f, 1.0f, 1.0f, 0.0f, 0.1f), 0x2U);
    assert_true(last_in_envelope(&d, &accused, &evaluable));
    /* the same with both signals beyond their limits, from a fresh episode */
    r1_now = 0.0f;
    v_now = 0.0f;
    warm(&d, FDI_ISO_EXONERATION);
    assert_int_equal(run(&d, 10U, 20.0f, 1.0f, 1.0f, 0.0f, 0.1f), 0x3U);
    v_now = 5.0f;
    w_now = -5.0f;
    r1_now = 20.0f;
    assert_int_equal(run(&d, 50U, 20.0f, 1.0f, 1.0f, 0.0f, 0.1f), 0x3U); /* held, 10 times episode_clear_steps */
    assert_false(last_in_envelope(&d, &accused, &evaluable));
    assert_int_equal(accused, 0x1U);
    assert_int_equal(evaluable, 0U);
    v_now = 0.0f; /* back inside: the tests warm up (no alarm: this episode ends after its 5 steps), then both alarm */
    w_now = 0.0f;
    for (k = 0U; (k < 1000U) && (evaluable == 0U); ++k)
    {
        (void)run(&d, 1U, 20.0f, 1.0f, 1.0f, 0.0f, 0.1f);
        (void)last_in_envelope(&d, &accused, &evaluable);
    }
    assert_true(k > 100U); /* the warm-up (the settling time of the design point) */
    assert_int_equal(run(&d, 5U, 20.0f, 1.0f, 1.0f, 0.0f, 0.1f), 0x2U); /* test 1's alarm, confirmed (SET 2) */
    assert_true(last_in_envelope(&d, &accused, &evaluable));
    assert_int_equal(accused, 0x3U);
    r1_now = 0.0f;
    v_now = 0.0f;
    w_now = 0.0f;
    active = &table;
}

static void test_outside_the_envelope_nothing_is_detected(void **state)
{
    /* no episode open: a residual far beyond its gate outside the envelope is not evaluated (no detection); inside
       again it is, after the warm-up */
    fdi_diag_t d;
    fdi_diag_result_t res;
    uint32_t k;
    (void)state;
    active = &table_envelope;
    v_now = 0.0f;
    w_now = 0.0f;
    warm(&d, FDI_ISO_EXONERATION);
    v_now = 2.0f;
    w_now = 2.0f;
    assert_int_equal(run(&d, 30U, 20.0f, 1.0f, 1.0f, 0.0f, 0.1f), 0U);
    assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
    assert_false(res.iso.detected);
    assert_false(res.in_envelope);
    assert_int_equal(res.status[0], FDI_TEST_NOT_EVALUABLE);
    v_now = 0.0f;
    for (k = 0U; (k < 1000U) && !res.iso.detected; ++k)
    {
        (void)run(&d, 1U, 20.0f, 1.0f, 1.0f, 0.0f, 0.1f);
        assert_int_equal(fdi_diag_result(&d, &res), FDI_OK);
    }
    assert_true(res.iso.detected && res.in_envelope && (k > 100U) && (k < 1000U));
    v_now = 0.0f;
    w_now = 0.0f;
    active = &table;
}

int main(void)
{
    const struct CMUnitTest list[] = {
        cmocka_unit_test(test_quiet_test_clears_where_it_would_have_seen_the_fault),
        cmocka_unit_test(test_weak_quiet_test_does_not_clear),
        cmocka_unit_test(test_explain_shows_the_evidence_of_the_rule),
        cmocka_unit_test(test_implied_size_needs_a_settled_residual),
        cmocka_unit_test(test_no_exoneration_mode_never_clears),
        cmocka_unit_test(test_implied_size_follows_recent_evidence),
        cmocka_unit_test(test_a_weak_spell_resets_the_confirmation),
        cmocka_unit_test(test_the_first_isolation_is_latched),
        cmocka_unit_test(test_a_settled_alarm_does_not_bound_a_fault_it_sees_only_through_its_rate),
        cmocka_unit_test(test_a_settled_alarm_bounds_the_drift_of_a_fault_it_sees_through_its_rate),
        cmocka_unit_test(test_quiet_tests_clear_together_what_each_misses),
        cmocka_unit_test(test_sensitivities_in_turn),
        cmocka_unit_test(test_outside_the_envelope_no_test_is_evaluable_and_the_isolation_holds),
        cmocka_unit_test(test_outside_the_envelope_nothing_is_detected),
    };
    return cmocka_run_group_tests(list, NULL, NULL);
}
