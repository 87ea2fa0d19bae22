/*
 * test_fdi_iso.c - isolation by signature matching: the kinematic table (every fault uniquely
 * isolable), a table with a non-trivial isolability class, not-evaluable tests, bad arguments, and a
 * brute-force cross-check of every alarm/evaluable pattern against the set definitions, exoneration by
 * reaction sizes (weak tests accuse, never clear), and the true fault kept under ideal responses.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <math.h>
#include <stddef.h>

#include <cmocka.h>

#include "fdi_iso.h"
#include "fdi_kin_table.h"
#include "fdi_romo_table.h"
#include "fdi_test_util.h"
#include "fdi_test_vehicle.h"

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
    fdi_table_t kin;
    const fdi_table_t *t = veh_kin_table(&kin);
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
    {NULL, "t0", 10U, 0x7U, 0x1U, 5.0f, 1.0f, 1U},
    {NULL, "t1", 11U, 0xBU, 0x1U, 5.0f, 1.0f, 1U},
};
static const uint32_t sig4[4] = {0x3U, 0x3U, 0x1U, 0x2U};
static const uint32_t class4[4] = {0x3U, 0x3U, 0x4U, 0x8U};
static const float size4[4 * 2] = {1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 0.0f, 0.0f, 1.0f}; /* classic */
static const char *const signal_names[1] = {"s"};
static const fdi_table_t table4 = {FDI_TABLE_FORMAT_VERSION, {0.01f, 0.5f, 0.7071f, 2.0f}, 1U, 4U, 2U, signal_names,
                                   names4, tests2, sig4, class4, size4, 1.0f, 1.0f, NULL};

/*
 * Reaction sizes: 3 faults, 3 tests, all faults in every test (one class), but
 *   f1: test 0 reacts at 1, test 1 at 10, test 2 never (weak);
 *   f2: test 0 at 5, test 1 at 1, test 2 at 1;
 *   f3: test 0 at 2, test 1 at 2, test 2 at 2.
 * Margin 2.
 */
static const char *const names3[3] = {"a", "b", "c"};
static const fdi_test_desc_t tests3[3] = {
    {NULL, "t0", 20U, 0x7U, 0x1U, 5.0f, 1.0f, 1U},
    {NULL, "t1", 21U, 0x7U, 0x1U, 5.0f, 1.0f, 1U},
    {NULL, "t2", 22U, 0x7U, 0x1U, 5.0f, 1.0f, 1U},
};
static const uint32_t sig3[3] = {0x7U, 0x7U, 0x7U};
static const uint32_t class3[3] = {0x7U, 0x7U, 0x7U};
static const float size3[3 * 3] = {1.0f, 10.0f, 0.0f, 5.0f, 1.0f, 1.0f, 2.0f, 2.0f, 2.0f};
static const fdi_table_t table3 = {FDI_TABLE_FORMAT_VERSION, {0.01f, 0.5f, 0.7071f, 2.0f}, 1U, 3U, 3U, signal_names,
                                   names3, tests3, sig3, class3, size3, 2.0f, 1.0f, NULL};

static void test_reaction_sizes(void **state)
{
    fdi_iso_result_t r;
    (void)state;
    assert_int_equal(fdi_table_check(&table3), FDI_OK);
    /* only test 0 alarms: f1 (implied >= 1; test 1 needs 10, test 2 never) stays; f2 implied >= 5, and tests
       1, 2 react at 1 (2 * 1 <= 5): cleared; f3 implied >= 2, tests 1, 2 need 2 (2 * 2 > 2): stays */
    r = iso(&table3, 0x1U, 0x7U, FDI_ISO_EXONERATION);
    assert_int_equal(r.candidates, 0x5U);
    /* tests 0 and 1 alarm, test 2 quiet: f1 implied >= 10, test 2 never reacts to f1: f1 stays; f2
       implied >= 5 and test 2 reacts at 1: cleared; f3 implied >= 2, test 2 at 2: stays */
    r = iso(&table3, 0x3U, 0x7U, FDI_ISO_EXONERATION);
    assert_int_equal(r.candidates, 0x5U);
    /* test 2 (weak for f1) alarms alone: for f1 the implied size is beyond every stated one, so quiet tests
       0 and 1 clear it; f2 implied >= 1: test 1 at 1 needs 2; f3 implied 2: tests 0, 1 at 2 need 4 */
    r = iso(&table3, 0x4U, 0x7U, FDI_ISO_EXONERATION);
    assert_int_equal(r.candidates, 0x6U);
    /* without exoneration every fault explains any alarm here */
    r = iso(&table3, 0x4U, 0x7U, FDI_ISO_NO_EXONERATION);
    assert_int_equal(r.candidates, 0x7U);
}

/*
 * The true fault is never exonerated by an ideal response: fault j of any size m makes exactly the tests
 * with 0 < s(j, i) <= m alarm, every other test is quiet; j must stay a candidate. Checked on the generated
 * ROMO table for every fault and sizes from 0.001 to 10,000 (every decade in 20 steps).
 */
