/*
 * fdi_gen.h - residual generators: one residual per test and step from the signal frame, through descriptors.
 *
 * The library holds no generator of any vehicle. A generator is a const descriptor (fdi_gen_desc_t) that a
 * vehicle target provides; a test of a table points to its generator's descriptor. Two kinds:
 *
 * Generated generators (fw/vehicles/<vehicle>/generated/fdi_<vehicle>_generators.c, written by `fdi-analyze
 * export-c` from the selected MSO sets) are the slots of one generator set (fdi_gen_set_t) per vehicle table:
 *  - the set's filter bank lists every filtered signal its generators read, once: filter k is fed with a raw frame
 *    signal or with the output y or dy of an earlier filter of the same signal (chains for higher derivatives);
 *    fdi_gen_bank_step() advances the whole bank once per step for all tests: filter k runs while its signal is
 *    usable (valid and finite), restarts in steady state at its input when the signal becomes usable again (or at
 *    the first step) and holds while it is not; a filter whose state would overflow holds and its signal counts as
 *    unusable for the step (it restarts when usable again);
 *  - the set's step function computes, in one call, the residual of every slot of io->run from the bank (outputs
 *    bank[k].x1 = y, bank[k].x2 = dy, fdi_svf.h) and the frame: the subexpressions the slots share (sin/cos of a
 *    steering angle, tyre-law terms) once per step, then each slot's own terms; a slot with an observer advances
 *    its estimate io->obs[io->at[k]] (fdi_gen_impl.h), restarting it from the current inputs for the slots of
 *    io->restart. It writes io->r[io->at[k]], with io->spread the residual's worst-case spread over the model's
 *    uncertainty at io->spread[io->at[k]] (from the same shared terms: the adaptive threshold, fdi_diag.h), sets bit
 *    k of io->failed when a value is not finite (residual, spread or the observer's next state: the caller restarts
 *    the slot), and for the slots of io->sens_mask the sensitivities
 *    d r / d f_j of the faults of the slot's sens_mask, ascending, at io->sens[io->sens_at[k]] (the linearisation
 *    of the residual in the faults at the current operating point, the steady-state value for an observer slot),
 *    from the same shared terms; the residual is the same with or without them.
 *  - derived signals (optional): the terms of a residual that contain no derivative, computed from the raw
 *    signals and filtered as one signal (a filter is linear, so the filtered sum of these terms is exactly what
 *    the residual needs; the same terms computed from filtered signals would differ wherever the signals change
 *    fast). The set's derive function writes them into free places of a copy of the frame (signal indices above
 *    the vehicle's signals); fdi_gen_derive() marks each usable while its sources are usable and it is finite,
 *    and the bank filters it like any frame signal;
 *   Its descriptors have step == NULL, set == the set and slot == their position; the diagnoser calls the set's
 *   step once per step for all its tests (a table holds at most one set, each slot at most once: fdi_table_check).
 *
 * Hand-written generators (examples in a vehicle target's src/) have their own step function and instance filters
 * (desc->n_filters states, reset with the generator; not the bank):
 *   step(g, par, in, reset, r, sens)
 *     reset = true: put every filter (and the observer estimate) of g in steady state at the frame `in`, *r = 0;
 *     reset = false: advance the filters by one sample and write the residual *r;
 *     sens != NULL: also write d r / d f_j for every fault j of desc->sens_mask, in ascending fault order
 *                   (fdi_gen_sens_count() values); sens == NULL costs nothing.
 *   It is called with every argument non-NULL and every signal of desc->input_mask finite (fdi_gen_step()
 *   and the diagnoser check that); it returns NOT_FINITE when a value it computes is not finite; the state may then
 *   be partly updated, so the caller resets it before use. fdi_gen_t is a view on the caller's storage: the
 *   descriptor, desc->n_filters filter states and one observer state.
 * Generated generators take the filter coefficients of fdi_gen_param_t and their model parameters compiled
 * in; hand-written ones may read run-time parameters from fdi_gen_param_t.param (their target documents the
 * meaning of each index).
 *
 * Cost per step: the bank, once for all tests (per running filter 4 multiplications, 7 additions and one
 * finiteness check); the set's step (the shared terms once, each running slot's own terms); a hand-written
 * generator's filters and expression. Measured by scripts/bench_fw.sh (per step, and per function and call on the
 * Cortex-M4F).
 * Memory: a bank filter 12 bytes (fdi_svf_t), an observer 8 bytes (fdi_obs_t), held by the caller (fdi_diag_t); a
 * set with derived signals costs the diagnoser a copy of the frame per step (fdi_frame_t, 128 bytes of stack);
 * fdi_gen_param_t 12 + 12 + 4 * FDI_GEN_N_PARAMS = 40 bytes (shared by all tests), asserted below; the set's
 * temporaries are locals of its step function (stack, no RAM).
 */
