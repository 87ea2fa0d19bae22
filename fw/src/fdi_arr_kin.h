/*
 * fdi_arr_kin.h - internal: the kinematic residual generators (MSO1..MSO4 of Table II), see fdi_gen.h for
 * the equations. Each function either resets (reset = true: all filters in steady state at the current
 * inputs, *r = 0) or steps its filters and writes the residual. Arguments are checked by fdi_gen.c.
 */
#ifndef FDI_ARR_KIN_H
#define FDI_ARR_KIN_H

#include <stdbool.h>

#include "fdi_gen.h"

fdi_status_t fdi_arr_kin_x_deriv(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_inputs_t *in, bool reset,
                                 float *r);
fdi_status_t fdi_arr_kin_y_deriv(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_inputs_t *in, bool reset,
                                 float *r);
fdi_status_t fdi_arr_kin_arr3(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_inputs_t *in, bool reset,
                              float *r);
fdi_status_t fdi_arr_kin_arr4(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_inputs_t *in, bool reset,
                              float *r);
fdi_status_t fdi_arr_kin_x_obs(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_inputs_t *in, bool reset,
                               float *r);
fdi_status_t fdi_arr_kin_y_obs(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_inputs_t *in, bool reset,
                               float *r);

#endif /* FDI_ARR_KIN_H */
