/*
 * fdi_diag.h - the diagnoser: residual generation, evaluation and isolation for a whole table.
 *
 * One fdi_diag_t owns the generator state of a table (the filter bank of its generator set, the instance filters of
 * its hand-written generators, one observer state per test), per test an evaluator (fdi_eval) and a warm-up
 * counter, and runs the isolation (fdi_iso) after every step. Per step k:
 *   usable  = validity & finite(frame)                       (stale, invalid or NaN/Inf signals drop out)
 *   the bank of the table's generator set (fdi_gen.h) advances once for all tests: a filter runs while its signal is
 *      usable, restarts in steady state when the signal becomes usable again, holds otherwise (a filter that
 *      would overflow holds and makes its signal unusable for the step);
 *   for each test i:
 *   if gen == NULL or (usable & input_mask_i) != input_mask_i
 *      or the frame is outside the generator's operating domain (fdi_gen_in_domain, e.g. a tyre-law
 *      residual near standstill):  status_i = NOT_EVALUABLE, re-arm warm-up
 *   else if first usable step since then: restart the test (a hand-written generator resets its filters, a slot of
 *        the set restarts its observer; the bank is shared and keeps running), restart the evaluator and count
 *        warmup_steps steps with status NOT_EVALUABLE (the filters settle), then
 *   status_i = fdi_eval(r_i)  (OK or ALARM); a non-finite residual is rejected (NOT_EVALUABLE, re-arm)
 *   the set's residuals are computed in one call of its step (shared terms once), then
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
 * of the observer (6 / L), rounded up to whole steps. A bank filter that restarts (its signal usable again) makes
 * every test reading the signal re-arm too (it was not evaluable while the signal was not usable).
 *
 * Fault sensitivities, bounded: with cfg->sensitivities = FDI_DIAG_SENS_EPISODE the diagnoser computes, during an
 * isolation episode (from the step after the first alarm), the sensitivities d r_i / d f_j of ONE test per step, in
 * round robin over the tests that are evaluated at that step (inputs usable, in the domain, warmed up) and have
 * some (gen->sens_mask): a test's values are refreshed every few steps (at most n_tests), from the shared terms of
 * that step; FDI_DIAG_SENS_ALWAYS does the same at every step (tools and tests), FDI_DIAG_SENS_OFF never (no
 * cost). The state keeps only the values of the test refreshed at the last step (FDI_DIAG_MAX_TEST_SENS floats) and
 * the step of each test's last refresh: the isolation reads them per refreshed test (fdi_diag_sens_fresh(),
 * fdi_diag_sens(), valid from the generator stage of fdi_diag_step() on, so inside the isolation of the same step,
 * and after it until the next step). A non-finite sensitivity leaves the test's values unrefreshed (the residual is
 * unaffected).
 *
 * Cost per step: the bank (~20 flops per filter) + the set's step (the shared terms once, each evaluated test's own
 * terms, one test's sensitivities during an episode) + the hand-written generators + ~25 operations per test for
 * evaluation + n_faults iterations of isolation + one finiteness compare pair per signal. Measured by
 * scripts/bench_fw.sh (instructions per step of the vehicle tables it benchmarks over a simulated drive on x86-64
 * with callgrind and on Cortex-M4F under qemu -icount: fault-free, in an episode, largest step).
 * Memory: sizeof(fdi_diag_t) ~ 160 + FDI_DIAG_MAX_TESTS * (sizeof(fdi_eval_t) + 30) + 12 * FDI_DIAG_MAX_FILTERS +
 * 4 * FDI_DIAG_MAX_TEST_SENS bytes (bound asserted below, and at most FDI_DIAG_RAM_BUDGET = 4 KB on a 32-bit
 * target at the configured capacities, also asserted; scripts/bench_fw.sh prints the value), caller-owned (static or
 * stack); the library itself has no .data/.bss.
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
#define FDI_DIAG_MAX_SENS 192U /* all tests' sensitivities (the result's list); -DFDI_DIAG_MAX_SENS=n (1..255) */
#endif

#if (FDI_DIAG_MAX_SENS < 1) || (FDI_DIAG_MAX_SENS > 255)
#error "FDI_DIAG_MAX_SENS must be in 1..255 (offsets are uint8_t)"
#endif

