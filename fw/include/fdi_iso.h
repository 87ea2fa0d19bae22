/*
 * fdi_iso.h - fault isolation: pattern matching of the alarm vector against the fault signatures.
 *
 * Single-fault hypotheses, one bit per fault (uint32_t). With A = alarmed tests, Q = evaluable tests
 * that are quiet, sig[j] = signature of fault j (tests sensitive to it), both as test bitmasks:
 *   no exoneration:  j is a candidate  iff  A != 0  and  (A & ~sig[j]) == 0
 *                    (fault j is in the fault set of every alarmed test)
 *   exoneration:     additionally  (Q & sig[j]) == 0  (a quiet, evaluable test clears its faults)
 * Tests that are not evaluable are in neither A nor Q, so they neither accuse nor exonerate. With no alarm
 * there is no candidate (nothing detected). An alarm pattern no single fault explains gives an empty
 * candidate set with `detected` set ("unexplained": multiple faults or a fault outside the model).
 *
 * Isolability classes: faults with equal signatures pass and fail the same tests, so the candidate set
 * is always a union of whole classes (iso_class of the table; never a fault outside the class of a
 * candidate). The result reports
 *   class_mask = union of the classes of the candidates (equals candidates for a checked table),
 *   n_classes  = number of distinct classes among the candidates,
 *   isolated   = (n_classes == 1): the fault is isolated as far as the structure allows; class_mask then
 *                holds the faults structurally not isolable from it (one bit if uniquely isolable).
 * Cost: n_faults iterations of 2-3 AND/compare operations, plus one per candidate class.
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
    uint32_t candidates; /* candidate faults (bit j = fault f(j+1)) */
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
