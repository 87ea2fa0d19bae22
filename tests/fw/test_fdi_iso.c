/*
 * test_fdi_iso.c - isolation by signature matching: the kinematic table (every fault uniquely
 * isolable), a table with a non-trivial isolability class, not-evaluable tests, bad arguments, and a
 * brute-force cross-check of every alarm/evaluable pattern against the set definitions.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "fdi_iso.h"
#include "fdi_kin_table.h"
#include "fdi_test_util.h"

#define F(n) (1U << ((n) - 1))

static fdi_iso_result_t iso(const fdi_table_t *t, uint32_t alarm, uint32_t eval, fdi_iso_mode_t mode)
{
    fdi_iso_result_t r;
    assert_int_equal(fdi_iso_run(t, alarm, eval, mode, &r), FDI_OK);
    return r;
}

/* Kinematic table, tests 0..3 = MSO1..4. Expected sets derived by hand from Table II. */
static void test_kinematic_table(void **state)
{
    const fdi_table_t *t = &fdi_kin_table;
    fdi_iso_result_t r;
    (void)state;
    /* nothing alarmed: nothing detected, no candidate */
    r = iso(t, 0U, 0xFU, FDI_ISO_EXONERATION);
    assert_false(r.detected);
    assert_int_equal(r.candidates, 0U);
    assert_int_equal(r.n_classes, 0U);
    /* f4 pattern {MSO1, MSO2, MSO3}: without exoneration f3 (in all MSOs) and f4 remain */
    r = iso(t, 0x7U, 0xFU, FDI_ISO_NO_EXONERATION);
    assert_true(r.detected);
    assert_int_equal(r.candidates, F(3) | F(4));
    assert_int_equal(r.n_classes, 2U);
    assert_false(r.isolated);
    /* with exoneration the quiet MSO4 clears f1, f2, f3, f5: f4 isolated (paper, Sec. V-C) */
    r = iso(t, 0x7U, 0xFU, FDI_ISO_EXONERATION);
    assert_int_equal(r.candidates, F(4));
    assert_true(r.isolated);
    assert_int_equal(r.class_mask, F(4));
    /* f5 pattern {MSO1, MSO2, MSO4} */
    r = iso(t, 0xBU, 0xFU, FDI_ISO_EXONERATION);
    assert_int_equal(r.candidates, F(5));
    /* only MSO3 and MSO4 alarm, as in Fig. 6 for f1/f2/f3 without the others evaluated: */
    r = iso(t, 0xCU, 0xCU, FDI_ISO_EXONERATION);
    assert_int_equal(r.candidates, F(1) | F(2) | F(3));
    /* ... MSO1 not evaluable: it neither accuses nor exonerates; with MSO1 quiet f1 and f3 are cleared */
    r = iso(t, 0xCU, 0xEU, FDI_ISO_EXONERATION);
    assert_int_equal(r.candidates, F(1));
    r = iso(t, 0xCU, 0xFU, FDI_ISO_EXONERATION);
    assert_int_equal(r.candidates, 0U); /* MSO2 quiet clears f2 too: no single fault explains it */
    assert_true(r.detected);
    assert_int_equal(r.n_classes, 0U);
}

/*
 * A 4-fault, 2-test table where f1 and f2 have the same signature (class {f1, f2}) and f3, f4 are unique.
 * test 0: faults 1, 2, 3; test 1: faults 1, 2, 4.
 */
static const char *const names4[4] = {"a", "b", "c", "d"};
static const fdi_test_desc_t tests2[2] = {
    {10U, FDI_GEN_KIN_X_DERIV, 0x7U, FDI_SIGM_ALL, 5.0f, 1.0f, "t0"},
    {11U, FDI_GEN_KIN_Y_DERIV, 0xBU, FDI_SIGM_ALL, 5.0f, 1.0f, "t1"},
};
static const uint32_t sig4[4] = {0x3U, 0x3U, 0x1U, 0x2U};
static const uint32_t class4[4] = {0x3U, 0x3U, 0x4U, 0x8U};
static const fdi_table_t table4 = {FDI_TABLE_FORMAT_VERSION, {0.01f, 0.5f, 0.7071f, 2.0f}, 4U, 2U, names4,
                                   tests2, sig4, class4};

