/*
 * fdi_table.h - the diagnosis table: const data exported by the offline structural analysis.
 *
 * The analysis (MSO search, selection, isolability) runs offline; its result is a data-only C file of a
 * vehicle target (fw/vehicles/<vehicle>/generated/fdi_<vehicle>_table.c/.h, written by `fdi-analyze
 * export-c`; a hand-made table of a vehicle target uses the same types) that defines one `const fdi_table_t` and the arrays it points to. There is no code in a table; each test
 * points to the descriptor of its residual generator (fdi_gen.h), provided by the same vehicle target.
 * fdi_table_check() validates a table once (fdi_diag_init() calls it); the diagnoser never trusts an
 * unchecked table.
 *
 * Conventions (binding for the exporter):
 *  - Signals are numbered by bit as in fdi_frame.h: bit k of every signal mask is frame value k; the
 *    vehicle has n_signals of them (1..FDI_FRAME_MAX_SIGNALS) named by signal_names[k].
 *  - Faults are numbered by bit: bit j (0-based) of every fault bitmask is fault index j, the model's j-th
 *    fault (fault_names[j]). A table may carry fewer faults than 32 (n_faults); bits >= n_faults must be
 *    zero everywhere.
 *  - Tests (selected MSO sets, one residual each) are numbered by their position i in tests[]; bit i of a
 *    test bitmask (alarm vector, fault signature) is test i. At most FDI_TABLE_MAX_TESTS tests.
 *  - tests[i].fault_mask is row i of the incidence matrix: the faults that test i is structurally
 *    sensitive to (union of the faults of the MSO's constraints).
 *  - fault_signature[j] is the same matrix by column, i.e. the signature of fault j: bit i set iff
 *    tests[i].fault_mask has bit j. Both forms are exported; fdi_table_check() verifies they agree.
 *  - iso_class[j] is the structural isolability class of fault j: the bitmask of all faults whose
 *    signature equals fault j's (faults with identical signatures cannot be told apart by any selected
 *    test). It contains bit j itself; a fault with a unique signature has a class of one bit. The classes
 *    partition the faults and fdi_table_check() verifies them against the signatures.
 *  - Exoneration (fdi_iso.h, fdi_diag.h): a quiet test clears a fault only where it would have reacted to it.
 *    Where its generator outputs the fault's sensitivity (gen->sens_mask), the diagnoser decides on line:
 *    the alarms imply a size of the fault, and the quiet test clears it when its current sensitivity times
 *    that size reaches sensitivity_margin times its gate. For the other pairs, test_size: an n_faults x
 *    n_tests matrix, row j = fault j, column i = test i, the size of fault j (in the fault's unit) at which
 *    test i reacts (from a fault-size sweep); 0 where test i does not react to fault j within the fault's
 *    physical limits (or is not sensitive to it at all): a quiet test clears fault j only when the tests in
 *    alarm imply, by the same matrix, a size of at least exoneration_margin times the size at which it
 *    reacts. A structurally sensitive but weak test therefore accuses a fault when it alarms and never clears
 *    it. A table without sensitivities and sizes uses 1 for every signature pair and margin 1: the classic
 *    rule (every quiet test of the signature clears the fault).
 *  - tests[i].response_steps: a quiet test takes part in the exoneration only after it has been evaluable and
 *    quiet for this many steps and the isolation episode is that old: the time its residual needs to show a
 *    fault (its filters' and observer's response, for the sensitivity rule; the window in which test_size was
 *    measured, for the size rule).
 *  - tests[i].input_mask must contain every signal the generator reads (gen->input_mask; it may contain
 *    more), and tests[i].gen->sens_mask and rate_mask must lie within tests[i].fault_mask. The generated
 *    generators of a table are slots of one generator set (fdi_gen.h), each used by one test at most.
 *  - Residual evaluation: alarm when r^2 > gate^2 * variance (|r| > gate * sigma); variance is the
 *    fault-free residual variance of the generator at the design point, in (units of r)^2, calibrated inside
 *    the generator's operating domain (fdi_gen_in_domain()); outside it the diagnoser reports the test "not
 *    evaluable".
 *  - gen == NULL marks a selected test without an on-board generator yet: it is always reported "not
 *    evaluable" and therefore neither accuses nor exonerates any fault.
 *  - envelope (optional, NULL: none): the operating envelope the gates were calibrated in, as limits on a few
 *    frame signals (e.g. the vehicle's side-slip velocity, yaw rate and lateral acceleration: the largest values of
 *    the fault-free calibration drives times a margin). The frame is outside the envelope when at least `votes` of
 *    those signals, usable at the step, exceed their limits in magnitude (votes > 1: one faulty sensor alone does
 *    not take the diagnosis out of its envelope). Outside it no gate is validated (a test's model error there is
 *    unknown, e.g. in a spin), so no test is evaluable there and the diagnoser holds its isolation (fdi_diag.h).
 *
 * Memory (flash, 32-bit target): fdi_table_t 60 bytes + 32 bytes per test (fdi_test_desc_t) + 12 bytes per
 * fault (name pointer, signature, class) + 4 bytes per (fault, test) + 4 bytes per signal + the strings; the
 * two struct sizes are asserted below for 32-bit targets. Cost: none at run time.
 */
