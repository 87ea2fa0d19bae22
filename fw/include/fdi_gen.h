/*
 * fdi_gen.h - residual generators: one residual per step from the signal frame.
 *
 * A generator is an instance (fdi_gen_t) with a kind (fdi_gen_kind_t from the table) and enough filter
 * state for the largest kind. Dispatch is a switch on the kind (no function pointers, MISRA-friendly); a new
 * hand-written or generated generator adds one enum value in fdi_table.h, one case in fdi_gen.c, its
 * input mask in fdi_gen_inputs() and its function in an fdi_arr_<group>.c file.
 *
 * Kinematic generators (sign conventions of the structural model; w = psidot_m, d_x, d_y = position of the
 * velocity sensor relative to the CoG):
 *   vx = vx_m + d_y*w,  vy = vy_m - d_x*w  (S4, S5)
 *   MSO1  r1 = ax_m - (d/dt vx - vy*w)
 *   MSO2  r2 = ay_m - (d/dt vy + vx*w)
 *   MSO3  p = d/dt vx - ax_m,  r3 = w*d/dt p - p*d/dt w - (ay_m - vx*w)*w^2     (eq. 8-10)
 *   MSO4  q = d/dt vy - ay_m,  r4 = w*d/dt q - q*d/dt w + (ax_m + vy*w)*w^2
 *   MSO1 observer: xh' = ax_m + vy*w + L*(vx - xh), r = vx - xh   (MSO2 likewise with ay_m - vx*w)
 * Derivatives come from fdi_svf filters. Every signal of one relation passes through the same number of
 * equal filters (one stage for r1, r2; two for r3, r4, whose p and q already contain a derivative), so all
 * terms carry the same delay and the residual of consistent signals stays near 0 in dynamic manoeuvres.
 * Note r3, r4 scale with w^2: they lose sensitivity when driving straight (w -> 0).
 *
 * Cost per step: r1, r2 4 filters (~70 flops); r3, r4 8 filters (~140 flops); observer ~12 flops.
 * Generated generators (kinds FDI_GEN_GENERATED_<n>): synthesised by fdi_analysis.residuals from the
 * selected MSO sets and emitted into fw/generated/fdi_romo_generators.c, which defines the two functions
 * below (a switch on the slot); they use up to FDI_GEN_MAX_FILTERS filters of the instance and the shared
 * filter coefficients of fdi_gen_param_t; model parameters (including d_x, d_y) are compiled in from the
 * model file, so fdi_gen_param_t.d_x/d_y only apply to the hand-written kinematic kinds.
 * A generated generator with integral causality (a state its MSO set would otherwise integrate open loop,
 * e.g. a wheel speed without its sensor) keeps the state estimate in the instance's fdi_obs_t (xh, and the
 * observer input of the previous step in g_prev): xh' = F(xh, u) + L(xh, u) e(xh, u), r = e, with the
 * run-time gain L = -max(lambda + a, 0) c / (c^2 + eps) (a = dF/dxh, c = de/dxh, compiled in) and the step
 * of fdi_gen_internal.h (exponential of the error pole a + L c, input averaged over the step; stable for any
 * pole). At a reset xh starts from the state's sensor outside the MSO set (when finite, else 0; it is not
 * an input of the test); the error decays with the pole (lambda = 2 x 2 pi x 1 Hz = 12.6 1/s where the
 * injection acts, the wheel's own slip dynamics of ~ -150..-800 1/s otherwise) inside the warm-up.
 * fdi_gen_param_t.obs applies to the hand-written kinds only.
 *
 * Memory: fdi_gen_t 4 + 16 filters * 12 + 8 = 204 bytes; fdi_gen_param_t 32 bytes (shared by all tests).
 */
#ifndef FDI_GEN_H
#define FDI_GEN_H

#include <stdbool.h>
#include <stdint.h>

#include "fdi_obs.h"
#include "fdi_signals.h"
#include "fdi_status.h"
#include "fdi_svf.h"
#include "fdi_table.h"

#define FDI_GEN_MAX_FILTERS 16U

typedef struct
{
    float dt;        /* sample time [s] */
    float cutoff_hz; /* cut-off of every derivative filter [Hz], < 0.5/dt */
    float zeta;      /* damping of the derivative filters (0.7071 typical) */
    float obs_gain;  /* observer gain L [1/s] of the observer-based generators, > 0 */
    float d_x;       /* velocity sensor position ahead of the CoG [m] */
    float d_y;       /* velocity sensor position left of the CoG [m] */
} fdi_gen_config_t;

typedef struct
{
    fdi_svf_coef_t svf;
    fdi_obs_coef_t obs;
    float d_x;
    float d_y;
} fdi_gen_param_t;

typedef struct
{
    fdi_gen_kind_t kind;
    fdi_svf_t filt[FDI_GEN_MAX_FILTERS];
    fdi_obs_t obs;
} fdi_gen_t; /* opaque by convention */

/* Design the shared parameters. BAD_ARG / NOT_FINITE on a bad config (see fdi_svf.h, fdi_obs.h). */
fdi_status_t fdi_gen_param_init(fdi_gen_param_t *par, const fdi_gen_config_t *cfg);

/* Bind an instance to a kind (not FDI_GEN_NONE). It must be reset before the first step. */
fdi_status_t fdi_gen_init(fdi_gen_t *self, fdi_gen_kind_t kind);

/* Put every filter in steady state at the current inputs (used at start and after invalid inputs). */
fdi_status_t fdi_gen_reset(fdi_gen_t *self, const fdi_gen_param_t *par, const fdi_inputs_t *in);

/*
 * One step: *r = residual. NOT_FINITE when an input the kind reads is not finite or a value overflows; the
 * state may then be partly updated, so the caller resets the generator before using it again.
 */
fdi_status_t fdi_gen_step(fdi_gen_t *self, const fdi_gen_param_t *par, const fdi_inputs_t *in, float *r);

/* Signals (FDI_SIGM_*) read by a kind; 0 for FDI_GEN_NONE and unknown kinds. Cannot fail. */
uint32_t fdi_gen_inputs(fdi_gen_kind_t kind);

/*
 * Operating domain: true when the residual of `kind` is meaningful at the frame `in` (e.g. a tyre-law
 * residual only above a minimum speed, derived from the model's slip regularisation by the generator
 * synthesis). Hand-written kinds are always in their domain. false for a NULL frame or a non-finite domain
 * signal. Outside the domain the diagnoser reports the test "not evaluable" and restarts it on re-entry.
 * Cannot fail.
 */
bool fdi_gen_in_domain(fdi_gen_kind_t kind, const fdi_inputs_t *in);

/* Implemented by the generated generator file. Arguments non-NULL and inputs checked (as fdi_gen_run_checked). */
fdi_status_t fdi_gen_generated_step(uint32_t slot, fdi_gen_t *self, const fdi_gen_param_t *par,
                                    const fdi_inputs_t *in, bool reset, float *r);
/* Signals read by generated slot `slot`; 0 for a slot without a generator. Cannot fail. */
uint32_t fdi_gen_generated_inputs(uint32_t slot);
/* Operating domain of generated slot `slot` (true for a slot without a condition); `in` non-NULL. */
bool fdi_gen_generated_in_domain(uint32_t slot, const fdi_inputs_t *in);

#endif /* FDI_GEN_H */
