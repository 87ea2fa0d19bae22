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
 *      residual near standstill) or its range (fdi_gen_in_range, e.g. the tyres far from their linear range):
 *      status_i = NOT_EVALUABLE, re-arm warm-up
 *   else if first usable step since then: restart the test (a hand-written generator resets its filters, a slot of
 *        the set restarts its observer; the bank is shared and keeps running), restart the evaluator and count
 *        warmup_steps steps with status NOT_EVALUABLE (the filters settle; reentry_steps for a slot of the set that
 *        only its range or the envelope held out, its signals usable and in its domain all along: its filters ran
 *        on), then
 *   status_i = fdi_eval(r_i)  (OK or ALARM); a non-finite residual is rejected (NOT_EVALUABLE, re-arm)
 *   the set's residuals (and, when asked for, all its sensitivities) are computed in one call of its step (shared
 *   terms once), then
 *   isolation on the alarm / evaluable masks in the configured mode (below).
 *
 * Isolation episodes. An episode starts at the first alarm; the tests in alarm at any step of the episode
 * stay accused (latched: a test that reacts only transiently to a step fault still counts) until no test
 * has been in alarm for episode_clear_steps steps. `detected` holds during the episode. The candidates are
 * the faults that explain every accused test and that no quiet test clears (fdi_iso.h). With exoneration, a
 * quiet test takes part once it has had time to react: it has been evaluable and quiet for its
 * response_steps (table) plus set_count (the alarm's confirmation) and the episode is that old. It clears
 * fault j
 *   - on line, where its generator gives j's sensitivity (gen->sens_mask): during an episode the diagnoser
 *     asks the generators for their sensitivities s_ij = d r_i / d f_j at the current operating point (those
 *     the rule reads at the step: of the tests in alarm for their response time or settled and quiet, and
 *     only while one of their faults is undecided: it explains every accused test and is not latched; each test's
 *     every sens_every steps, the tests in turn, grouped by their number of sensitivities so that a step computes
 *     about 1 / sens_every of them; a rule keeps a test's last values, or its last decision, in between). Each
 *     test i in alarm for at least its response_steps, whose residual has settled (within a fifth plus 2
 *     sigma of both its 0.1 s and 0.3 s averages: a step through a filtered derivative first kicks a residual
 *     far above its steady value), bounds the size of every fault j of its sensitivities from below,
 *     f_j >= (min(|r_i|, |0.1 s average|) - noise_allowance sigma_i) / |s_ij|,
 *     and the largest recent bound is the size the alarms imply, F_j (the bounds are forgotten with a 1 s time
 *     constant: where an alarmed test's sensitivity passes near zero its bound spikes). A fault j of test i's
 *     signature that its generator lists no sensitivity for has a steady-state sensitivity of
 *     exactly zero (fdi_gen.h: it reaches r_i only through a filtered derivative, e.g. a vx offset in
 *     a_x = d vx / dt - psidot vy): its size gets no bound from test i, because a drift of j (a steady rate)
 *     explains the settled alarm as well as a constant size of a fault of its sensitivities does. Where the
 *     generator lists j's rate gain g_ij (gen->rate_mask), the alarm bounds how fast j moves instead: under j
 *     alone r_i = g_ij d/dt (f_j through the filters) + noise, whatever the shape of f_j (a step's decaying
 *     kick, a drift's steady value), so at every step of the alarm (from its first, settled or not) f_j moves
 *     by at least rho_j dt, rho_j = (|r_i| - noise_allowance sigma_i) / |g_ij| signed as r_i / g_ij, and the
 *     moves add up over the episode (opposite ones cancel): F_j >= |sum of rho_j dt| for a fault absent before
 *     the episode (e.g. a vx sensor drift that explains an a_x test's steady alarm has moved by 0.4 m/s after
 *     1 s of an alarm at 0.5 m/s^2, and the tyre tests that see vx would show it). A settled quiet test q
 *     clears j when |s_qj| F_j >= sensitivity_margin * gate_q * sigma_q: at that size it would have crossed its
 *     gate with margin. Several settled quiet tests clear j together where none does alone: with the
 *     sensitivities taken sensitivity_margin times smaller, test q would show a response its residual lacks by
 *     d_q = (|s_qj| F_j / sensitivity_margin - max(|r_q|, |0.1 s average|)) / (gate_q sigma_q) gates, and j is
 *     cleared when the positive d_q reach 1 in the sum of their squares (for one test with a zero residual
 *     this is the single-test rule). The decision is re-made at every step (operating points change); j leaves
 *     the candidates once the rule has cleared it for 0.1 s in a row;
 *   - by the reaction sizes (test_size) for the pairs without an on-line sensitivity (fdi_iso_size_cleared).
 * The first class isolated in an episode is latched: exoneration no longer removes its faults (the on-line
 * rule is a linearisation: a later operating point may make a quiet test look as if it should have seen the
 * true fault). An accused test that none of them explains contradicts it: several faults, or the vehicle in a
 * state no test was calibrated for (a spin); the episode then stays "detected, not isolated" (no candidate)
 * until it ends, rather than name another class.
 * Before any quiet test has settled, the candidates are all the faults that explain the alarms, which
 * contains the true fault but may span several classes. episode_clear_steps = 1 and response_steps of 1
 * give the memoryless rule (isolation on this step's masks only).
 * Operating envelope: where the table has one (fdi_table.h) and at least `votes` of its signals usable at the step
 * exceed their limits, the gates are not validated, so no test is evaluable (as outside its operating domain: it
 * restarts and warms up when back inside, so no evidence gathered outside, e.g. in its CUSUM, carries over), and an
 * open episode holds: its accused tests and its result stay, it neither ends for want of alarms nor loses its
 * isolation for want of exonerating tests. (A fault that spins the vehicle makes tests blind to it alarm at their
 * gates, whose model error was never calibrated there; isolating on those alarms names a wrong class.)
 * Warm-up: fdi_diag_init() rejects warmup_steps shorter than the settling time of the table's design
 * point, FDI_DIAG_SETTLE_TAUS time constants of every filter stage (2 stages: 2 * 6 / (zeta * W)) and
 * of the observer (6 / L), rounded up to whole steps.
 *
 * Adaptive thresholds (cfg->adaptive): a generated generator whose residual depends on the table's uncertain
 * quantities (parameters known within a range, unknown parameters and inputs the residual is not decoupled from:
 * the model's declarations) computes at every step its worst-case spread a_i = sum |d r_i / d theta| * dtheta from
 * its operating point (fdi_gen.h); test i then alarms where the residual exceeds gate_i * sigma_i + a_i
 * (fdi_eval.h), so a vehicle anywhere in the envelope stays quiet however far its residual sits from 0 where the
 * sensitivity is large, and the test keeps its full resolution where it is small. The exoneration counts the spread
 * as unexplained-by-the-fault: an alarmed test's implied sizes and drifts are those of the residual beyond noise
 * allowance plus spread, and a quiet test clears a fault only where its response would exceed margin * gate * sigma
 * + 2 a_i (the uncertainty may hide up to a_i of it and has raised the threshold by as much). Without
 * cfg->adaptive, or for hand-written generators, a_i = 0: the fixed gates.
 *
 * On-line estimation (cfg->estimate, fdi_est.h): for each test of the mask, a Kalman filter estimates the deviations
 * of the quantities its generator declares estimable (fdi_gen_desc_t.est: a few of the table's uncertain quantities,
 * e.g. a rolling radius and the mass for a wheel's spin test; quantities entering as constants lumped into one offset,
 * e.g. an accelerometer bias plus the grade) from the residual, their sensitivities at the step as regressors
 * (io->reg of the set's step; 1 for a hand-written generator's offsets). The test evaluates the innovation
 * nu_i = r_i - h_i . theta_i against gate_i * sigma_i + kappa * sqrt(h_i' P_i h_i) + a_i, a_i the generator's spread
 * over the quantities it does not estimate (so with estimation the threshold is adaptive whatever cfg->adaptive
 * says): as wide as the declared envelope while the filter knows nothing of the vehicle, narrowing to the test's own
 * noise as it learns; after the test's first warm-up the filter learns for estimate_startup steps before the test is
 * evaluable. Its result's residual is nu_i and its offset h_i . theta_i (what the estimate removed). The
 * filter is frozen (it predicts only: the estimate stays, its uncertainty grows by the declared drift) while the
 * test alarms and for the rest of an isolation episode that accuses it, so a fault that set its alarm is not
 * absorbed; other tests' episodes do not hold it. It updates only while the test is evaluable (after the warm-up, in
 * its domain and envelope); a restarted test keeps its estimate. What the estimator cannot tell from a fault (one
 * present at start-up, one slower than the quantities' declared drift, up to their declared bounds) is stated in
 * fdi_est.h. Without cfg->estimate but with cfg->adaptive, a_i also holds the estimable quantities at their
 * declared widths: the whole envelope.
 *
 * Fault sensitivities: at every step with cfg->sensitivities the diagnoser asks every generator for d r / d f_j
 * of the faults of its sens_mask (fdi_gen.h) and keeps the last ones: the result lists them per test (sens_offset,
 * sens; all offsets 0 without cfg->sensitivities). Without cfg->sensitivities they are computed only during an
 * isolation episode (from its second step, with exoneration), and only those the on-line rule reads, each test's at
 * its turn (sens_every, above); outside episodes, and once no fault is left to decide, none (no cost). They are 0 while a test lacks its inputs or its domain; a non-finite
 * sensitivity makes the step fail like a non-finite residual (the test is "not evaluable" and restarts).
 *
 * Cost per step: the bank (per running filter 4 multiplications, 7 additions and one finiteness check) + the set's
 * step (the shared terms once, each evaluated test's own terms, the sensitivities the on-line rule reads during an
 * episode at their turn, all of them with cfg->sensitivities) + the hand-written generators + the evaluation of each
 * evaluated test (fdi_eval.h) + n_faults iterations of isolation (while a fault is undecided, for each settled quiet
 * or alarmed test, its sensitivities of the undecided faults for the implied sizes and the clearing rules, which
 * visit only those faults, plus the reaction-size rule) + the finiteness of the signals (fdi_frame_finite_mask).
 * Measured, not estimated, by scripts/bench_fw.sh: instructions per step of the vehicle tables it benchmarks over a
 * simulated drive on x86-64 with callgrind and on Cortex-M4F under qemu -icount (fault-free, in an episode with one
 * class left, in one with several (undecided), largest step), and on the Cortex-M4F per function: instructions per
 * step, calls per step and instructions a call (its profile, scripts/profile_m4.sh).
 * Memory: sizeof(fdi_diag_t) <= 224 + 2 * sizeof(void *) + FDI_DIAG_MAX_TESTS * (sizeof(fdi_eval_t) +
 * sizeof(fdi_obs_t) + sizeof(fdi_est_t) + 43) + 12 * FDI_DIAG_MAX_FILTERS + 4 * FDI_DIAG_MAX_SENS +
 * 10 * FDI_TABLE_MAX_FAULTS + 2 * FDI_GEN_MAX_SLOTS + 4 * FDI_DIAG_MAX_SENS_EVERY bytes (asserted below;
 * scripts/bench_fw.sh prints the value), caller-owned (static or stack); the library itself has no .data/.bss. A
 * step also takes 4 * FDI_DIAG_MAX_TESTS * (1 + FDI_EST_MAX_PARAMS) bytes of stack for the residuals and regressors.
 */
#ifndef FDI_DIAG_H
#define FDI_DIAG_H

#include <stdbool.h>
#include <stdint.h>

#include "fdi_est.h"
#include "fdi_eval.h"
#include "fdi_frame.h"
#include "fdi_gen.h"
#include "fdi_iso.h"
#include "fdi_static_assert.h"
#include "fdi_status.h"
#include "fdi_table.h"
/* FDI_DIAG_MAX_TESTS (tests), FDI_DIAG_MAX_SENS (sensitivities of all tests together), FDI_DIAG_MAX_FILTERS (the
   set's bank + the hand-written generators' instance filters): overridable capacities, generated/fdi_capacity.h */
#include "generated/fdi_capacity.h"

#define FDI_DIAG_SETTLE_TAUS 6.0f
#define FDI_DIAG_MAX_SENS_EVERY 16U /* fdi_diag_config_t.sens_every */
#define FDI_DIAG_CONTRADICTED 0xFFFFFFFFU /* latched: the isolated class was contradicted in this episode */

typedef struct
{
    const fdi_table_t *table; /* must pass fdi_table_check(); must outlive the instance */
    float gen_param[FDI_GEN_N_PARAMS]; /* run-time parameters of hand-written generators (fdi_gen.h), finite */
    float cusum_k;            /* CUSUM drift [sigma], > 0 */
    float cusum_h;            /* CUSUM threshold [sigma], > 0 */
    uint16_t set_count;       /* consecutive raw alarms to set an alarm, >= 1 */
    uint16_t clear_count;     /* consecutive quiet samples to clear it, >= 1 */
    uint16_t warmup_steps;    /* steps after (re)start before a test is evaluable, >= the settling time */
    uint16_t reentry_steps;   /* steps a generated test waits back in its range or the envelope, its signals usable
                                 and in its domain all along (its filters ran on; its observer restarts),
                                 1 .. warmup_steps */
    fdi_iso_mode_t mode;      /* isolation with or without exoneration */
    uint16_t episode_clear_steps; /* steps without any alarm that end an episode, >= 1 */
    float noise_allowance;        /* sigmas of an alarmed residual not counted as fault response, >= 0 */
    bool sensitivities;           /* compute and report the generators' fault sensitivities at every step */
    uint16_t sens_every;          /* without `sensitivities`: during an episode, steps between two computations of
                                     a test's sensitivities, the tests in turn (<= FDI_DIAG_MAX_SENS_EVERY; 0 and 1:
                                     at every step) */
    bool adaptive;                /* adaptive thresholds: each test of the set alarms beyond gate * sigma plus its
                                     generator's spread over the table's uncertainty at the step (fdi_gen.h); false:
                                     the fixed gates */
    uint32_t estimate;            /* tests (bit i: test i) whose generator's estimable quantities are estimated on
                                     line ("On-line estimation" above; each must declare some); 0: none */
    float estimate_kappa;         /* the threshold's multiple of an estimate's prediction spread sqrt(h' P h), >= 0
                                     (read when estimate != 0) */
    float estimate_decorrelation; /* D >= 1: the estimators take the residual's variance per sample as sigma^2 * D
                                     and the declared drifts' q as D q (what the model leaves unexplained is
                                     correlated over about D samples; fdi_est.h) (read when estimate != 0) */
    uint16_t estimate_startup;    /* updates an estimator makes after its test's first warm-up before the test is
                                     evaluable (it learns the vehicle; later restarts keep the estimate) */
} fdi_diag_config_t;

typedef struct
{
    const fdi_table_t *table;
    const fdi_gen_set_t *set; /* the generator set of the table's generated generators; NULL if none */
    fdi_gen_param_t par;
    fdi_iso_mode_t mode;
    uint16_t warmup_steps;
    uint16_t reentry_steps; /* fdi_diag_config_t.reentry_steps */
    uint16_t episode_clear_steps;
    uint16_t set_count; /* the evaluators' alarm delay, added to every test's response_steps */
    float noise_allowance;
    float fast_gain; /* dt / tau of the residuals' fast average */
    float implied_keep; /* 1 - dt / tau of the implied sizes' forgetting */
    uint16_t clear_confirm; /* steps the on-line rule must clear a fault before it leaves the candidates */
    uint8_t n_faults;
    float slow_gain; /* dt / tau of the residuals' slow average */
    uint16_t episode_age; /* steps since the episode started (saturating) */
    uint16_t calm;        /* consecutive steps without an alarm during the episode */
    uint8_t n_tests;
    bool sensitivities;
    bool adaptive;      /* fdi_diag_config_t.adaptive */
    uint32_t estimate;  /* fdi_diag_config_t.estimate */
    float est_kappa;    /* fdi_diag_config_t.estimate_kappa */
    float est_decorrelation; /* fdi_diag_config_t.estimate_decorrelation */
    uint16_t est_startup;    /* fdi_diag_config_t.estimate_startup */
    uint8_t sens_every; /* fdi_diag_config_t.sens_every */
    uint8_t n_domains;  /* runs of consecutive tests whose generators share a domain function (runnable()) */
    uint32_t signals;   /* signals read by some test (finiteness checked once per step) */
    uint32_t accused;   /* tests in alarm at some step of the current episode (0: no episode) */
    uint32_t rearm;     /* tests whose generator must be reset at the next usable step */
    uint32_t held;      /* tests of rearm held out by their range or the envelope only: back after reentry_steps */
    uint32_t alarm;     /* tests in alarm (last step) */
    uint32_t evaluable; /* tests evaluable (last step) */
    uint32_t set_tests; /* tests whose generator is a slot of the set */
    uint32_t gen_tests; /* tests with a generator */
    uint32_t range_tests; /* tests whose generator has a range (fdi_gen_desc_t.in_range) */
    uint32_t inputs;    /* signals read by some test */
    uint32_t sens_tests; /* tests whose generator outputs at least one sensitivity */
    bool slots_in_order; /* every test of the set is its slot (masks of tests are masks of slots) */
    uint32_t size_tests; /* tests with a reaction size for a fault they give no sensitivity of (fdi_iso) */
    uint32_t bank_live; /* signals whose bank filters ran at the last step */
    bool in_envelope;   /* the last frame was inside the table's calibrated envelope (or it has none) */
    fdi_iso_result_t iso;
    uint32_t iso_accused; /* the accused tests and cleared faults iso was matched with (iso_valid) */
    uint32_t iso_cleared;
    bool iso_valid;
    uint32_t size_accused; /* the accused tests and settled quiet tests size_cleared was computed for */
    uint32_t size_quiet;
    uint32_t size_cleared; /* faults the reaction-size rule clears (fdi_iso_size_cleared) */
    fdi_eval_t eval[FDI_DIAG_MAX_TESTS];
    fdi_obs_t obs[FDI_DIAG_MAX_TESTS];     /* observer state of test i's generator */
    fdi_est_t est[FDI_DIAG_MAX_TESTS];     /* test i's estimator (estimate) */
    fdi_svf_t filt[FDI_DIAG_MAX_FILTERS];  /* the set's bank, then the hand-written generators' filters */
    uint8_t filt_base[FDI_DIAG_MAX_TESTS]; /* hand-written test i: its filters at filt[filt_base[i]] */
    uint8_t slot_test[FDI_GEN_MAX_SLOTS];  /* slot k of the set -> its test */
    uint8_t slot_sens[FDI_GEN_MAX_SLOTS];  /* slot k of the set -> its test's first sensitivity in sens[] */
    uint8_t domain_test[FDI_DIAG_MAX_TESTS];   /* run k: its first test */
    uint32_t domain_tests[FDI_DIAG_MAX_TESTS]; /* run k: its tests */
    float residual[FDI_DIAG_MAX_TESTS];
    float ratio[FDI_DIAG_MAX_TESTS];
    float spread[FDI_DIAG_MAX_TESTS]; /* test i's adaptive threshold term at the step (0: the fixed gate) */
    float correction[FDI_DIAG_MAX_TESTS]; /* test i's estimate's share of its residual, h . theta, at the step */
    uint16_t warm[FDI_DIAG_MAX_TESTS];
    uint16_t est_seen[FDI_DIAG_MAX_TESTS]; /* updates of test i's estimator so far, up to est_startup */
    uint16_t quiet_run[FDI_DIAG_MAX_TESTS]; /* consecutive evaluable steps without alarm (saturating) */
    uint16_t alarm_run[FDI_DIAG_MAX_TESTS]; /* consecutive steps in alarm (saturating) */
    uint32_t clears[FDI_DIAG_MAX_TESTS];    /* faults each settled quiet test clears on line (last decision) */
    float implied[FDI_TABLE_MAX_FAULTS];    /* fault sizes the recent alarms imply (to first order) */
    float drift[FDI_TABLE_MAX_FAULTS];      /* signed drift each fault's rate bounds add up to in the episode */
    uint32_t rate_tests; /* tests whose generator lists rate gains */
    uint16_t cleared_run[FDI_TABLE_MAX_FAULTS]; /* consecutive steps the on-line rule cleared each fault */
    float r_fast[FDI_DIAG_MAX_TESTS];       /* each residual's average over 0.1 s ... */
    float r_slow[FDI_DIAG_MAX_TESTS];       /* ... and over 0.3 s (whether it has settled) */
    uint32_t fresh;                         /* tests whose sensitivities were computed at the last step */
    uint32_t sens_known; /* tests whose sensitivities were computed in this episode (and kept since) */
    uint32_t turns[FDI_DIAG_MAX_SENS_EVERY]; /* the tests whose sensitivities are computed at each step of sens_every */
    uint32_t latched; /* faults isolated first in the episode (exonerated no more), or FDI_DIAG_CONTRADICTED */
    uint32_t undecided; /* faults that explain every accused test and are not latched (on-line exoneration) */
    uint8_t sens_offset[FDI_DIAG_MAX_TESTS + 1U]; /* test i: sens[sens_offset[i] .. sens_offset[i + 1] - 1] */
    float sens[FDI_DIAG_MAX_SENS];
} fdi_diag_t; /* opaque by convention */

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(sizeof(fdi_diag_t) <= (224U + (sizeof(void *) * 2U) +
                                         (FDI_DIAG_MAX_TESTS * (sizeof(fdi_eval_t) + sizeof(fdi_obs_t) +
                                                                sizeof(fdi_est_t) + 43U)) +
                                         (sizeof(fdi_svf_t) * FDI_DIAG_MAX_FILTERS) +
                                         (sizeof(float) * FDI_DIAG_MAX_SENS) +
                                         (((2U * sizeof(float)) + sizeof(uint16_t)) * FDI_TABLE_MAX_FAULTS) +
                                         (sizeof(uint16_t) * FDI_GEN_MAX_SLOTS) +
                                         (sizeof(uint32_t) * FDI_DIAG_MAX_SENS_EVERY)),
                  fdi_sa_diag_size);

typedef struct
{
    uint8_t n_tests;
    uint32_t alarm_mask;     /* bit i: test i in alarm */
    uint32_t evaluable_mask; /* bit i: test i evaluable */
    fdi_test_status_t status[FDI_DIAG_MAX_TESTS];
    float residual[FDI_DIAG_MAX_TESTS]; /* last residual (0 while not evaluable for lack of inputs) */
    float ratio[FDI_DIAG_MAX_TESTS];    /* last test ratio (0 while not evaluable): of the residual's excess over its
                                           spread, with an adaptive threshold */
    float spread[FDI_DIAG_MAX_TESTS];   /* last adaptive threshold term: the residual's worst-case spread over the
                                           table's uncertainty (units of r; 0 with the fixed gate) */
    float offset[FDI_DIAG_MAX_TESTS];   /* test i's estimate's share of its residual, h . theta, removed from it (0: not
                                           estimated) */
    float estimate[FDI_DIAG_MAX_TESTS][FDI_EST_MAX_PARAMS]; /* test i's estimated deviations, in the order of its
                                                               generator's est (0: not estimated) */
    uint32_t accused_mask;              /* tests accused in the current isolation episode */
    fdi_iso_result_t iso;               /* candidates and isolability class (detected: episode active) */
    bool in_envelope;                   /* the frame was inside the table's calibrated envelope (or it has none):
                                           outside, the isolation holds (fdi_table.h, "Operating envelope" above) */
    uint8_t sens_offset[FDI_DIAG_MAX_TESTS + 1U]; /* test i's sensitivities: sens[sens_offset[i] ..
                                                     sens_offset[i + 1] - 1], ascending faults of its sens_mask;
                                                     all 0 (none listed) without cfg->sensitivities */
    float sens[FDI_DIAG_MAX_SENS];      /* last sensitivities d r / d f; only the listed entries are written */
} fdi_diag_result_t;

/* Defaults for `table`: CUSUM k 1.5, h 150 (as validated in tests/fw/test_fdi_diag.c), set 3, clear 100,
   warm-up = the design point's settling time + 20 steps, re-entry 0.5 s (at most the warm-up), exoneration, episodes
   ending after 3 s without alarm, noise allowance 3 sigma, generator parameters 0, no reported sensitivities, adaptive thresholds, on-line
   estimation for every test whose generator declares estimable quantities (kappa 3, decorrelation 10, a start-up of
   1 s), each test's
   sensitivities every 4th step of an episode. BAD_ARG on NULL; BAD_TABLE when
   the design point has no finite settling time (the table itself is checked by fdi_diag_init). */
fdi_status_t fdi_diag_config_default(fdi_diag_config_t *cfg, const fdi_table_t *table);

/* One fixed step with the current frame; validity uses the frame's bit layout. BAD_ARG on NULL only. */
fdi_status_t fdi_diag_step(fdi_diag_t *self, const fdi_frame_t *frame, uint32_t validity);

/* Copy the result of the last step (all tests NOT_EVALUABLE before the first step). */
fdi_status_t fdi_diag_result(const fdi_diag_t *self, fdi_diag_result_t *out);

/* The evidence of the on-line exoneration after the last step ("Isolation episodes" above), for traces and
   tests: why a fault is still a candidate. Entries of faults outside `undecided` are 0 (the rule no longer reads
   them in this episode); outside an episode, everything is 0. */
typedef struct
{
    uint16_t episode_age;                       /* steps since the episode's first alarm (saturating); 0: none */
    uint32_t undecided;                         /* faults the exoneration can still change (explain every accused
                                                   test, not latched) */
    uint32_t latched;                           /* the class isolated first in the episode (exonerated no more),
                                                   FDI_DIAG_CONTRADICTED, or 0 */
    float implied[FDI_TABLE_MAX_FAULTS];        /* F_j: the size the recent settled alarms imply, or how far
                                                   the alarms through a rate gain say j has moved (a lower bound
                                                   to first order: where a sensitivity passes near zero it can
                                                   exceed the true size; 0: no bound yet) */
    uint16_t cleared_run[FDI_TABLE_MAX_FAULTS]; /* consecutive steps the on-line rule has cleared fault j (it leaves
                                                   the candidates at 0.1 s) */
    uint32_t cleared;                           /* the faults exonerated at the step (the on-line rule, confirmed,
                                                   or the reaction sizes; the latched class never) */
    uint32_t clears[FDI_DIAG_MAX_TESTS];        /* per test: the faults it clears alone at F (its last decision; 0
                                                   while it has not settled quiet) */
} fdi_diag_evidence_t;

/* Copy the exoneration's evidence after the last step into *out (read only; no cost to the step). BAD_ARG on
   NULL. */
fdi_status_t fdi_diag_explain(const fdi_diag_t *self, fdi_diag_evidence_t *out);

/* Layout signature: the capacities and struct sizes a translation unit sees. A caller compiled with other
   capacities than the library (e.g. -DFDI_DIAG_MAX_TESTS=24 against a library built with 16, or with another
   FDI_EST_MAX_PARAMS) would hand it structures of another size and layout; fdi_diag_init() (inline, so compiled in
   the caller) passes the caller's signature to fdi_diag_init_layout(), which refuses any difference from the
   library's own with FDI_BAD_LAYOUT before it reads the configuration. The instance is only marked failed, as after
   any failed init (its first member, `table`, at the same place in every layout), so fdi_diag_step() refuses it. */
typedef struct
{
    uint32_t max_tests;       /* FDI_DIAG_MAX_TESTS */
    uint32_t max_sens;        /* FDI_DIAG_MAX_SENS */
    uint32_t max_filters;     /* FDI_DIAG_MAX_FILTERS */
    uint32_t est_max_params;  /* FDI_EST_MAX_PARAMS */
    uint32_t gen_max_filters; /* FDI_GEN_MAX_FILTERS */
    uint32_t size_diag;       /* sizeof(fdi_diag_t) */
    uint32_t size_config;     /* sizeof(fdi_diag_config_t) */
    uint32_t size_result;     /* sizeof(fdi_diag_result_t) */
    uint32_t size_evidence;   /* sizeof(fdi_diag_evidence_t) */
    uint32_t size_table;      /* sizeof(fdi_table_t) */
    uint32_t size_gen_desc;   /* sizeof(fdi_gen_desc_t) */
} fdi_diag_layout_t;
/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(sizeof(fdi_diag_layout_t) == (11U * sizeof(uint32_t)), fdi_sa_diag_layout_size);

/* The layout signature of the translation unit that calls it (the caller's view of the library's structures). */
static inline fdi_diag_layout_t fdi_diag_layout_here(void)
{
    const fdi_diag_layout_t here = {FDI_DIAG_MAX_TESTS,
                                    FDI_DIAG_MAX_SENS,
                                    FDI_DIAG_MAX_FILTERS,
                                    FDI_EST_MAX_PARAMS,
                                    FDI_GEN_MAX_FILTERS,
                                    (uint32_t)sizeof(fdi_diag_t),
                                    (uint32_t)sizeof(fdi_diag_config_t),
                                    (uint32_t)sizeof(fdi_diag_result_t),
                                    (uint32_t)sizeof(fdi_diag_evidence_t),
                                    (uint32_t)sizeof(fdi_table_t),
                                    (uint32_t)sizeof(fdi_gen_desc_t)};
    return here;
}

/* The library's layout signature, as the library was compiled, into *out (for a message naming both sides of a
   FDI_BAD_LAYOUT). BAD_ARG on NULL. */
fdi_status_t fdi_diag_layout(fdi_diag_layout_t *out);

/* fdi_diag_init with the caller's layout signature `caller` (fdi_diag_layout_here() of the caller). BAD_ARG: NULL
   (any argument); BAD_LAYOUT: *caller differs from the library's signature (cfg not read); then as fdi_diag_init. */
fdi_status_t fdi_diag_init_layout(fdi_diag_t *self, const fdi_diag_config_t *cfg, const fdi_diag_layout_t *caller);

/* Initialise the diagnoser (inline: the layout signature is the caller's, fdi_diag_init_layout). BAD_ARG: NULL or
   bad config (also: the table's generators output more sensitivities than FDI_DIAG_MAX_SENS while they are needed:
   reported, or exoneration; the set's bank and the hand-written generators' filters need more than
   FDI_DIAG_MAX_FILTERS states); BAD_LAYOUT: the caller was compiled with other capacities or struct layouts than the
   library; BAD_TABLE: table fails fdi_table_check(); NOT_FINITE: NaN/Inf in cfg. */
static inline fdi_status_t fdi_diag_init(fdi_diag_t *self, const fdi_diag_config_t *cfg)
{
    const fdi_diag_layout_t caller = fdi_diag_layout_here();
    return fdi_diag_init_layout(self, cfg, &caller);
}

#endif /* FDI_DIAG_H */