#ifndef FDI_GEN_H
#define FDI_GEN_H

#include <stdbool.h>
#include <stdint.h>

#include "fdi_est.h"
#include "fdi_frame.h"
#include "fdi_obs.h"
#include "fdi_static_assert.h"
#include "fdi_status.h"
#include "fdi_svf.h"

/* FDI_GEN_MAX_FILTERS: instance filters of one hand-written generator, an overridable capacity
   (generated/fdi_capacity.h) */
#include "generated/fdi_capacity.h"

#define FDI_GEN_MAX_SLOTS 32U   /* generators of one set (slot bitmasks are uint32_t) */
#define FDI_GEN_MAX_BANK 255U   /* filters of one bank (indices are uint8_t) */
#define FDI_GEN_BANK_RAW 0xFFU  /* fdi_gen_bank_filter_t.source of a filter fed with the raw signal */
/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(FDI_GEN_MAX_BANK <= (FDI_GEN_BANK_RAW + 1U), fdi_sa_gen_bank_index);

#define FDI_GEN_N_PARAMS 4U /* run-time parameters of hand-written generators (fdi_gen_param_t.param) */

/* 1: generated generators carry their sensitivity code (run only when requested). 0 (-DFDI_GEN_SENSITIVITIES=0):
   compiled without it (less flash); their descriptors then list no sensitivity (FDI_GEN_SENS_MASK gives 0). */
#ifndef FDI_GEN_SENSITIVITIES
#define FDI_GEN_SENSITIVITIES 1
#endif
#if FDI_GEN_SENSITIVITIES
#define FDI_GEN_SENS_MASK(mask) (mask)
#else
#define FDI_GEN_SENS_MASK(mask) 0U
#endif

typedef struct
{
    float dt;                         /* sample time [s] */
    float cutoff_hz;                  /* cut-off of every derivative filter [Hz], < 0.5/dt */
    float zeta;                       /* damping of the derivative filters (0.7071 typical) */
    float obs_gain;                   /* observer gain L [1/s] of the constant-gain observers, > 0 */
    float param[FDI_GEN_N_PARAMS];    /* run-time parameters of hand-written generators, finite */
} fdi_gen_config_t;

typedef struct
{
    fdi_svf_coef_t svf;
    fdi_obs_coef_t obs;
    float param[FDI_GEN_N_PARAMS];
} fdi_gen_param_t;

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(sizeof(fdi_gen_param_t) == (24U + (FDI_GEN_N_PARAMS * sizeof(float))), fdi_sa_gen_param_size);

struct fdi_gen_s;
typedef struct fdi_gen_s fdi_gen_t;
struct fdi_gen_set_s;
typedef struct fdi_gen_set_s fdi_gen_set_t;

/* Step of a hand-written generator (see the header comment). */
typedef fdi_status_t (*fdi_gen_step_fn_t)(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_frame_t *in,
                                          bool reset, float *r, float *sens);