static void test_isolability_class(void **state)
{
    fdi_iso_result_t r;
    (void)state;
    assert_int_equal(fdi_table_check(&table4), FDI_OK);
    r = iso(&table4, 0x3U, 0x3U, FDI_ISO_EXONERATION);
    assert_int_equal(r.candidates, 0x3U); /* f1 and f2 together: never one without the other */
    assert_int_equal(r.class_mask, 0x3U);
    assert_int_equal(r.n_classes, 1U);
    assert_true(r.isolated); /* isolated as far as the structure allows */
    r = iso(&table4, 0x1U, 0x1U, FDI_ISO_EXONERATION); /* test 1 not evaluable */
    assert_int_equal(r.candidates, 0x7U);
    assert_int_equal(r.n_classes, 2U);
    r = iso(&table4, 0x1U, 0x3U, FDI_ISO_EXONERATION);
    assert_int_equal(r.candidates, 0x4U);
    assert_int_equal(r.class_mask, 0x4U);
}

static void test_bad_args(void **state)
{
    fdi_iso_result_t r;
    (void)state;
    assert_int_equal(fdi_iso_run(NULL, 0U, 0U, FDI_ISO_EXONERATION, &r), FDI_BAD_ARG);
    assert_int_equal(fdi_iso_run(&fdi_kin_table, 0U, 0U, FDI_ISO_EXONERATION, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_iso_run(&fdi_kin_table, 0x1U, 0x2U, FDI_ISO_EXONERATION, &r), FDI_BAD_ARG); /* alarm not evaluable */
    assert_int_equal(fdi_iso_run(&fdi_kin_table, 0x10U, 0x10U, FDI_ISO_EXONERATION, &r), FDI_BAD_ARG); /* no test 4 */
    assert_int_equal(fdi_iso_run(&fdi_kin_table, 0U, 0U, (fdi_iso_mode_t)7, &r), FDI_BAD_ARG);
}

/*
 * Every (alarm, evaluable) pair of both tables, both modes, against the definition written per test
 * (a fault is a candidate iff it is in every alarmed test's fault set and, with exoneration, in no quiet
 * evaluable test's fault set); candidates are always whole classes; exoneration only removes candidates.
 */
static void brute_force(const fdi_table_t *t)
{
    const uint32_t all_tests = (1U << t->n_tests) - 1U;
    uint32_t ev;
    for (ev = 0U; ev <= all_tests; ++ev)
    {
        uint32_t al;
        for (al = 0U; al <= all_tests; ++al)
        {
            uint32_t expect_ne;
            uint32_t expect_ex;
            uint32_t f;
            fdi_iso_result_t rn;
            fdi_iso_result_t rx;
            if ((al & ~ev) != 0U)
            {
                continue;
            }
            expect_ne = (al != 0U) ? ((1U << t->n_faults) - 1U) : 0U;
            expect_ex = expect_ne;
            for (f = 0U; f < t->n_tests; ++f)
            {
                const uint32_t bit = 1U << f;
                if ((al & bit) != 0U)
                {
                    expect_ne &= t->tests[f].fault_mask;
                    expect_ex &= t->tests[f].fault_mask;
                }
                else if ((ev & bit) != 0U)
                {
                    expect_ex &= ~t->tests[f].fault_mask;
                }
            }
            rn = iso(t, al, ev, FDI_ISO_NO_EXONERATION);
            rx = iso(t, al, ev, FDI_ISO_EXONERATION);
            assert_int_equal(rn.candidates, expect_ne);
            assert_int_equal(rx.candidates, expect_ex);
            assert_int_equal(rx.candidates & ~rn.candidates, 0U);
            for (f = 0U; f < t->n_faults; ++f)
            {
                if ((rn.candidates & (1U << f)) != 0U)
                {
                    assert_int_equal(rn.candidates & t->iso_class[f], t->iso_class[f]);
                }
            }
            assert_int_equal(rn.class_mask, rn.candidates);
        }
    }
}

static void test_brute_force(void **state)
{
    (void)state;
    brute_force(&fdi_kin_table);
    brute_force(&table4);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_kinematic_table),
        cmocka_unit_test(test_isolability_class),
        cmocka_unit_test(test_bad_args),
        cmocka_unit_test(test_brute_force),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
