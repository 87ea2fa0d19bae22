/*
 * fdi_romo_kin.h - hand-written residual generators of the ROboMObil: the four kinematic tests MSO1..MSO4 of
 * Table II of the paper (derivative form, eq. 8-10) and MSO1/MSO2 in observer form. An example of
 * hand-written generators on the generic core (fdi_gen.h descriptors); the generated ones of the same vehicle
 * are in generated/fdi_romo_generators.c.
 *
 * Sign conventions of the structural model; w = psidot_m, d_x, d_y = position of the velocity sensor
 * relative to the CoG (run-time parameters FDI_ROMO_KIN_PARAM_D_X/_D_Y of fdi_gen_param_t.param):
 *   vx = vx_m + d_y*w,  vy = vy_m - d_x*w  (S4, S5)
 *   MSO1  r1 = ax_m - (d/dt vx - vy*w)                                            [m/s^2]
 *   MSO2  r2 = ay_m - (d/dt vy + vx*w)                                            [m/s^2]
 *   MSO3  p = d/dt vx - ax_m,  r3 = w*d/dt p - p*d/dt w - (ay_m - vx*w)*w^2  (eq. 8-10, no vy_m)
 *   MSO4  q = d/dt vy - ay_m,  r4 = w*d/dt q - q*d/dt w + (ax_m + vy*w)*w^2  (no vx_m)
 *   MSO1 observer: xh' = ax_m + vy*w + L*(vx - xh), r = vx - xh  [m/s] (MSO2 likewise with ay_m - vx*w)
 * Derivatives come from fdi_svf filters. Every signal of one relation passes through the same number of
 * equal filters (one stage for r1, r2; two for r3, r4, whose p and q already contain a derivative), so all
 * terms carry the same delay and the residual of consistent signals stays near 0 in dynamic manoeuvres.
 * r3, r4 scale with w^2: they lose sensitivity when driving straight (w -> 0). They output no fault
 * sensitivities (sens_mask 0).
 *
 * Cost per step: r1, r2 4 filters each (fdi_svf.h); r3, r4 8 filters each; an observer form no filter, its
 * observer's step (fdi_obs.h); the Cortex-M4F instructions of each function per step and a call are printed by
 * scripts/bench_fw.sh (its profile of the kinematic table).
 * Memory: the six descriptors, const (flash), their size printed by scripts/bench_fw.sh; state in the caller's
 * fdi_gen_t.
 */
#ifndef FDI_ROMO_KIN_H
#define FDI_ROMO_KIN_H

#include "fdi_gen.h"

#define FDI_ROMO_KIN_PARAM_D_X 0U /* index of d_x [m] in fdi_gen_param_t.param (fdi_diag_config_t.gen_param) */
#define FDI_ROMO_KIN_PARAM_D_Y 1U /* index of d_y [m] */
#define FDI_ROMO_KIN_D_X 1.0f     /* velocity sensor position of the ROMO model (romo_quasistatic.toml) */
#define FDI_ROMO_KIN_D_Y 0.3f

extern const fdi_gen_desc_t fdi_romo_kin_x_deriv; /* MSO1 {K1,D1,S1,S3,S4,S5}, faults f1 f3 f4 f5 */
extern const fdi_gen_desc_t fdi_romo_kin_y_deriv; /* MSO2 {K2,D2,S2,S3,S4,S5}, faults f2 f3 f4 f5 */
extern const fdi_gen_desc_t fdi_romo_kin_arr3;    /* MSO3 {K1,K2,D1,D2,S1..S4}, faults f1 f2 f3 f4 */
extern const fdi_gen_desc_t fdi_romo_kin_arr4;    /* MSO4 {K1,K2,D1,D2,S1,S2,S3,S5}, faults f1 f2 f3 f5 */
extern const fdi_gen_desc_t fdi_romo_kin_x_obs;   /* MSO1 by an observer on vx' = ax_m + vy w */
extern const fdi_gen_desc_t fdi_romo_kin_y_obs;   /* MSO2 by an observer on vy' = ay_m - vx w */

#endif /* FDI_ROMO_KIN_H */