/* Operating domain: true when the residual is meaningful at the frame `in` (non-NULL, domain signals finite). */
typedef bool (*fdi_gen_domain_fn_t)(const fdi_frame_t *in);

typedef struct
{
    const char *name;              /* e.g. "MSO351", for logs and tools; non-NULL */
    fdi_gen_step_fn_t step;        /* hand-written: its step; NULL for a slot of a set (the set's step runs it) */
    fdi_gen_domain_fn_t in_domain; /* NULL: always in its domain */
    uint32_t input_mask;           /* frame signals the step and the domain read (non-zero) */
    uint32_t sens_mask;            /* faults (bit j = fault j of the table) whose d r / d f_j the step outputs;
                                      when non-zero, a fault of the test's signature left out has a steady-state
                                      sensitivity of exactly zero (it reaches r only while it changes: the
                                      diagnoser bounds no size of it by this test, fdi_diag.h) */
    uint8_t n_filters;             /* hand-written: instance filter states it uses (<= FDI_GEN_MAX_FILTERS); slot: 0 */
    uint8_t n_obs;                 /* observer states it uses: 0 or 1 */
    const fdi_gen_set_t *set;      /* the set of a generated generator; NULL for a hand-written one */
    uint8_t slot;                  /* its slot in the set (< set->n_slots); 0 for a hand-written one */
    uint32_t rate_mask;            /* faults outside sens_mask that reach r only through a derivative, with a
                                      constant rate gain: a drift of rate rho_j gives the steady residual
                                      rate_gain[k] * rho_j (k: j's place among the bits of rate_mask, ascending);
                                      the diagnoser bounds how far such a fault has moved by it (fdi_diag.h) */
    const float *rate_gain;        /* the rate gains d r / d (d f_j / dt), finite and non-zero; non-NULL when
                                      rate_mask is non-zero */
    uint8_t n_est;                 /* the vehicle's uncertain quantities (or lumped offsets) the diagnoser may
                                      estimate on line for this test, <= FDI_EST_MAX_PARAMS (fdi_est.h); 0: none */
    const fdi_est_param_t *est;    /* their declarations (n_est entries; NULL when n_est is 0). A slot of a set
                                      writes their regressors d r / d theta (io->reg); a hand-written generator's
                                      are offsets (regressor 1) */
    fdi_gen_domain_fn_t in_range;  /* NULL: always; else where the model's physics holds within the domain (e.g. a
                                      tyre law near its linear range): outside it the test is not evaluable, but
                                      its filters run on, so back in range it waits the diagnoser's re-entry, not
                                      its whole warm-up */
} fdi_gen_desc_t;

/* A hand-written generator's instance: a view on the caller's storage (fdi_gen_init). */
struct fdi_gen_s
{
    const fdi_gen_desc_t *desc;
    fdi_svf_t *filt; /* desc->n_filters filter states */
    fdi_obs_t *obs;  /* its observer state (desc->n_obs == 1), else unused */
}; /* opaque by convention */

/* One filter of a bank: fed with frame signal `signal` (source FDI_GEN_BANK_RAW), or with the output y (order 0) or
   dy (order 1) of the earlier filter `source` of the same signal. It runs while `signal` is usable. */
typedef struct
{
    uint8_t signal; /* frame signal at the root of the chain, < FDI_FRAME_MAX_SIGNALS */
    uint8_t source; /* FDI_GEN_BANK_RAW, or the index of an earlier filter of the bank fed by the same signal */
    uint8_t order;  /* source != FDI_GEN_BANK_RAW: 0 fed with that filter's y, 1 with its dy; else 0 */
} fdi_gen_bank_filter_t;

/* A derived signal of a set: its place in the frame and the frame signals it is computed from. */
typedef struct
{
    uint8_t signal;   /* its index in the frame, < FDI_FRAME_MAX_SIGNALS, not one of its sources */
    uint32_t sources; /* the frame signals it reads (non-zero) */
} fdi_gen_derived_t;

