/*
 * fdi_table.h - the diagnosis table: const data exported by the offline structural analysis.
 *
 * The analysis (MSO search, selection, isolability) runs offline; its result is a data-only C file
 * (fw/generated/fdi_romo_table.c/.h, written by the exporter; a hand-made kinematic table is in
 * fdi_kin_table.h) that defines one `const fdi_table_t` and the arrays it points to. There is no code in a
 * table. fdi_table_check() validates a table once (fdi_diag_init() calls it); the diagnoser never trusts an
 * unchecked table.
 *
 * Conventions (binding for the exporter):
 *  - Faults are numbered by bit: bit j (0-based) of every fault bitmask is fault index j, which is the
 *    paper's fault f(j+1) in the 25-fault numbering (f1 = ax sensor ... f25 = wheel-4 speed sensor).
 *    A table may carry fewer faults (n_faults); bits >= n_faults must be zero everywhere.
 *  - Tests (selected MSO sets, one residual each) are numbered by their position i in tests[]; bit i of a
 *    test bitmask (alarm vector, fault signature) is test i. At most FDI_TABLE_MAX_TESTS tests.
 *  - tests[i].fault_mask is row i of the incidence matrix: the faults that test i is structurally
 *    sensitive to (union of the faults of the MSO's constraints, eq. 1 of the paper).
 *  - fault_signature[j] is the same matrix by column, i.e. the signature of fault j: bit i set iff
 *    tests[i].fault_mask has bit j. Both forms are exported; fdi_table_check() verifies they agree.
 *  - iso_class[j] is the structural isolability class of fault j: the bitmask of all faults whose
 *    signature equals fault j's (method B of the paper: faults with identical signatures cannot be told
 *    apart by any selected test). It contains bit j itself; a fault with a unique signature has a class of
 *    one bit. The classes partition the faults and fdi_table_check() verifies them against the signatures.
 *  - test_size (format 3) is an n_faults x n_tests matrix, row j = fault j, column i = test i: the size of
 *    fault j (in the fault's unit) at which test i reacts, from the analysis' fault-size sweep; 0 where test
 *    i does not react to fault j within the fault's physical limits (or is not sensitive to it at all). It
 *    decides exoneration (fdi_iso.h): a quiet test clears fault j only when the tests in alarm imply, were
 *    the fault j, a size of at least exoneration_margin times the size at which the quiet test reacts. A
 *    structurally sensitive but weak test therefore accuses a fault when it alarms and never clears it.
 *    A table without measured sizes uses 1 for every signature pair and margin 1: the classic rule (every
 *    quiet test of the signature clears the fault).
 *  - tests[i].input_mask uses the FDI_SIGM_* layout of fdi_signals.h and must contain every signal the
 *    generator of tests[i].kind reads (it may contain more).
 *  - Residual evaluation: alarm when r^2 > gate^2 * variance (|r| > gate * sigma); variance is the
 *    fault-free residual variance of the generator at the configured filters, in (units of r)^2.
 *  - kinds FDI_GEN_GENERATED_<n> run the generated generator of slot n-1 (fw/generated/, written by the
 *    exporter with the table); a kind whose generator is not linked (no inputs) fails the check. The
 *    generated file also carries each generator's operating domain (fdi_gen_in_domain(), e.g. a minimum
 *    speed for tyre-law residuals); the variance is calibrated inside that domain only, and outside it the
 *    diagnoser reports the test "not evaluable". The domain is code, not table data: the table format is
 *    unchanged.
 *  - kind FDI_GEN_NONE marks a selected test without an on-board generator yet: it is always reported
 *    "not evaluable" and therefore neither accuses nor exonerates any fault.
 *
 * Memory (flash): ~48 bytes + 32 bytes per test + 8 bytes per fault + 4 bytes per (fault, test) + the strings. Cost: none at run time.
 */
#ifndef FDI_TABLE_H
#define FDI_TABLE_H

#include <stdint.h>

#include "fdi_status.h"

#define FDI_TABLE_FORMAT_VERSION 3U /* bump on any change of these types; checked by fdi_table_check() */
#define FDI_TABLE_MAX_FAULTS 32U    /* fault bitmasks are uint32_t */
#define FDI_TABLE_MAX_TESTS 32U     /* test bitmasks are uint32_t */

