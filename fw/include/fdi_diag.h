/*
 * fdi_diag.h - the diagnoser: residual generation, evaluation and isolation for a whole table.
 *
 * One fdi_diag_t owns, per test of the table, a generator (fdi_gen), an evaluator (fdi_eval) and a warm-up
 * counter, and runs the isolation (fdi_iso) after every step. Per step k, for each test i:
 *   usable  = validity & finite(inputs)                      (stale, invalid or NaN/Inf signals drop out)
 *   if kind == NONE or (usable & input_mask_i) != input_mask_i
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
 * Cost per step: sum of the generators (r1, r2 4 filters, r3, r4 8 filters) + ~25 operations per test
 * for evaluation + n_faults iterations of isolation. Measured (scripts/bench_fw.sh, kinematic table, 4
 * tests): ~2,500 instructions per step on Cortex-M4F (qemu -icount), ~2,400 on x86-64 (callgrind).
 * Memory: sizeof(fdi_diag_t) = 2,580 bytes on Cortex-M4F for FDI_DIAG_MAX_TESTS = 16 (~48 + 158 per test
 * slot), caller-owned (static or stack); the library itself has no .data/.bss.
 */
#ifndef FDI_DIAG_H
#define FDI_DIAG_H

#include <stdbool.h>
#include <stdint.h>

#include "fdi_eval.h"
#include "fdi_gen.h"
#include "fdi_iso.h"
#include "fdi_signals.h"
#include "fdi_status.h"
#include "fdi_table.h"

#ifndef FDI_DIAG_MAX_TESTS
#define FDI_DIAG_MAX_TESTS 16U /* capacity; override with -DFDI_DIAG_MAX_TESTS=n (1..32) */
#endif

#if (FDI_DIAG_MAX_TESTS < 1) || (FDI_DIAG_MAX_TESTS > 32)
#error "FDI_DIAG_MAX_TESTS must be in 1..32 (test bitmasks are uint32_t)"
#endif

#define FDI_DIAG_SETTLE_TAUS 6.0f

typedef struct
{
    const fdi_table_t *table; /* must pass fdi_table_check(); must outlive the instance */
    float d_x;                /* velocity sensor position ahead of the CoG [m] */
    float d_y;                /* velocity sensor position left of the CoG [m] */
    float cusum_k;            /* CUSUM drift [sigma], > 0 */
    float cusum_h;            /* CUSUM threshold [sigma], > 0 */
    uint16_t set_count;       /* consecutive raw alarms to set an alarm, >= 1 */
    uint16_t clear_count;     /* consecutive quiet samples to clear it, >= 1 */
    uint16_t warmup_steps;    /* steps after (re)start before a test is evaluable, >= the settling time */
    fdi_iso_mode_t mode;      /* isolation with or without exoneration */
    uint16_t iso_settle_steps;    /* steps a quiet test (and the episode) must last before it exonerates */
    uint16_t episode_clear_steps; /* steps without any alarm that end an episode, >= 1 */
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
} fdi_diag_t; /* opaque by convention */

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
} fdi_diag_result_t;

/* BAD_ARG: NULL or bad config; BAD_TABLE: table fails fdi_table_check(); NOT_FINITE: NaN/Inf in cfg. */
fdi_status_t fdi_diag_init(fdi_diag_t *self, const fdi_diag_config_t *cfg);

/* One fixed step with the current frame; validity uses the FDI_SIGM_* layout. BAD_ARG on NULL only. */
fdi_status_t fdi_diag_step(fdi_diag_t *self, const fdi_inputs_t *inputs, uint32_t validity);

/* Copy the result of the last step (all tests NOT_EVALUABLE before the first step). */
fdi_status_t fdi_diag_result(const fdi_diag_t *self, fdi_diag_result_t *out);

#endif /* FDI_DIAG_H */
