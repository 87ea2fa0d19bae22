/*
 * fdi_diag.h - the diagnoser: residual generation, evaluation and isolation for a whole table.
 *
 * One fdi_diag_t owns, per test of the table, a generator (fdi_gen), an evaluator (fdi_eval) and a warm-up
 * counter, and runs the isolation (fdi_iso) after every step. Per step k, for each test i:
 *   usable  = validity & finite(frame)                       (stale, invalid or NaN/Inf signals drop out)
 *   if gen == NULL or (usable & input_mask_i) != input_mask_i
 *      or the frame is outside the generator's operating domain (fdi_gen_in_domain, e.g. a tyre-law
 *      residual near standstill):  status_i = NOT_EVALUABLE, re-arm warm-up
 *   else if first usable step since then: reset the generator at the current inputs, restart the evaluator
 *        and count warmup_steps steps with status NOT_EVALUABLE (the filters settle), then
 *   status_i = fdi_eval(r_i)  (OK or ALARM); a non-finite residual is rejected (NOT_EVALUABLE, re-arm)
 *   isolation on the alarm / evaluable masks in the configured mode (below).
 *
 * Isolation episodes. An episode starts at the first alarm; the tests in alarm at any step of the episode
 * stay accused (latched: a test that reacts only transiently to a step fault still counts) until no test
 * has been in alarm for episode_clear_steps steps. `detected` holds during the episode. With exoneration, a
 * test clears the faults of its table row `exonerating` only once it has had time to react: it must have
 * been evaluable and quiet for iso_settle_steps consecutive steps and the episode must be that old. Before
 * that the candidates are the faults that explain every accused test (no exoneration), which contains the
 * true fault but may span several classes. iso_settle_steps = 0 and episode_clear_steps = 1 give the
 * memoryless rule (isolation on this step's masks only).
 * Signals that no test needs do not matter. fdi_diag_step() returns FDI_OK for invalid or non-finite
 * signals: that is an operating condition reported per test, not an error of the call.
 *
 * Warm-up: fdi_diag_init() rejects warmup_steps shorter than the settling time of the table's design
 * point, FDI_DIAG_SETTLE_TAUS time constants of every filter stage (2 stages: 2 * 6 / (zeta * W)) and
 * of the observer (6 / L), rounded up to whole steps.
 *
 * Fault sensitivities: with cfg->sensitivities the diagnoser asks every generator for d r / d f_j of the
 * faults of its sens_mask at every step (fdi_gen.h) and keeps the last ones: the result lists them per test
 * (sens_offset, sens); without it no sensitivity is computed (no cost) and they stay 0. They are 0 while a
 * test lacks its inputs or its domain; a non-finite sensitivity makes the step fail like a non-finite
 * residual (the test is "not evaluable" and restarts). They do not enter the isolation (yet).
 *
 * Cost per step: sum of the generators + ~25 operations per test for evaluation + n_faults iterations of
 * isolation + one finiteness compare pair per signal. Measured by scripts/bench_fw.sh (instructions per step
 * of a table on x86-64 with callgrind and on Cortex-M4F under qemu -icount; it prints the numbers).
 * Memory: sizeof(fdi_diag_t) ~ 120 + FDI_DIAG_MAX_TESTS * (sizeof(fdi_gen_t) + sizeof(fdi_eval_t) + 13) +
 * 4 * FDI_DIAG_MAX_SENS bytes (bound asserted below; scripts/bench_fw.sh prints the value), caller-owned
 * (static or stack); the library itself has no .data/.bss.
 */
#ifndef FDI_DIAG_H
#define FDI_DIAG_H

#include <stdbool.h>
#include <stdint.h>

#include "fdi_eval.h"
#include "fdi_frame.h"
#include "fdi_gen.h"
#include "fdi_iso.h"
#include "fdi_static_assert.h"
#include "fdi_status.h"
#include "fdi_table.h"

#ifndef FDI_DIAG_MAX_TESTS
#define FDI_DIAG_MAX_TESTS 16U /* capacity; override with -DFDI_DIAG_MAX_TESTS=n (1..32) */
#endif

#if (FDI_DIAG_MAX_TESTS < 1) || (FDI_DIAG_MAX_TESTS > 32)
#error "FDI_DIAG_MAX_TESTS must be in 1..32 (test bitmasks are uint32_t)"
#endif

#ifndef FDI_DIAG_MAX_SENS
#define FDI_DIAG_MAX_SENS 192U /* sensitivities of all tests together; override with -DFDI_DIAG_MAX_SENS=n (1..255) */
#endif

#if (FDI_DIAG_MAX_SENS < 1) || (FDI_DIAG_MAX_SENS > 255)
#error "FDI_DIAG_MAX_SENS must be in 1..255 (offsets are uint8_t)"
#endif

#define FDI_DIAG_SETTLE_TAUS 6.0f

