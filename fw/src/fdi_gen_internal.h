/*
 * fdi_gen_internal.h - internal: generator step for callers that have already checked the inputs
 * (fdi_diag checks every signal once per step and runs a test only when all its signals are valid and
 * finite), so the 19-signal finiteness scan of fdi_gen_step() is not repeated per test. Arguments must be
 * non-NULL and the instance initialised; everything else is as fdi_gen_step() / fdi_gen_reset().
 */
#ifndef FDI_GEN_INTERNAL_H
#define FDI_GEN_INTERNAL_H

#include <stdbool.h>
#include <stdint.h>

#include "fdi_gen.h"

/*
 * Building blocks shared by the hand-written (fdi_arr_kin.c) and the generated (fw/generated) generators.
 * fdi_gen_filter_step: one step of derivative filter idx of the instance, or its reset to steady state at u
 *   (then out = {u, 0}). fdi_gen_status_worst: the first non-OK of two statuses. fdi_gen_finish: *r = value
 *   (0 while resetting) when st is OK and value is finite, else the failing status (NOT_FINITE for value).
 */
fdi_status_t fdi_gen_filter_step(fdi_gen_t *g, const fdi_gen_param_t *par, uint32_t idx, float u, bool reset,
                                 fdi_svf_out_t *out);
fdi_status_t fdi_gen_status_worst(fdi_status_t a, fdi_status_t b);
fdi_status_t fdi_gen_finish(fdi_status_t st, float value, bool reset, float *r);

/*
 * Observer generators (integral causality for one state, fdi_analysis/residuals/observer.py): the estimate
 * lives in g->obs (xh = estimate, g_prev = observer input G of the previous step).
 * fdi_gen_obs_predict: xh[k] = xh[k-1] + phi * (g_prev + g1) / 2 with phi = expm1(jac dt) / jac (dt when
 *   |jac dt| < 1e-6), the exponential of the error pole jac = a + L c; stable for every jac < 0. g NULL or
 *   par NULL give 0 (callers pass their checked instance).
 * fdi_gen_obs_store: keep xh and g_prev for the next step; NOT_FINITE (nothing stored) on NaN/Inf, BAD_ARG on
 *   NULL.
 * fdi_gen_heaviside(x): 1 for x > 0, else 0; fdi_gen_sign(x): -1, 0, 1 (derivatives of Max and Abs).
 */
float fdi_gen_obs_predict(const fdi_gen_t *g, const fdi_gen_param_t *par, float g1, float jac);
fdi_status_t fdi_gen_obs_store(fdi_gen_t *g, float xh, float g_next);
float fdi_gen_heaviside(float x);
float fdi_gen_sign(float x);

fdi_status_t fdi_gen_run_checked(fdi_gen_t *self, const fdi_gen_param_t *par, const fdi_inputs_t *in, bool reset,
                                 float *r);

#endif /* FDI_GEN_INTERNAL_H */