/* Residual generator of a test. Values are stable (the exporter writes the names). */
typedef enum
{
    FDI_GEN_NONE = 0,         /* no on-board generator yet: test always "not evaluable" */
    FDI_GEN_KIN_X_DERIV = 1,  /* MSO1 {K1,D1,S1,S3,S4,S5}: r1 = ax_m - (d/dt vx - vy w), [m/s^2] */
    FDI_GEN_KIN_Y_DERIV = 2,  /* MSO2 {K2,D2,S2,S3,S4,S5}: r2 = ay_m - (d/dt vy + vx w), [m/s^2] */
    FDI_GEN_KIN_ARR3 = 3,     /* MSO3 {K1,K2,D1,D2,S1..S4}, eq. 8-10, no vy_m, [m/s^2 * rad^2/s^2] */
    FDI_GEN_KIN_ARR4 = 4,     /* MSO4 {K1,K2,D1,D2,S1,S2,S3,S5}, no vx_m, [m/s^2 * rad^2/s^2] */
    FDI_GEN_KIN_X_OBS = 5,    /* MSO1 by an observer on vx' = ax_m + vy w: r = y - xh, [m/s] */
    FDI_GEN_KIN_Y_OBS = 6,    /* MSO2 by an observer on vy' = ay_m - vx w: r = y - xh, [m/s] */
    /* Generated generators (fw/generated/fdi_romo_generators.c, slot = kind - FDI_GEN_GENERATED_1). */
    FDI_GEN_GENERATED_1 = 7,
    FDI_GEN_GENERATED_2 = 8,
    FDI_GEN_GENERATED_3 = 9,
    FDI_GEN_GENERATED_4 = 10,
    FDI_GEN_GENERATED_5 = 11,
    FDI_GEN_GENERATED_6 = 12,
    FDI_GEN_GENERATED_7 = 13,
    FDI_GEN_GENERATED_8 = 14,
    FDI_GEN_GENERATED_9 = 15,
    FDI_GEN_GENERATED_10 = 16,
    FDI_GEN_GENERATED_11 = 17,
    FDI_GEN_GENERATED_12 = 18,
    FDI_GEN_GENERATED_13 = 19,
    FDI_GEN_GENERATED_14 = 20,
    FDI_GEN_GENERATED_15 = 21,
    FDI_GEN_GENERATED_16 = 22
} fdi_gen_kind_t;

#define FDI_GEN_KIND_COUNT 23U
#define FDI_GEN_GENERATED_MAX 16U /* slots for generated generators */

/* One selected MSO set = one test. */
typedef struct
{
    uint32_t mso_id;            /* MSO number from the analysis (e.g. 3 for MSO3 of Table II, 433 for MSO433) */
    fdi_gen_kind_t kind;        /* residual generator, see fdi_gen_kind_t */
    uint32_t fault_mask;        /* faults the test is sensitive to (bit j = fault f(j+1)) */
    uint32_t input_mask;        /* measured signals the generator reads (FDI_SIGM_*) */
    float gate;                 /* threshold in standard deviations, > 0 (e.g. 5) */
    float variance;             /* fault-free residual variance, > 0 */
    const char *interpretation; /* physical meaning, for logs and tools (Table II text) */
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
    float obs_gain;  /* gain of the observer-based generators [1/s], > 0 */
} fdi_table_design_t;

/* The whole diagnosis table. */
typedef struct
{
    uint16_t format_version;        /* FDI_TABLE_FORMAT_VERSION of the exporter */
    fdi_table_design_t design;      /* generator design point */
    uint8_t n_faults;               /* 1..FDI_TABLE_MAX_FAULTS */
    uint8_t n_tests;                /* 1..FDI_TABLE_MAX_TESTS */
    const char *const *fault_names; /* n_faults strings, e.g. "f4 vx sensor" */
    const fdi_test_desc_t *tests;   /* n_tests tests */
    const uint32_t *fault_signature; /* n_faults rows: bit i = test i is sensitive to the fault */
    const uint32_t *iso_class;      /* n_faults rows: faults structurally not isolable from the fault */
    const float *test_size;         /* n_faults * n_tests, row-major: size of fault j test i reacts to; 0: never */
    float exoneration_margin;       /* >= 1: how much larger the implied fault size must be to exonerate */
} fdi_table_t;

/*
 * Validate a table: version, counts, non-NULL arrays and strings, no bits beyond n_faults / n_tests /
 * FDI_SIGM_ALL, known generator kinds, input masks covering each generator's signals, finite positive
 * gate and variance, signature matrix equal to the transposed fault masks, classes equal to the sets of
 * faults with identical signatures, finite non-negative test sizes that are 0 outside the signatures,
 * margin finite and >= 1. FDI_OK or FDI_BAD_ARG (NULL) or FDI_BAD_TABLE.
 * Cost: O(n_faults^2 + n_tests * n_faults) bit operations, once at init.
 */
fdi_status_t fdi_table_check(const fdi_table_t *table);

#endif /* FDI_TABLE_H */