/* Writes every derived signal of a set into the frame (non-NULL) from the frame's signals. Cannot fail. */
typedef void (*fdi_gen_derive_fn_t)(fdi_frame_t *frame);

/* What a set's step reads and writes; the caller fills it (the diagnoser once per step). Slot k's bit in the
   masks is bit k; its observer state and residual are at index at[k] of obs[] and r[]. */
typedef struct
{
    const fdi_gen_param_t *par; /* filter and observer coefficients */
    const fdi_frame_t *in;      /* the frame (raw signals, the domain, observer restarts) */
    const fdi_svf_t *bank;      /* the set's bank after fdi_gen_bank_step() of this frame */
    fdi_obs_t *obs;             /* observer states */
    float *r;                   /* out: residuals */
    const uint8_t *at;          /* slot -> index in obs[] and r[] (set->n_slots entries) */
    float *sens;                /* out: sensitivities of slot k of sens_mask at sens[sens_at[k]] .. */
    const uint8_t *sens_at;     /* slot -> index in sens[] (set->n_slots entries; may be NULL when sens_mask is 0) */
    uint32_t run;               /* slots to compute (their inputs usable and finite, in their domain) */
    uint32_t restart;           /* slots of run to restart: observer estimate from the current inputs */
    uint32_t sens_mask;         /* slots of run whose sensitivities to compute */
    float *spread;              /* out, NULL: not computed: each slot of run whose residual depends on the
                                   vehicle's uncertain quantities writes at spread[at[k]] its worst-case spread over
                                   those it does not estimate (desc->est), sum |d r / d theta| * dtheta (the adaptive
                                   threshold's term, >= 0; a slot without one leaves its entry as it is: the caller
                                   sets 0) */
    float *reg;                 /* out, non-NULL when spread is: each slot of run with estimated quantities writes
                                   their regressors d r / d theta_e (desc->est order) at
                                   reg[at[k] * FDI_EST_MAX_PARAMS + e] */
    uint32_t failed;            /* out (the caller sets 0): slots of run with a non-finite residual, state or spread */
} fdi_gen_io_t;

typedef void (*fdi_gen_set_step_fn_t)(fdi_gen_io_t *io);

/* A generated generator set: its step, its filter bank and its number of slots (see the header comment). */
struct fdi_gen_set_s
{
    const char *name;                   /* the vehicle's name; non-NULL */
    fdi_gen_set_step_fn_t step;         /* non-NULL */
    const fdi_gen_bank_filter_t *bank;  /* n_bank filters; NULL only when n_bank is 0 */
    uint8_t n_bank;
    uint8_t n_slots;                    /* 1..FDI_GEN_MAX_SLOTS */
    fdi_gen_derive_fn_t derive;         /* NULL when the set has no derived signal */
    const fdi_gen_derived_t *derived;   /* n_derived derived signals; NULL only when n_derived is 0 */
    uint8_t n_derived;                  /* 0 when derive is NULL, else >= 1 */
};

/* Design the shared parameters. BAD_ARG / NOT_FINITE on a bad config (see fdi_svf.h, fdi_obs.h). */
fdi_status_t fdi_gen_param_init(fdi_gen_param_t *par, const fdi_gen_config_t *cfg);

/* A usable descriptor: name non-NULL, non-zero input mask, n_obs <= 1, rate_mask disjoint from sens_mask with a
   finite non-zero gain per bit, and either a hand-written generator (step non-NULL, no set, n_filters <=
   FDI_GEN_MAX_FILTERS) or a slot of a usable set (step NULL, n_filters 0, slot < set->n_slots), and its estimated
   quantities none or usable declarations (fdi_est_check). FDI_OK or FDI_BAD_ARG. */
fdi_status_t fdi_gen_desc_check(const fdi_gen_desc_t *desc);

/* A usable set: name and step non-NULL, 1..FDI_GEN_MAX_SLOTS slots, every bank filter fed by a signal of the
   frame or by an earlier filter of the same signal (order 0 or 1), derive and n_derived both set or both not, each
   derived signal in the frame, with sources, not among them and not among another's. FDI_OK or FDI_BAD_ARG. */