static void test_true_fault_never_exonerated(void **state)
{
    const fdi_table_t *t = &fdi_romo_table;
    const uint32_t nt = (uint32_t)t->n_tests;
    const uint32_t all = (nt >= 32U) ? 0xFFFFFFFFU : ((1U << nt) - 1U);
    uint32_t j;
    (void)state;
    assert_int_equal(fdi_table_check(t), FDI_OK);
    for (j = 0U; j < (uint32_t)t->n_faults; ++j)
    {
        int k;
        for (k = -60; k <= 80; ++k)
        {
            const float m = powf(10.0f, (float)k / 20.0f);
            uint32_t alarm = 0U;
            uint32_t i;
            fdi_iso_result_t r;
            for (i = 0U; i < nt; ++i)
            {
                const float s = t->test_size[(j * nt) + i];
                alarm |= ((s > 0.0f) && (s <= m)) ? (1U << i) : 0U;
            }
            if (alarm == 0U)
            {
                continue;
            }
            r = iso(t, alarm, all, FDI_ISO_EXONERATION);
            assert_true((r.candidates >> j) & 1U);
        }
    }
}

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

/* Reference of the reaction-size rule (fdi_iso.h), in double: does a quiet test of `quiet` clear fault f? A test
   whose generator gives f's sensitivity on line is left to the diagnoser's rule (never clears here). */
static int ref_cleared(const fdi_table_t *t, uint32_t f, uint32_t alarm, uint32_t quiet)
{
    double implied = 0.0;
    int beyond = 0;
    int cleared = 0;
    uint32_t i;
    for (i = 0U; i < t->n_tests; ++i)
    {
        const double s = (double)t->test_size[(f * t->n_tests) + i];
        if ((alarm & (1U << i)) != 0U)
        {
            beyond |= (s <= 0.0) ? 1 : 0;
            implied = (s > implied) ? s : implied;
        }
    }
    for (i = 0U; i < t->n_tests; ++i)
    {
        const double s = (double)t->test_size[(f * t->n_tests) + i];
        const int sees = ((t->tests[i].fault_mask >> f) & 1U) != 0U;
        const int online = (t->tests[i].gen != NULL) && (((t->tests[i].gen->sens_mask >> f) & 1U) != 0U);
        if (((quiet & (1U << i)) != 0U) && sees && !online && (s > 0.0) &&
            ((beyond != 0) || (((double)t->exoneration_margin * s) <= implied)))
        {
            cleared = 1;
        }
    }
    return cleared;
}

/*
 * Every (alarm, evaluable) pair of a table, both modes, against the definition written per test (a fault
 * is a candidate iff it is in every alarmed test's fault set and, with exoneration, no quiet evaluable test
 * clears it by the reaction-size rule; for the classic tables (sizes 1, margin 1): no quiet evaluable test
 * sees it); without exoneration candidates are whole classes; exoneration only removes candidates.
 */
static void brute_force(const fdi_table_t *t, int classic)
{
    const uint32_t all_tests = (1U << t->n_tests) - 1U;
    uint32_t ev;
    for (ev = 0U; ev <= all_tests; ++ev)
    {
        uint32_t al;
        for (al = 0U; al <= all_tests; ++al)
        {
            uint32_t expect_ne;
            uint32_t expect_ex = 0U;
            uint32_t expect_classic;
            uint32_t f;
            fdi_iso_result_t rn;
            fdi_iso_result_t rx;
            if ((al & ~ev) != 0U)
            {
                continue;
            }
            expect_ne = (al != 0U) ? ((1U << t->n_faults) - 1U) : 0U;
            expect_classic = expect_ne;
            for (f = 0U; f < t->n_tests; ++f)
            {
                const uint32_t bit = 1U << f;
                if ((al & bit) != 0U)
                {
                    expect_ne &= t->tests[f].fault_mask;
                    expect_classic &= t->tests[f].fault_mask;
                }
                else if ((ev & bit) != 0U)
                {
                    expect_classic &= ~t->tests[f].fault_mask;
                }
            }
            for (f = 0U; f < t->n_faults; ++f)
            {
                if (((expect_ne >> f) & 1U) && !ref_cleared(t, f, al, ev & ~al))
                {
                    expect_ex |= 1U << f;
                }
            }
            rn = iso(t, al, ev, FDI_ISO_NO_EXONERATION);
            rx = iso(t, al, ev, FDI_ISO_EXONERATION);
            assert_int_equal(rn.candidates, expect_ne);
            assert_int_equal(rx.candidates, expect_ex);
            if (classic)
            {
                assert_int_equal(rx.candidates, expect_classic);
            }
            assert_int_equal(rx.candidates & ~rn.candidates, 0U);
            assert_int_equal(expect_classic & ~rx.candidates, 0U); /* sizes never clear more than classic */
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
    brute_force(&fdi_kin_table, 0);
    brute_force(&fdi_romo_table, 0);
    brute_force(&table4, 1);
    brute_force(&table3, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_kinematic_table),
        cmocka_unit_test(test_isolability_class),
        cmocka_unit_test(test_bad_args),
        cmocka_unit_test(test_brute_force),
        cmocka_unit_test(test_reaction_sizes),
        cmocka_unit_test(test_true_fault_never_exonerated),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
