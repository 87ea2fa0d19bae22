/*
 * fdi_gen_internal.h - internal: generator step for callers that have already checked the inputs
 * (fdi_diag checks every signal once per step and runs a test only when all its signals are valid and
 * finite), so the finiteness scan of fdi_gen_step() is not repeated per test. self, par, in and r must be
 * non-NULL and the instance initialised; everything else is as fdi_gen_step() / fdi_gen_reset().
 */
#ifndef FDI_GEN_INTERNAL_H
#define FDI_GEN_INTERNAL_H

#include <stdbool.h>

#include "fdi_gen.h"

fdi_status_t fdi_gen_run_checked(fdi_gen_t *self, const fdi_gen_param_t *par, const fdi_frame_t *in, bool reset,
                                 float *r, float *sens);

#endif /* FDI_GEN_INTERNAL_H */
