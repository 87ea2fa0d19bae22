/*
 * fdi_iso.h - fault isolation: pattern matching of the alarm vector against the fault signatures.
 *
 * Single-fault hypotheses, one bit per fault (uint32_t). With A = alarmed tests, Q = evaluable tests
 * that are quiet, sig[j] = signature of fault j (tests sensitive to it), both as test bitmasks:
 *   no exoneration:  j is a candidate  iff  A != 0  and  (A & ~sig[j]) == 0
 *                    (fault j is in the fault set of every alarmed test)
 *   exoneration:     additionally no test of Q & sig[j] clears j. With s(j,i) the size of fault j at which
 *                    test i reacts (table test_size, 0: never within the limits) and the size the alarms
 *                    imply were the fault j, S = max over i in A of s(j,i) (infinite if some s(j,i) = 0),
 *                    quiet test q clears j when s(j,q) > 0 and margin * s(j,q) <= S: at the size the
 *                    alarms imply, q would have reacted. (Sizes 1 and margin 1: the classic rule
 *                    (Q & sig[j]) == 0.) A weak test (s = 0) accuses when it alarms, never clears.
 *                    The sizes come from one manoeuvre (the analysis' sweep); a test whose sensitivity
 *                    depends on the operating point (e.g. through the yaw rate) can still stay quiet where
 *                    it would have reacted there, so a quiet test may clear the true fault: the candidate set
 *                    is then empty or, rarely, another class. The margin guards against it.
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
 * Cost: n_faults iterations of 2-3 AND/compare operations (2 * n_tests more with exoneration for the
 * faults that explain the alarms), plus one per candidate class.
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
 * Isolate. alarm_mask and evaluable_mask are test bitmasks; alarm_mask must be a subset of evaluable_mask
 * and both within n_tests (else BAD_ARG). The table must have passed fdi_table_check().
 */
fdi_status_t fdi_iso_run(const fdi_table_t *table, uint32_t alarm_mask, uint32_t evaluable_mask,
                         fdi_iso_mode_t mode, fdi_iso_result_t *out);

#endif /* FDI_ISO_H */
