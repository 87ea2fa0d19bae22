/*
 * bench_drive.h - what the benchmarks step through and how they classify the steps (header-only, shared by
 * bench_host.c and m4/bench_m4.c).
 *
 * The drive: a simulated ROMO drive as the ECU's steps see it, fault-free and then two isolation episodes, one that
 * the ROMO table isolates at once and one it cannot decide (host_tools/bench/fw_bench_drive.py writes it;
 * scripts/bench_fw.sh makes it). In memory: a buffer of 32-bit words,
 * [magic, n_steps, n_signals, fault_step] then per step the validity mask and n_signals float values.
 * The tables: the kinematic table (4 hand-written tests) and the generated ROMO table that ships, each with the
 * diagnoser's defaults (fdi_diag_config_default) and the ROMO model's velocity-sensor position.
 * The phase of a step, from the result before it: "episode" while an isolation episode is active and its candidates
 * are one class or none, "undecided" while they span several classes (the exoneration asks the generators for their
 * sensitivities), "fault-free" once every test with a generator has been evaluable and before the first fault
 * starts, "warm-up" otherwise.
 */
#ifndef BENCH_DRIVE_H
#define BENCH_DRIVE_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "fdi_diag.h"
#include "fdi_kin_table.h"
#include "fdi_romo_kin.h"
#include "fdi_romo_signals.h"
#include "fdi_romo_table.h"

#define BENCH_MAGIC 0x42494446U
#define BENCH_MAX_STEPS 2500U
#define BENCH_WORDS (4U + (BENCH_MAX_STEPS * (1U + ROMO_SIG_COUNT)))

typedef struct
{
    const uint32_t *w; /* the file's words */
    uint32_t n_steps;
    uint32_t n_signals;
    uint32_t fault_step;
} bench_drive_t;

/* false when the buffer (n_words words) is not a drive of the ROMO frame. */
static inline bool bench_drive_open(bench_drive_t *d, const uint32_t *w, uint32_t n_words)
{
    bool ok = (n_words >= 4U) && (w[0] == BENCH_MAGIC) && (w[2] == (uint32_t)ROMO_SIG_COUNT) &&
              (w[1] <= BENCH_MAX_STEPS) && (n_words >= (4U + (w[1] * (1U + w[2]))));
    if (ok)
    {
        d->w = w;
        d->n_steps = w[1];
        d->n_signals = w[2];
        d->fault_step = w[3];
    }
    return ok;
}

/* Step k of the drive: the frame (signals beyond the ROMO frame 0) and its validity. */
static inline uint32_t bench_drive_frame(const bench_drive_t *d, uint32_t k, fdi_frame_t *in)
{
    const uint32_t *p = &d->w[4U + (k * (1U + d->n_signals))];
    uint32_t i;
    for (i = 0U; i < FDI_FRAME_MAX_SIGNALS; ++i)
    {
        in->value[i] = 0.0f;
    }
    for (i = 0U; i < d->n_signals; ++i)
    {
        memcpy(&in->value[i], &p[1U + i], sizeof(float));
    }
    return p[0];
}

#define BENCH_N_TABLES 2U
static inline const fdi_table_t *bench_table(uint32_t k, const char **name)
{
    *name = (k == 0U) ? "kinematic table" : "generated ROMO table";
    return (k == 0U) ? &fdi_kin_table : &fdi_romo_table;
}

/* The diagnoser's defaults for `table`, the vehicle's sensor position, sensitivities as requested. */
static inline fdi_diag_config_t bench_config(const fdi_table_t *table, bool sens)
{
    fdi_diag_config_t c;
    (void)fdi_diag_config_default(&c, table);
    c.gen_param[FDI_ROMO_KIN_PARAM_D_X] = FDI_ROMO_KIN_D_X;
    c.gen_param[FDI_ROMO_KIN_PARAM_D_Y] = FDI_ROMO_KIN_D_Y;
    c.sensitivities = sens;
    return c;
}

typedef enum
{
    BENCH_WARMUP = 0,
    BENCH_FAULT_FREE = 1,
    BENCH_EPISODE = 2,
    BENCH_UNDECIDED = 3
} bench_phase_t;
#define BENCH_N_PHASES 4U

/* Phase of step k from the result of step k - 1; *settled latches "every test has been evaluable". */
static inline bench_phase_t bench_phase(const fdi_table_t *t, const fdi_diag_result_t *last, uint32_t k,
                                        uint32_t fault_step, bool *settled)
{
    uint32_t with_gen = 0U;
    uint32_t i;
    bench_phase_t ph = BENCH_WARMUP;
    for (i = 0U; i < (uint32_t)t->n_tests; ++i)
    {
        with_gen |= (t->tests[i].gen != NULL) ? ((uint32_t)1U << i) : 0U;
    }
    if ((last->evaluable_mask & with_gen) == with_gen)
    {
        *settled = true;
    }
    if (last->iso.detected)
    {
        ph = (last->iso.n_classes > 1U) ? BENCH_UNDECIDED : BENCH_EPISODE;
    }
    else if (*settled && (k < fault_step))
    {
        ph = BENCH_FAULT_FREE;
    }
    else
    {
        /* warm-up (or after the fault without an episode) */
    }
    return ph;
}

/* FNV-1a over 32-bit words, a byte at a time (the same on any byte order). */
static inline uint32_t bench_fnv(uint32_t h, uint32_t w)
{
    uint32_t x = h;
    uint32_t b;
    for (b = 0U; b < 4U; ++b)
    {
        x = (x ^ ((w >> (8U * b)) & 0xFFU)) * 16777619U;
    }
    return x;
}

static inline uint32_t bench_float_bits(float v)
{
    uint32_t w;
    memcpy(&w, &v, sizeof w);
    return w;
}

/* The digest h carried over one step's result: its masks, candidates and class, and the bits of every test's
   residual and test ratio and of every sensitivity (the step's whole arithmetic, so that two builds that print the
   same digest computed the same values at every step). Start with BENCH_DIGEST_START. */
#define BENCH_DIGEST_START 2166136261U
static inline uint32_t bench_digest(uint32_t h, const fdi_table_t *t, const fdi_diag_result_t *r)
{
    uint32_t x = bench_fnv(bench_fnv(bench_fnv(h, r->alarm_mask), r->evaluable_mask), r->accused_mask);
    uint32_t i;
    x = bench_fnv(bench_fnv(x, r->iso.candidates), r->iso.class_mask);
    for (i = 0U; i < (uint32_t)t->n_tests; ++i)
    {
        x = bench_fnv(bench_fnv(x, bench_float_bits(r->residual[i])), bench_float_bits(r->ratio[i]));
    }
    for (i = 0U; i < FDI_DIAG_MAX_SENS; ++i)
    {
        x = bench_fnv(x, bench_float_bits(r->sens[i]));
    }
    return x;
}

#endif /* BENCH_DRIVE_H */
