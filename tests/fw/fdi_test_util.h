/*
 * fdi_test_util.h - shared helpers of the fw unit tests: tolerance checks that print the numbers,
 * a deterministic Gaussian noise source and the analytic reference vehicle of the kinematic tests.
 *
 * Reference vehicle (body frame at the CoG, exact kinematics K1, K2 and sensors S1..S5):
 *   vx(t) = VX0 + VX1 sin(2 pi 0.1 t)           [m/s]    constant-speed turn plus a speed oscillation
 *   vy(t) = VY1 sin(2 pi 0.2 t + 0.5)            [m/s]
 *   w(t)  = W0 + W1 sin(2 pi 0.25 t)             [rad/s]  never near 0 (ARR3/4 need w != 0)
 *   ax = dvx/dt - vy w,  ay = dvy/dt + vx w
 *   ax_m = ax + f1, ay_m = ay + f2, psidot_m = w + f3, vx_m = vx - d_y w + f4, vy_m = vy + d_x w + f5
 */
#ifndef FDI_TEST_UTIL_H
#define FDI_TEST_UTIL_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fdi_signals.h"

#define TEST_PI 3.14159265358979323846

/* Fail (through cmocka's assert_true) unless |actual - expected| <= tol; print all three on failure. */
#define assert_near(actual, expected, tol)                                                                        \
    do                                                                                                            \
    {                                                                                                             \
        const double a_ = (double)(actual);                                                                       \
        const double e_ = (double)(expected);                                                                     \
        const double t_ = (double)(tol);                                                                          \
        if (!(fabs(a_ - e_) <= t_))                                                                               \
        {                                                                                                         \
            print_error("%s = %.9g, expected %.9g +- %.3g (%s:%d)\n", #actual, a_, e_, t_, __FILE__, __LINE__); \
        }                                                                                                         \
        assert_true(fabs(a_ - e_) <= t_);                                                                         \
    } while (0)

/* Deterministic standard normal numbers (xorshift64* + Box-Muller). */
typedef struct
{
    uint64_t s;
} test_rng_t;

static inline double test_uniform(test_rng_t *r)
{
    r->s ^= r->s >> 12;
    r->s ^= r->s << 25;
    r->s ^= r->s >> 27;
    return ((double)((r->s * 2685821657736338717ULL) >> 11) + 0.5) / 9007199254740992.0;
}

static inline double test_normal(test_rng_t *r)
{
    const double u1 = test_uniform(r);
    const double u2 = test_uniform(r);
    return sqrt(-2.0 * log(u1)) * cos(2.0 * TEST_PI * u2);
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
static inline void veh_measure(double t, const veh_meas_cfg_t *c, test_rng_t *rng, fdi_inputs_t *in)
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
    for (i = 0; i < 5; ++i)
    {
        n[i] = (c->noise[i] > 0.0) ? c->noise[i] * test_normal(rng) : 0.0;
    }
    in->ax_m = (float)(ax + c->f[0] + n[0]);
    in->ay_m = (float)(ay + c->f[1] + n[1]);
    in->psidot_m = (float)(w + c->f[2] + n[2]);
    in->vx_m = (float)(vx - VEH_DY * w + c->f[3] + n[3]);
    in->vy_m = (float)(vy + VEH_DX * w + c->f[4] + n[4]);
    in->delta1_m = 0.05f;
    in->delta2_m = 0.05f;
    in->delta3_m = 0.0f;
    in->delta4_m = 0.0f;
    in->iTM1_m = 20.0f;
    in->iTM2_m = 20.0f;
    in->iTM3_m = 20.0f;
    in->iTM4_m = 20.0f;
    in->P_f_m = 0.0f;
    in->P_r_m = 0.0f;
    in->omega1_m = 50.0f;
    in->omega2_m = 50.0f;
    in->omega3_m = 50.0f;
    in->omega4_m = 50.0f;
}

#endif /* FDI_TEST_UTIL_H */