#ifndef FDI_DIAG_MAX_FILTERS
#define FDI_DIAG_MAX_FILTERS 48U /* filter states: the set's bank + the hand-written generators' instance filters;
                                    override with -DFDI_DIAG_MAX_FILTERS=n (1..255) */
#endif

#if (FDI_DIAG_MAX_FILTERS < 1) || (FDI_DIAG_MAX_FILTERS > 255)
#error "FDI_DIAG_MAX_FILTERS must be in 1..255"
#endif

#define FDI_DIAG_MAX_TEST_SENS 32U /* sensitivities of one test (one per fault of the table at most) */

#ifndef FDI_DIAG_RAM_BUDGET
#define FDI_DIAG_RAM_BUDGET 4096U /* sizeof(fdi_diag_t) on a 32-bit target at the configured capacities, at most
                                     (asserted below); raise it with -DFDI_DIAG_RAM_BUDGET=n with larger capacities */
#endif
#define FDI_DIAG_SETTLE_TAUS 6.0f

/* When the diagnoser computes fault sensitivities (one test per step, round robin; see the header comment). */
typedef enum
{
    FDI_DIAG_SENS_OFF = 0,     /* never */
    FDI_DIAG_SENS_EPISODE = 1, /* during isolation episodes */
    FDI_DIAG_SENS_ALWAYS = 2   /* at every step (tools, tests) */
} fdi_diag_sens_mode_t;

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
    fdi_diag_sens_mode_t sensitivities; /* when to compute the generators' fault sensitivities */
} fdi_diag_config_t;

typedef struct
{
    const fdi_table_t *table;
    const fdi_gen_set_t *set; /* the generator set of the table's generated generators; NULL if none */
    fdi_gen_param_t par;
    fdi_iso_mode_t mode;
    fdi_diag_sens_mode_t sens_mode;
    uint16_t warmup_steps;
    uint16_t iso_settle_steps;
    uint16_t episode_clear_steps;
    uint16_t episode_age; /* steps since the episode started (saturating) */
    uint16_t calm;        /* consecutive steps without an alarm during the episode */
    uint8_t n_tests;
    uint8_t sens_next;  /* round robin: the test whose sensitivities come next */
    uint32_t signals;   /* signals read by some test (finiteness checked once per step) */
    uint32_t accused;   /* tests in alarm at some step of the current episode (0: no episode) */
    uint32_t rearm;     /* tests whose generator must be reset at the next usable step */
    uint32_t alarm;     /* tests in alarm (last step) */
    uint32_t evaluable; /* tests evaluable (last step) */
    uint32_t set_tests; /* tests whose generator is a slot of the set */
    uint32_t bank_live; /* signals whose bank filters ran at the last step */
    uint32_t steps;     /* fdi_diag_step calls (saturating) */
    uint32_t sens_fresh; /* tests whose sensitivities were computed at the last step (at most one) */
    fdi_iso_result_t iso;
    fdi_eval_t eval[FDI_DIAG_MAX_TESTS];
    fdi_obs_t obs[FDI_DIAG_MAX_TESTS];       /* observer state of test i's generator */
    fdi_svf_t filt[FDI_DIAG_MAX_FILTERS];    /* the set's bank, then the hand-written generators' filters */
    float residual[FDI_DIAG_MAX_TESTS];
    float ratio[FDI_DIAG_MAX_TESTS];
    uint32_t sens_step[FDI_DIAG_MAX_TESTS];  /* step (1-based) of test i's last sensitivity refresh; 0: never */
    uint16_t warm[FDI_DIAG_MAX_TESTS];
    uint16_t quiet_run[FDI_DIAG_MAX_TESTS]; /* consecutive evaluable steps without alarm (saturating) */
    uint8_t filt_base[FDI_DIAG_MAX_TESTS];  /* hand-written test i: its filters at filt[filt_base[i]] */
    uint8_t slot_test[FDI_GEN_MAX_SLOTS];   /* slot k of the set -> its test */
    uint8_t sens_offset[FDI_DIAG_MAX_TESTS + 1U]; /* the result's layout: test i at sens[sens_offset[i]] .. */
    float sens[FDI_DIAG_MAX_TEST_SENS];     /* the sensitivities of the test in sens_fresh */
} fdi_diag_t; /* opaque by convention */

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(sizeof(fdi_diag_t) <= (160U + (FDI_DIAG_MAX_TESTS * (sizeof(fdi_eval_t) + 30U)) +
                                         (sizeof(fdi_svf_t) * FDI_DIAG_MAX_FILTERS) +
                                         (sizeof(float) * FDI_DIAG_MAX_TEST_SENS) + (sizeof(void *) * 4U)),
                  fdi_sa_diag_size);
