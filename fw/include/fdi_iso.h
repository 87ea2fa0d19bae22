/*
 * fdi_iso.h - fault isolation: pattern matching of the alarm vector against the fault signatures.
 *
 * Single-fault hypotheses, one bit per fault (uint32_t). With A = alarmed tests, Q = evaluable tests
 * that are quiet, sig[j] = signature of fault j (tests sensitive to it), both as test bitmasks, and C = the
 * faults some quiet test clears:
 *   j is a candidate  iff  A != 0  and  (A & ~sig[j]) == 0  and  j not in C
 *   (fault j is in the fault set of every alarmed test, and no quiet test says it would have seen j).
 * fdi_iso_match() takes C from the caller: the diagnoser (fdi_diag.h) builds it from the tests' on-line
 * fault sensitivities and from the reaction sizes below. fdi_iso_run() builds it from the reaction sizes
 * only, in one of two modes:
 *   no exoneration:  C = {} (every fault that explains the alarms stays a candidate)
 *   exoneration:     with s(j,i) the size of fault j at which test i reacts (table test_size, 0: never
 *                    within the limits) and the size the alarms imply were the fault j, S = max over i in A
 *                    of s(j,i) (infinite if some s(j,i) = 0), quiet test q clears j when s(j,q) > 0 and
 *                    margin * s(j,q) <= S: at the size the alarms imply, q would have reacted. (Sizes 1 and
 *                    margin 1: the classic rule (Q & sig[j]) == 0.) A weak test (s = 0) accuses when it
 *                    alarms, never clears. Pairs (j, q) for which q's generator outputs the sensitivity to
 *                    j (gen->sens_mask) are left to the on-line rule (fdi_iso_size_cleared skips them).
 *                    Sizes come from one manoeuvre; a test whose sensitivity depends on the operating point
 *                    can still stay quiet where it would have reacted there: the margin guards against it.
 * Tests that are not evaluable are in neither A nor Q, so they neither accuse nor exonerate. With no alarm
 * there is no candidate (nothing detected). An alarm pattern no single fault explains gives an empty
 * candidate set with `detected` set ("unexplained": multiple faults or a fault outside the model).
 *
 * Isolability classes: faults with equal signatures fail the same tests; class_mask reports the whole
 * classes of the candidates (with measured sizes a quiet test may clear one fault of a class and not
 * another, so the candidates can be part of a class). The result reports
 *   class_mask = union of the classes of the candidates (equals candidates under the classic rule),
 *   n_classes  = number of distinct classes among the candidates,
 *   isolated   = (n_classes == 1): the fault is isolated as far as the structure allows; class_mask then
 *                holds the faults structurally not isolable from it (one bit if uniquely isolable).
 * Cost: n_faults iterations of 2-3 AND/compare operations (with exoneration, for each fault that explains the
 * alarms, at most 2 * n_tests more: the tests up to the last quiet one, then up to the last alarmed one), plus one
 * per candidate class.
 * Memory: none (pure function of its arguments).
 */
#ifndef FDI_ISO_H
#define FDI_ISO_H

#include <stdbool.h>
#include <stdint.h>

#include "fdi_status.h"
#include "fdi_table.h"

typedef enum
{
    FDI_ISO_NO_EXONERATION = 0,
    FDI_ISO_EXONERATION = 1
} fdi_iso_mode_t;

typedef struct
{
    uint32_t candidates; /* candidate faults (bit j = fault j of the table) */
    uint32_t class_mask; /* union of the isolability classes of the candidates */
    uint8_t n_classes;   /* distinct classes among the candidates */
    bool detected;       /* at least one test in alarm */
    bool isolated;       /* n_classes == 1 */
} fdi_iso_result_t;

/*
 * Isolate by reaction sizes. alarm_mask and evaluable_mask are test bitmasks; alarm_mask must be a subset of
 * evaluable_mask and both within n_tests (else BAD_ARG). The table must have passed fdi_table_check().
 */
fdi_status_t fdi_iso_run(const fdi_table_t *table, uint32_t alarm_mask, uint32_t evaluable_mask,
                         fdi_iso_mode_t mode, fdi_iso_result_t *out);

/*
 * The faults that the quiet tests `quiet` (test bitmask within n_tests, disjoint from alarm_mask) clear by
 * the reaction-size rule, for the pairs their generators give no sensitivity for. 0 for a NULL table or bad
 * masks. The table must have passed fdi_table_check(). Cannot fail.
 */
uint32_t fdi_iso_size_cleared(const fdi_table_t *table, uint32_t alarm_mask, uint32_t quiet);

/*
 * Isolate with the cleared faults given: candidates = the faults that explain alarm_mask (a test bitmask
 * within n_tests) and are not in `cleared` (a fault bitmask). BAD_ARG on NULL or masks beyond n_tests /
 * n_faults. The table must have passed fdi_table_check().
 */
fdi_status_t fdi_iso_match(const fdi_table_t *table, uint32_t alarm_mask, uint32_t cleared, fdi_iso_result_t *out);

#endif /* FDI_ISO_H */
