/*
 * bench_phase_step.h - fdi_diag_step through one never-inlined wrapper per phase of bench_drive.h
 * (bench_step_warmup, bench_step_fault_free, bench_step_episode, bench_step_undecided), so that a profiler
 * attributes every step to its phase: callgrind's inclusive count of a wrapper on the host (bench_host.c,
 * scripts/bench_fw.sh), qemu's instruction trace on the Cortex-M4F (m4/bench_m4.c built with BENCH_PROFILE,
 * scripts/profile_m4.sh). Header-only; include it once per program.
 */
#ifndef BENCH_PHASE_STEP_H
#define BENCH_PHASE_STEP_H

#include <stdint.h>

#include "bench_drive.h"
#include "fdi_diag.h"

/* External, as their names are what the profilers look for (a static one could be cloned under another name). */
__attribute__((noinline)) fdi_status_t bench_step_warmup(fdi_diag_t *d, const fdi_frame_t *in, uint32_t v);
__attribute__((noinline)) fdi_status_t bench_step_fault_free(fdi_diag_t *d, const fdi_frame_t *in, uint32_t v);
__attribute__((noinline)) fdi_status_t bench_step_episode(fdi_diag_t *d, const fdi_frame_t *in, uint32_t v);
__attribute__((noinline)) fdi_status_t bench_step_undecided(fdi_diag_t *d, const fdi_frame_t *in, uint32_t v);

fdi_status_t bench_step_warmup(fdi_diag_t *d, const fdi_frame_t *in, uint32_t v)
{
    return fdi_diag_step(d, in, v);
}

fdi_status_t bench_step_fault_free(fdi_diag_t *d, const fdi_frame_t *in, uint32_t v)
{
    return fdi_diag_step(d, in, v);
}

fdi_status_t bench_step_episode(fdi_diag_t *d, const fdi_frame_t *in, uint32_t v)
{
    return fdi_diag_step(d, in, v);
}

fdi_status_t bench_step_undecided(fdi_diag_t *d, const fdi_frame_t *in, uint32_t v)
{
    return fdi_diag_step(d, in, v);
}

/* One step of `d` through the wrapper of phase `ph`. */
static fdi_status_t bench_phase_step(fdi_diag_t *d, bench_phase_t ph, const fdi_frame_t *in, uint32_t v)
{
    fdi_status_t st;
    if (ph == BENCH_FAULT_FREE)
    {
        st = bench_step_fault_free(d, in, v);
    }
    else if (ph == BENCH_EPISODE)
    {
        st = bench_step_episode(d, in, v);
    }
    else if (ph == BENCH_UNDECIDED)
    {
        st = bench_step_undecided(d, in, v);
    }
    else
    {
        st = bench_step_warmup(d, in, v);
    }
    return st;
}

#endif /* BENCH_PHASE_STEP_H */
