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

fdi_status_t fdi_gen_run_checked(fdi_gen_t *self, const fdi_gen_param_t *par, const fdi_inputs_t *in, bool reset,
                                 float *r);

#endif /* FDI_GEN_INTERNAL_H */
