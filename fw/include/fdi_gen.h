/*
 * fdi_gen.h - residual generators: one residual per step from the signal frame, through a descriptor.
 *
 * The library holds no generator of any vehicle. A generator is a const descriptor (fdi_gen_desc_t) that a
 * vehicle target provides: generated ones (fw/vehicles/<vehicle>/generated/fdi_<vehicle>_generators.c,
 * written by `fdi-analyze export-c` from the selected MSO sets) or hand-written ones (examples in a vehicle
 * target's src/). The descriptor names its step function, its operating domain, the frame
 * signals it reads, the faults whose sensitivity it can output and the filters and observer state it uses.
 * A test of a table points to its generator's descriptor; the diagnoser calls the step through the pointer
 * (no kind enum, no switch; function pointers are called, never converted: fw/MISRA_DEVIATIONS.md).
 *
 * The step of a generator, every dt of the table's design point:
 *   step(g, par, in, reset, r, sens)
 *     reset = true: put every filter (and the observer estimate) of g in steady state at the frame `in`,
 *                   *r = 0;
 *     reset = false: advance the filters by one sample and write the residual *r;
 *     sens != NULL: also write d r / d f_j for every fault j of desc->sens_mask, in ascending fault order
 *                   (fdi_gen_sens_count() values), computed from the same common subexpressions as r (the
 *                   linearisation of the residual in the faults at the current operating point, the
 *                   steady-state value for an observer generator); sens == NULL costs nothing.
 *   It is called with every argument non-NULL and every signal of desc->input_mask finite (fdi_gen_step()
 *   and the diagnoser check that); it returns NOT_FINITE when a value it computes is not finite (r, or a
 *   sensitivity when requested); the state may then be partly updated, so the caller resets it before use.
 * Generated generators take the filter coefficients of fdi_gen_param_t and their model parameters compiled
 * in; hand-written ones may read run-time parameters from fdi_gen_param_t.param (their target documents the
 * meaning of each index).
 * An observer generator (integral causality for one state) keeps its estimate in the instance's fdi_obs_t:
 * xh' = F(xh, u) + L(xh, u) e(xh, u), r = e, with the step of fdi_gen_impl.h (exponential of the error pole,
 * input averaged over the step; stable for any pole).
 *
 * Cost per step: the generator's (its filters, ~15 flops each, and its expression); the dispatch is one
 * indirect call. Memory: fdi_gen_t = one pointer + FDI_GEN_MAX_FILTERS filter states (12 bytes each) +
 * one observer state (8 bytes): 204 bytes on a 32-bit target for 16 filters; fdi_gen_param_t 12 + 12 +
 * 4 * FDI_GEN_N_PARAMS = 40 bytes (shared by all tests); both asserted below.
 */
#ifndef FDI_GEN_H
#define FDI_GEN_H

#include <stdbool.h>
#include <stdint.h>

#include "fdi_frame.h"
#include "fdi_obs.h"
#include "fdi_static_assert.h"
#include "fdi_status.h"
#include "fdi_svf.h"

#ifndef FDI_GEN_MAX_FILTERS
#define FDI_GEN_MAX_FILTERS 16U /* filter states per instance; override with -DFDI_GEN_MAX_FILTERS=n (1..255) */
#endif
#if (FDI_GEN_MAX_FILTERS < 1) || (FDI_GEN_MAX_FILTERS > 255)
#error "FDI_GEN_MAX_FILTERS must be in 1..255"
#endif

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

/* Step of a generator (see the header comment). */
typedef fdi_status_t (*fdi_gen_step_fn_t)(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_frame_t *in,
                                          bool reset, float *r, float *sens);
/* Operating domain: true when the residual is meaningful at the frame `in` (non-NULL, domain signals finite). */
typedef bool (*fdi_gen_domain_fn_t)(const fdi_frame_t *in);

typedef struct
{
    const char *name;              /* e.g. "MSO351", for logs and tools; non-NULL */
    fdi_gen_step_fn_t step;        /* non-NULL */
    fdi_gen_domain_fn_t in_domain; /* NULL: always in its domain */
    uint32_t input_mask;           /* frame signals the step and the domain read (non-zero) */
    uint32_t sens_mask;            /* faults (bit j = fault j of the table) whose d r / d f_j the step outputs */
    uint8_t n_filters;             /* filter states of the instance it uses, <= FDI_GEN_MAX_FILTERS */
    uint8_t n_obs;                 /* observer states it uses: 0 or 1 */
} fdi_gen_desc_t;

struct fdi_gen_s
{
    const fdi_gen_desc_t *desc;
    fdi_svf_t filt[FDI_GEN_MAX_FILTERS];
    fdi_obs_t obs;
}; /* opaque by convention */

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(sizeof(fdi_gen_t) == (sizeof(void *) + (FDI_GEN_MAX_FILTERS * sizeof(fdi_svf_t)) + sizeof(fdi_obs_t)),
                  fdi_sa_gen_size);

/* Design the shared parameters. BAD_ARG / NOT_FINITE on a bad config (see fdi_svf.h, fdi_obs.h). */
fdi_status_t fdi_gen_param_init(fdi_gen_param_t *par, const fdi_gen_config_t *cfg);

/* A usable descriptor: name and step non-NULL, non-zero input mask, n_filters and n_obs within the
   instance's capacity. FDI_OK or FDI_BAD_ARG. */
fdi_status_t fdi_gen_desc_check(const fdi_gen_desc_t *desc);

/* Bind an instance to a descriptor (fdi_gen_desc_check). It must be reset before the first step. */
fdi_status_t fdi_gen_init(fdi_gen_t *self, const fdi_gen_desc_t *desc);

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

#endif /* FDI_GEN_H */
