/*
 * test_fdi_table.c - table validation: the hand-made kinematic table passes; each kind of corruption an
 * exporter could produce is rejected with FDI_BAD_TABLE.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "fdi_kin_table.h"
#include "fdi_romo_signals.h"
#include "fdi_test_util.h"

static fdi_test_desc_t tests_copy[4];
static uint32_t sig_copy[5];
static uint32_t class_copy[5];
static const char *names_copy[5];
static float size_copy[5 * 4];
static const char *signal_names_copy[ROMO_SIG_COUNT];
static fdi_gen_desc_t bad_gen;
static uint8_t env_signal[2];
static float env_limit[2];
static fdi_table_envelope_t env;
static fdi_table_t t;

/* A writable copy of the kinematic table. */
static int setup(void **state)
{
    int i;
    (void)state;
    t = fdi_kin_table;
    for (i = 0; i < 4; ++i)
    {
        tests_copy[i] = fdi_kin_table.tests[i];
    }
    for (i = 0; i < 5; ++i)
    {
        sig_copy[i] = fdi_kin_table.fault_signature[i];
        class_copy[i] = fdi_kin_table.iso_class[i];
        names_copy[i] = fdi_kin_table.fault_names[i];
    }
    for (i = 0; i < 5 * 4; ++i)
    {
        size_copy[i] = fdi_kin_table.test_size[i];
    }
    t.tests = tests_copy;
    t.fault_signature = sig_copy;
    t.iso_class = class_copy;
    t.fault_names = names_copy;
    t.test_size = size_copy;
    for (i = 0; i < (int)ROMO_SIG_COUNT; ++i)
    {
        signal_names_copy[i] = fdi_kin_table.signal_names[i];
    }
    t.signal_names = signal_names_copy;
    bad_gen = *fdi_kin_table.tests[0].gen; /* test 0 runs a copy of its generator that a case may corrupt */
    tests_copy[0].gen = &bad_gen;
    env_signal[0] = (uint8_t)ROMO_SIG_VY_M; /* a valid envelope on two signals that a case may corrupt */
    env_signal[1] = (uint8_t)ROMO_SIG_PSIDOT_M;
    env_limit[0] = 1.0f;
    env_limit[1] = 0.5f;
    env.n_signals = 2U;
    env.votes = 2U;
    env.signal = env_signal;
    env.limit = env_limit;
    t.envelope = &env;
    return 0;
}

static void test_kin_table_ok(void **state)
{
    (void)state;
    assert_int_equal(fdi_table_check(&fdi_kin_table), FDI_OK);
    assert_int_equal(fdi_table_check(&t), FDI_OK); /* with an envelope */
    t.envelope = NULL;
    assert_int_equal(fdi_table_check(&t), FDI_OK); /* and without */
    assert_int_equal(fdi_table_check(NULL), FDI_BAD_ARG);
}

#define EXPECT_BAD(stmt)                                                                                      \
    do                                                                                                        \
    {                                                                                                         \
        (void)setup(NULL);                                                                                    \
        stmt;                                                                                                 \
        assert_int_equal(fdi_table_check(&t), FDI_BAD_TABLE);                                                 \
    } while (0)

static void test_corruptions(void **state)
{
    (void)state;
    EXPECT_BAD(t.format_version = 99U);
    EXPECT_BAD(t.n_faults = 0U);
    EXPECT_BAD(t.n_tests = 33U);
    EXPECT_BAD(t.tests = NULL);
    EXPECT_BAD(t.fault_names = NULL);
    EXPECT_BAD(names_copy[2] = NULL);
    EXPECT_BAD(t.design.dt = 0.0f);
    EXPECT_BAD(t.design.cutoff_hz = NAN);
    EXPECT_BAD(tests_copy[1].interpretation = NULL);
    EXPECT_BAD(bad_gen.step = NULL);                     /* an unusable generator descriptor */
    EXPECT_BAD(bad_gen.sens_mask = 0x20U);               /* sensitivity to a fault outside the test's set */
    EXPECT_BAD(t.n_signals = 0U);
    EXPECT_BAD(t.n_signals = 33U);
    EXPECT_BAD(t.n_signals = 3U);                        /* the tests read signals beyond the first three */
    EXPECT_BAD(t.signal_names = NULL);
    EXPECT_BAD(signal_names_copy[18] = NULL);
    EXPECT_BAD(tests_copy[2].input_mask = ROMO_SIGM_AX_M); /* misses signals ARR3 reads */
    EXPECT_BAD(tests_copy[2].input_mask |= 0x00100000U);  /* no such signal */
    EXPECT_BAD(tests_copy[0].variance = 0.0f);
    EXPECT_BAD(tests_copy[0].gate = INFINITY);
    EXPECT_BAD(tests_copy[3].fault_mask |= 0x20U);     /* fault beyond n_faults */
    EXPECT_BAD(tests_copy[3].fault_mask = 0U);         /* a test that sees no fault */
    EXPECT_BAD(sig_copy[3] = 0x3U);                    /* signature != transposed fault masks */
    EXPECT_BAD(tests_copy[0].fault_mask &= ~0x08U);    /* fault masks != signatures */
    EXPECT_BAD(class_copy[0] = 0x03U);                 /* f1, f2 have different signatures */
    EXPECT_BAD(class_copy[4] = 0x00U);                 /* a class must contain its fault */
    EXPECT_BAD(t.test_size = NULL);
    EXPECT_BAD(size_copy[1] = 0.5f);                   /* f1 is not in test 1's fault set */
    EXPECT_BAD(size_copy[0] = -1.0f);
    EXPECT_BAD(size_copy[0] = NAN);
    EXPECT_BAD(t.exoneration_margin = 0.5f);           /* a margin below 1 would exonerate the true fault */
    EXPECT_BAD(t.exoneration_margin = INFINITY);
    EXPECT_BAD(t.sensitivity_margin = 0.9f);
    EXPECT_BAD(t.sensitivity_margin = NAN);
    EXPECT_BAD(env.n_signals = 0U);                    /* the operating envelope (fdi_table_envelope_t) */
    EXPECT_BAD(env.n_signals = (uint8_t)(FDI_TABLE_MAX_ENVELOPE + 1U));
    EXPECT_BAD(env.votes = 0U);
    EXPECT_BAD(env.votes = 3U);                        /* more votes than signals */
    EXPECT_BAD(env.signal = NULL);
    EXPECT_BAD(env.limit = NULL);
    EXPECT_BAD(env_signal[1] = (uint8_t)ROMO_SIG_COUNT); /* beyond the vehicle's signals */
    EXPECT_BAD(env_signal[1] = (uint8_t)ROMO_SIG_VY_M);  /* the same signal twice */
    EXPECT_BAD(env_limit[0] = 0.0f);
    EXPECT_BAD(env_limit[1] = INFINITY);
    EXPECT_BAD(env_limit[1] = NAN);
}

/* A test without a generator yet (gen NULL) is valid data. */
static void test_kind_none_allowed(void **state)
{
    (void)state;
    (void)setup(NULL);
    tests_copy[3].gen = NULL;
    tests_copy[3].input_mask = 0U;
    assert_int_equal(fdi_table_check(&t), FDI_OK);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_kin_table_ok, setup),
        cmocka_unit_test(test_corruptions),
        cmocka_unit_test(test_kind_none_allowed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