/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT((sizeof(void *) != 4U) || (sizeof(fdi_diag_t) <= FDI_DIAG_RAM_BUDGET), fdi_sa_diag_ram_budget);

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
    uint32_t step;                      /* fdi_diag_step calls so far (saturating) */
    uint32_t sens_fresh_mask;           /* tests whose sensitivities were computed at the last step */
    uint32_t sens_step[FDI_DIAG_MAX_TESTS]; /* step of test i's last sensitivity refresh (0: never) */
    uint8_t sens_offset[FDI_DIAG_MAX_TESTS + 1U]; /* test i's sensitivities: sens[sens_offset[i] ..
                                                     sens_offset[i + 1] - 1], ascending faults of its sens_mask;
                                                     all 0 (none listed) with FDI_DIAG_SENS_OFF */
    float sens[FDI_DIAG_MAX_SENS];      /* d r / d f: fdi_diag_result() writes the values of the tests of
                                           sens_fresh_mask and leaves the others as they are in *out (0 before
                                           the first step), so a result kept across steps holds every test's
                                           last refreshed values */
} fdi_diag_result_t;

/* Defaults for `table`: settings as validated in tests/fw/test_fdi_diag.c (CUSUM k 1.5, h 150, set 10, clear 100,
   warm-up = the design point's settling time + 20 steps, exoneration after a 3 s settle window, episodes ending
   after 3 s without alarm), generator parameters 0, no sensitivities (FDI_DIAG_SENS_OFF). BAD_ARG on NULL;
   BAD_TABLE when the design point has no finite settling time (the table itself is checked by fdi_diag_init). */
fdi_status_t fdi_diag_config_default(fdi_diag_config_t *cfg, const fdi_table_t *table);

/* BAD_ARG: NULL or bad config (also: sensitivities requested and the table's generators output more than
   FDI_DIAG_MAX_SENS; the set's bank and the hand-written generators' filters need more than FDI_DIAG_MAX_FILTERS
   states); BAD_TABLE: table fails fdi_table_check(); NOT_FINITE: NaN/Inf in cfg. */
fdi_status_t fdi_diag_init(fdi_diag_t *self, const fdi_diag_config_t *cfg);

/* One fixed step with the current frame; validity uses the frame's bit layout. BAD_ARG on NULL only. */
fdi_status_t fdi_diag_step(fdi_diag_t *self, const fdi_frame_t *frame, uint32_t validity);

/* Copy the result of the last step (all tests NOT_EVALUABLE before the first step); the sensitivities as described
   at fdi_diag_result_t.sens. */
fdi_status_t fdi_diag_result(const fdi_diag_t *self, fdi_diag_result_t *out);

/*
 * The isolation's access to the sensitivities (see the header comment), valid inside fdi_diag_step() once the
 * generators have run (the isolation of the same step) and after it:
 * fdi_diag_sens_fresh: the tests whose sensitivities were computed at this step (bit i = test i; at most one);
 *   0 for NULL.
 * fdi_diag_sens: *values -> *n values d r_i / d f_j of test i, for the faults j of its generator's sens_mask in
 *   ascending order, computed at this step. FDI_OK; BAD_ARG for NULL arguments or a test not refreshed at this
 *   step (nothing written).
 * fdi_diag_sens_step: the step (1-based count of fdi_diag_step() calls) of test i's last refresh; 0: never (or
 *   NULL, or i out of range).
 */
uint32_t fdi_diag_sens_fresh(const fdi_diag_t *self);
fdi_status_t fdi_diag_sens(const fdi_diag_t *self, uint32_t test, const float **values, uint32_t *n);
uint32_t fdi_diag_sens_step(const fdi_diag_t *self, uint32_t test);

#endif /* FDI_DIAG_H */
