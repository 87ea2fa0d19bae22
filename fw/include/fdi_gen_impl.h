/*
 * fdi_gen_impl.h - building blocks for generator implementations (generated vehicle code and hand-written
 * generators); applications use fdi_gen.h.
 *
 * Hand-written generators (instance filters, fdi_gen_t):
 * fdi_gen_filter_step: one step of filter idx of the instance (idx < desc->n_filters), or its reset to
 *   steady state at u (then out = {u, 0}). fdi_gen_status_worst: the first non-OK of two statuses.
 * fdi_gen_finish: *r = value (0 while resetting) when st is OK and value is finite, else the failing status
 *   (NOT_FINITE for value). fdi_gen_sens_finish: st, or NOT_FINITE when one of the n sensitivities written
 *   is not finite.
 * Observer generators (integral causality for one state, fdi_analysis/residuals/observer.py): the estimate
 *   lives in an fdi_obs_t (xh = estimate, g_prev = observer input G of the previous step).
 *   fdi_gen_obs_predict: xh[k] = xh[k-1] + phi * (g_prev + g1) / 2 with phi = expm1(jac dt) / jac (dt at
 *   jac = 0), the exponential of the error pole jac = a + L c; stable for every jac < 0. obs NULL or
 *   par NULL give 0 (callers pass their checked state).
 *   fdi_gen_obs_store: keep xh and g_prev for the next step; NOT_FINITE (nothing stored) on NaN/Inf, BAD_ARG
 *   on NULL.
 * Inline helpers of generated expressions (static inline, no library; the generated generators, built for size,
 *   may still call them: the profile of scripts/bench_fw.sh lists such calls): fdi_gen_heaviside(x): 1 for x > 0,
 *   else 0; fdi_gen_sign(x): -1, 0, 1 (derivatives of Max and Abs); fdi_gen_max / fdi_gen_min: the larger / smaller
 *   of two values (a NaN operand may propagate, where fmaxf would drop it: the caller's finiteness check then sees it).
 * fdi_gen_tanh: tanh of the generated expressions (the brake torque's sign law of the wheel speeds).
 * fdi_gen_sin, fdi_gen_cos: sin and cos of the generated expressions (the steering angles' rotations).
 * The exponentials of fdi_gen_obs_predict and fdi_gen_tanh are float-only series (fdi_gen.c, a few ulp): the C
 * library's expm1f and tanhf, general-purpose, cost several times as much on the target.
 * fdi_gen_sin and fdi_gen_cos are float-only polynomials too (fdi_gen.c: within 1.6 ulp of the exact value for
 * |x| <= 13, within 1e-7 up to |x| = 2048, NaN beyond): cheaper than the C library's, and the same operations on
 * every target, so that the generated generators compute the same bits on the host (the quality suite, the
 * bindings) as on the ECU (newlib's sinf and glibc's differ in the last bit; scripts/check_identity.sh compares a
 * digest of every step's results).
 * Cost: fdi_gen_sin and fdi_gen_cos a polynomial of degree 7 and 8 after the quadrant's reduction; the exponentials
 * a polynomial of degree 7 (for large negative arguments times 2^-n from the table); fdi_gen_tanh one division
 * more, none where it saturates. The Cortex-M4F instructions of each call, for the arguments of the benchmark drive,
 * are printed by scripts/bench_fw.sh (its profile: calls per step and instructions a call).
 * Memory: none (a 28-entry const table).
 */
#ifndef FDI_GEN_IMPL_H
#define FDI_GEN_IMPL_H

#include <stdbool.h>
#include <stdint.h>

#include "fdi_gen.h"

fdi_status_t fdi_gen_filter_step(fdi_gen_t *g, const fdi_gen_param_t *par, uint32_t idx, float u, bool reset,
                                 fdi_svf_out_t *out);
fdi_status_t fdi_gen_status_worst(fdi_status_t a, fdi_status_t b);
fdi_status_t fdi_gen_finish(fdi_status_t st, float value, bool reset, float *r);
fdi_status_t fdi_gen_sens_finish(fdi_status_t st, const float *sens, uint32_t n);

/* tanh(x) in float, a few ulp (fdi_gen.c: +-1 from |x| >= 9.1, else from e^-2|x|); NaN for NaN. */
float fdi_gen_tanh(float x);

/* sin(x) and cos(x) in float, within 1.6 ulp for |x| <= 13 and 1e-7 for |x| <= 2048; NaN beyond (no angle of a
   vehicle model: the test is then not evaluable for the step) and for NaN and +-Inf. */
float fdi_gen_sin(float x);
float fdi_gen_cos(float x);

float fdi_gen_obs_predict(const fdi_obs_t *obs, const fdi_gen_param_t *par, float g1, float jac);
fdi_status_t fdi_gen_obs_store(fdi_obs_t *obs, float xh, float g_next);

static inline float fdi_gen_heaviside(float x)
{
    return (x > 0.0f) ? 1.0f : 0.0f;
}

static inline float fdi_gen_sign(float x)
{
    float s = 0.0f;
    if (x > 0.0f)
    {
        s = 1.0f;
    }
    else if (x < 0.0f)
    {
        s = -1.0f;
    }
    else
    {
        /* 0 (and NaN, caught by the caller's finiteness check) */
    }
    return s;
}

static inline float fdi_gen_max(float a, float b)
{
    return (a > b) ? a : b;
}

static inline float fdi_gen_min(float a, float b)
{
    return (a < b) ? a : b;
}

#endif /* FDI_GEN_IMPL_H */