typedef struct
{
    const fdi_table_t *table; /* must pass fdi_table_check(); must outlive the instance */
    float gen_param[FDI_GEN_N_PARAMS]; /* run-time parameters of hand-written generators (fdi_gen.h), finite */
    float cusum_k;            /* CUSUM drift [sigma], > 0 */
    float cusum_h;            /* CUSUM threshold [sigma], > 0 */
    uint16_t set_count;       /* consecutive raw alarms to set an alarm, >= 1 */
    uint16_t clear_count;     /* consecutive quiet samples to clear it, >= 1 */
    uint16_t warmup_steps;    /* steps after (re)start before a test is evaluable, >= the settling time */
    fdi_iso_mode_t mode;      /* isolation with or without exoneration */
    uint16_t iso_settle_steps;    /* steps a quiet test (and the episode) must last before it exonerates */
    uint16_t episode_clear_steps; /* steps without any alarm that end an episode, >= 1 */
    bool sensitivities;           /* compute the generators' fault sensitivities at every step */
} fdi_diag_config_t;

typedef struct
{
    const fdi_table_t *table;
    fdi_gen_param_t par;
    fdi_iso_mode_t mode;
    uint16_t warmup_steps;
    uint16_t iso_settle_steps;
    uint16_t episode_clear_steps;
    uint16_t episode_age; /* steps since the episode started (saturating) */
    uint16_t calm;        /* consecutive steps without an alarm during the episode */
    uint8_t n_tests;
    bool sensitivities;
    uint32_t signals;   /* signals read by some test (finiteness checked once per step) */
    uint32_t accused;   /* tests in alarm at some step of the current episode (0: no episode) */
    uint32_t rearm;     /* tests whose generator must be reset at the next usable step */
    uint32_t alarm;     /* tests in alarm (last step) */
    uint32_t evaluable; /* tests evaluable (last step) */
    fdi_iso_result_t iso;
    fdi_gen_t gen[FDI_DIAG_MAX_TESTS];
    fdi_eval_t eval[FDI_DIAG_MAX_TESTS];
    float residual[FDI_DIAG_MAX_TESTS];
    float ratio[FDI_DIAG_MAX_TESTS];
    uint16_t warm[FDI_DIAG_MAX_TESTS];
    uint16_t quiet_run[FDI_DIAG_MAX_TESTS]; /* consecutive evaluable steps without alarm (saturating) */
    uint8_t sens_offset[FDI_DIAG_MAX_TESTS + 1U]; /* test i: sens[sens_offset[i] .. sens_offset[i + 1] - 1] */
    float sens[FDI_DIAG_MAX_SENS];
} fdi_diag_t; /* opaque by convention */

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(sizeof(fdi_diag_t) <= (128U + (FDI_DIAG_MAX_TESTS * (sizeof(fdi_gen_t) + sizeof(fdi_eval_t) + 13U)) +
                                         (sizeof(float) * FDI_DIAG_MAX_SENS)),
                  fdi_sa_diag_size);

typedef struct
{
    uint8_t n_tests;
    uint32_t alarm_mask;     /* bit i: test i in alarm */
    uint32_t evaluable_mask; /* bit i: test i evaluable */
    fdi_test_status_t status[FDI_DIAG_MAX_TESTS];
    float residual[FDI_DIAG_MAX_TESTS]; /* last residual (0 while not evaluable for lack of inputs) */
    float ratio[FDI_DIAG_MAX_TESTS];    /* last test ratio (0 while not evaluable) */
    uint32_t accused_mask;              /* tests accused in the current isolation episode */
    fdi_iso_result_t iso;               /* candidates and isolability class (detected: episode active) */
    uint8_t sens_offset[FDI_DIAG_MAX_TESTS + 1U]; /* test i's sensitivities: sens[sens_offset[i] ..
                                                     sens_offset[i + 1] - 1], ascending faults of its sens_mask;
                                                     all 0 (none listed) without cfg->sensitivities */
    float sens[FDI_DIAG_MAX_SENS];      /* last sensitivities d r / d f; only the listed entries are written */
} fdi_diag_result_t;

/* Defaults for `table`: settings as validated in tests/fw/test_fdi_diag.c (CUSUM k 1.5, h 150, set 10, clear 100,
   warm-up = the design point's settling time + 20 steps, exoneration after a 3 s settle window, episodes ending
   after 3 s without alarm), generator parameters 0, no sensitivities. BAD_ARG on NULL; BAD_TABLE when the design
   point has no finite settling time (the table itself is checked by fdi_diag_init). */
fdi_status_t fdi_diag_config_default(fdi_diag_config_t *cfg, const fdi_table_t *table);

/* BAD_ARG: NULL or bad config (also: sensitivities requested and the table's generators output more than
   FDI_DIAG_MAX_SENS); BAD_TABLE: table fails fdi_table_check(); NOT_FINITE: NaN/Inf in cfg. */
fdi_status_t fdi_diag_init(fdi_diag_t *self, const fdi_diag_config_t *cfg);

/* One fixed step with the current frame; validity uses the frame's bit layout. BAD_ARG on NULL only. */
fdi_status_t fdi_diag_step(fdi_diag_t *self, const fdi_frame_t *frame, uint32_t validity);

/* Copy the result of the last step (all tests NOT_EVALUABLE before the first step). */
fdi_status_t fdi_diag_result(const fdi_diag_t *self, fdi_diag_result_t *out);

#endif /* FDI_DIAG_H */