fdi_status_t fdi_gen_set_check(const fdi_gen_set_t *set);

/* The frame signals the bank of a (checked) set filters; 0 for NULL. Cannot fail. */
uint32_t fdi_gen_bank_signals(const fdi_gen_set_t *set);

/* The frame places of the derived signals of a (checked) set; 0 for NULL or none. Cannot fail. */
uint32_t fdi_gen_derived_signals(const fdi_gen_set_t *set);

/*
 * The derived signals of a checked set: writes them into `frame` (the caller's copy of the step's frame) and
 * returns `usable` with each derived signal whose sources are all usable and whose value is finite; a derived
 * signal that is not finite although its sources are makes its sources unusable for the step (returned without
 * them). A set without derived signals, or a NULL argument, returns `usable` unchanged.
 */
uint32_t fdi_gen_derive(const fdi_gen_set_t *set, fdi_frame_t *frame, uint32_t usable);

/*
 * One step of the bank of a checked set: bank[0 .. set->n_bank - 1] (the caller's filter states) at the frame `in`.
 * A filter whose signal is in `usable` runs; it restarts in steady state at its input (y = input, dy = 0) when its
 * signal is not in `live` (the usable signals of the previous step: 0 at the first step); the others hold.
 * Returns the signals of `usable` whose filters failed (the state would not be finite: it holds): the caller treats
 * them as unusable for this step (they restart when usable again). The caller checks finiteness of the inputs
 * (usable); NULL arguments give 0 and change nothing.
 */
uint32_t fdi_gen_bank_step(const fdi_gen_set_t *set, fdi_svf_t *bank, const fdi_svf_coef_t *coef,
                           const fdi_frame_t *in, uint32_t usable, uint32_t live);

/* Bind a hand-written generator's instance to its storage: n_filt >= desc->n_filters filter states and an observer
   state (obs may be NULL when desc->n_obs is 0). BAD_ARG for a slot of a set or storage that does not fit. It must
   be reset before the first step. */
fdi_status_t fdi_gen_init(fdi_gen_t *self, const fdi_gen_desc_t *desc, fdi_svf_t *filt, uint32_t n_filt,
                          fdi_obs_t *obs);

/* Put every filter in steady state at the current inputs (used at start and after invalid inputs). */
fdi_status_t fdi_gen_reset(fdi_gen_t *self, const fdi_gen_param_t *par, const fdi_frame_t *in);

/*
 * One step: *r = residual; sens non-NULL: the fault sensitivities (fdi_gen_sens_count() values). NOT_FINITE
 * when a signal of the input mask is not finite or a value overflows; the state may then be partly updated,
 * so the caller resets the generator before using it again.
 */
fdi_status_t fdi_gen_step(fdi_gen_t *self, const fdi_gen_param_t *par, const fdi_frame_t *in, float *r,
                          float *sens);

/* Number of sensitivities the step of `desc` outputs (bits of sens_mask); 0 for NULL. Cannot fail. */
uint32_t fdi_gen_sens_count(const fdi_gen_desc_t *desc);

/*
 * Operating domain: true when the residual of `desc` is meaningful at the frame `in` (e.g. a tyre-law
 * residual only above a minimum speed, derived from the model's slip regularisation by the generator
 * synthesis). false for a NULL descriptor or frame. Outside the domain the diagnoser reports the test
 * "not evaluable" and restarts it on re-entry. Cannot fail.
 */
bool fdi_gen_in_domain(const fdi_gen_desc_t *desc, const fdi_frame_t *in);

/* Whether `in` lies in the range of `desc` (desc->in_range; true without one); false for a NULL descriptor or frame.
   Cannot fail. */
bool fdi_gen_in_range(const fdi_gen_desc_t *desc, const fdi_frame_t *in);

#endif /* FDI_GEN_H */