#ifndef FDI_TABLE_H
#define FDI_TABLE_H

#include <stdint.h>

#include "fdi_gen.h"
#include "fdi_static_assert.h"
#include "fdi_status.h"

#define FDI_TABLE_FORMAT_VERSION 6U /* bump on any change of these types; checked by fdi_table_check() */
#define FDI_TABLE_MAX_ENVELOPE 8U   /* signals of an operating envelope */
#define FDI_TABLE_MAX_FAULTS 32U    /* fault bitmasks are uint32_t */
#define FDI_TABLE_MAX_TESTS 32U     /* test bitmasks are uint32_t */

/* One selected MSO set = one test. */
typedef struct
{
    const fdi_gen_desc_t *gen;  /* residual generator; NULL: none on board yet ("not evaluable") */
    const char *interpretation; /* physical meaning, for logs and tools */
    uint32_t mso_id;            /* MSO number from the analysis (e.g. 3 for MSO3, 433 for MSO433) */
    uint32_t fault_mask;        /* faults the test is sensitive to (bit j = fault j) */
    uint32_t input_mask;        /* frame signals the test reads (fdi_frame.h bit layout) */
    float gate;                 /* threshold in standard deviations, > 0 (e.g. 5) */
    float variance;             /* fault-free residual variance, > 0 */
    uint16_t response_steps;    /* steps a quiet test needs to have reacted to a fault (>= 1; see below) */
} fdi_test_desc_t;

/*
 * Generator design point: the residual variances of the table are valid for exactly these filter and
 * observer settings, so they travel with the table (fdi_diag uses them; see fdi_gen.h).
 */
typedef struct
{
    float dt;        /* sample time [s], > 0 */
    float cutoff_hz; /* cut-off of the derivative filters [Hz], < 0.5 / dt */
    float zeta;      /* damping of the derivative filters */
    float obs_gain;  /* gain of the constant-gain observers [1/s], > 0 */
} fdi_table_design_t;

/* The operating envelope of the calibration (see the header comment). */
typedef struct
{
    uint8_t n_signals;     /* 1..FDI_TABLE_MAX_ENVELOPE */
    uint8_t votes;         /* 1..n_signals: outside when this many usable signals exceed their limits */
    const uint8_t *signal; /* n_signals frame signal indices (< the table's n_signals), distinct */
    const float *limit;    /* n_signals limits on |value|, finite, > 0 */
} fdi_table_envelope_t;

/* The whole diagnosis table. */
typedef struct
{
    uint16_t format_version;         /* FDI_TABLE_FORMAT_VERSION of the exporter */
    fdi_table_design_t design;       /* generator design point */
    uint8_t n_signals;               /* 1..FDI_FRAME_MAX_SIGNALS: frame signals of the vehicle */
    uint8_t n_faults;                /* 1..FDI_TABLE_MAX_FAULTS */
    uint8_t n_tests;                 /* 1..FDI_TABLE_MAX_TESTS */
    const char *const *signal_names; /* n_signals strings, the model's names of the measured signals */
    const char *const *fault_names;  /* n_faults strings, e.g. "f4 vx sensor" */
    const fdi_test_desc_t *tests;    /* n_tests tests */
    const uint32_t *fault_signature; /* n_faults rows: bit i = test i is sensitive to the fault */
    const uint32_t *iso_class;       /* n_faults rows: faults structurally not isolable from the fault */
    const float *test_size;          /* n_faults * n_tests, row-major: size of fault j test i reacts to; 0: never */
    float exoneration_margin;        /* >= 1: reaction-size rule: implied size / reaction size to exonerate */
    float sensitivity_margin;        /* >= 1: on-line rule: |s| * implied size / (gate * sigma) to exonerate */
    const fdi_table_envelope_t *envelope; /* the calibrated operating envelope; NULL: none */
} fdi_table_t;

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT((sizeof(void *) != 4U) || (sizeof(fdi_test_desc_t) == 32U), fdi_sa_test_desc_size);
/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT((sizeof(void *) != 4U) || (sizeof(fdi_table_t) == 60U), fdi_sa_table_size);

/*
 * Validate a table: version, counts, non-NULL arrays and strings, no bits beyond n_signals / n_faults /
 * n_tests, usable generator descriptors (fdi_gen_desc_check) whose signals lie within the test's input mask
 * and whose sensitivities and rate gains within its fault mask, generated generators from one set with each slot
 * at most once and the set's bank within the vehicle's signals, finite positive gate and variance,
 * response_steps >= 1,
 * signature matrix equal to the transposed fault masks, classes equal to the sets of faults with identical
 * signatures, finite non-negative test sizes that are 0 outside the signatures, margins finite and >= 1, an
 * envelope (if any) of 1..FDI_TABLE_MAX_ENVELOPE distinct signals of the frame with finite positive limits and
 * 1..n_signals votes.
 * FDI_OK or FDI_BAD_ARG (NULL) or FDI_BAD_TABLE.
 * Cost: O(n_faults^2 + n_tests * n_faults) bit operations, once at init.
 */
fdi_status_t fdi_table_check(const fdi_table_t *table);

#endif /* FDI_TABLE_H */
