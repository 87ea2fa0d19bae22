/*
 * fdi_test_vehicle.h - the analytic reference vehicle of the ROMO kinematic tests, as frames of the ROMO target
 * (fdi_romo_signals.h).
 *
 * Reference vehicle (body frame at the CoG, exact kinematics K1, K2 and sensors S1..S5):
 *   vx(t) = VX0 + VX1 sin(2 pi 0.1 t)           [m/s]    constant-speed turn plus a speed oscillation
 *   vy(t) = VY1 sin(2 pi 0.2 t + 0.5)            [m/s]
 *   w(t)  = W0 + W1 sin(2 pi 0.25 t)             [rad/s]  never near 0 (ARR3/4 need w != 0)
 *   ax = dvx/dt - vy w,  ay = dvy/dt + vx w
 *   ax_m = ax + f1, ay_m = ay + f2, psidot_m = w + f3, vx_m = vx - d_y w + f4, vy_m = vy + d_x w + f5
 */
#ifndef FDI_TEST_VEHICLE_H
#define FDI_TEST_VEHICLE_H

#include "fdi_frame.h"
#include "fdi_kin_table.h"
#include "fdi_romo_signals.h"
#include "fdi_test_util.h"

/* Reaction sizes of the kinematic tests as the isolation tests state them (row fault j, column test i, fdi_table.h
   test_size), with exoneration margin 2: the committed calibration fdi_kin_calibration.h is regenerated from
   simulated drives and moves with the simulator and the ECU's CAN view, the logic under test must not. */
static const float veh_kin_test_size[5 * 4] = {
    0.1f,  0.0f,   0.2f,  0.7f,  /* f1 */
    0.0f,  0.1f,   0.7f,  0.3f,  /* f2 */
    0.15f, 0.007f, 0.07f, 0.02f, /* f3: MSO1 sees a yaw rate offset only as vy * f3 */
    0.1f,  0.3f,   0.1f,  0.0f,  /* f4 */
    0.5f,  0.1f,   0.0f,  0.1f,  /* f5 */
};

/* *copy = the kinematic table with the reaction sizes above. */
static inline const fdi_table_t *veh_kin_table(fdi_table_t *copy)
{
    *copy = fdi_kin_table;
    copy->test_size = veh_kin_test_size;
    copy->exoneration_margin = 2.0f;
    return copy;
}

/* Reference vehicle and sensor layout. */
#define VEH_VX0 10.0
#define VEH_VX1 1.0
#define VEH_VY1 0.3
#define VEH_W0 0.5
#define VEH_W1 0.1
#define VEH_DX 1.2
#define VEH_DY 0.3

typedef struct
{
    double f[5];      /* additive faults f1..f5 at this instant */
    double noise[5];  /* noise sigma of ax_m, ay_m, psidot_m, vx_m, vy_m (0 = exact) */
} veh_meas_cfg_t;

/* Fill *in with the measurements at time t; delta/iTM/P/omega get plausible constants. */
static inline void veh_measure(double t, const veh_meas_cfg_t *c, test_rng_t *rng, fdi_frame_t *in)
{
    const double wv = 2.0 * TEST_PI * 0.1;
    const double wy = 2.0 * TEST_PI * 0.2;
    const double ww = 2.0 * TEST_PI * 0.25;
    const double vx = VEH_VX0 + VEH_VX1 * sin(wv * t);
    const double dvx = VEH_VX1 * wv * cos(wv * t);
    const double vy = VEH_VY1 * sin(wy * t + 0.5);
    const double dvy = VEH_VY1 * wy * cos(wy * t + 0.5);
    const double w = VEH_W0 + VEH_W1 * sin(ww * t);
    const double ax = dvx - vy * w;
    const double ay = dvy + vx * w;
    double n[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
    int i;
    for (i = 0; i < (int)FDI_FRAME_MAX_SIGNALS; ++i)
    {
        in->value[i] = 0.0f;
    }
    for (i = 0; i < 5; ++i)
    {
        n[i] = (c->noise[i] > 0.0) ? c->noise[i] * test_normal(rng) : 0.0;
    }
    in->value[ROMO_SIG_AX_M] = (float)(ax + c->f[0] + n[0]);
    in->value[ROMO_SIG_AY_M] = (float)(ay + c->f[1] + n[1]);
    in->value[ROMO_SIG_PSIDOT_M] = (float)(w + c->f[2] + n[2]);
    in->value[ROMO_SIG_VX_M] = (float)(vx - VEH_DY * w + c->f[3] + n[3]);
    in->value[ROMO_SIG_VY_M] = (float)(vy + VEH_DX * w + c->f[4] + n[4]);
    in->value[ROMO_SIG_DELTA1_M] = 0.05f;
    in->value[ROMO_SIG_DELTA2_M] = 0.05f;
    in->value[ROMO_SIG_DELTA3_M] = 0.0f;
    in->value[ROMO_SIG_DELTA4_M] = 0.0f;
    in->value[ROMO_SIG_ITM1_M] = 20.0f;
    in->value[ROMO_SIG_ITM2_M] = 20.0f;
    in->value[ROMO_SIG_ITM3_M] = 20.0f;
    in->value[ROMO_SIG_ITM4_M] = 20.0f;
    in->value[ROMO_SIG_P_F_M] = 0.0f;
    in->value[ROMO_SIG_P_R_M] = 0.0f;
    in->value[ROMO_SIG_OMEGA1_M] = 50.0f;
    in->value[ROMO_SIG_OMEGA2_M] = 50.0f;
    in->value[ROMO_SIG_OMEGA3_M] = 50.0f;
    in->value[ROMO_SIG_OMEGA4_M] = 50.0f;
}

#endif /* FDI_TEST_VEHICLE_H */
