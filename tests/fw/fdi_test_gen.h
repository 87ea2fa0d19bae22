/*
 * fdi_test_gen.h - a generator set (fdi_gen.h) run on its own, every slot every step, for the unit tests: the bank
 * and one observer state per slot in one struct, all signals usable (the caller passes finite frames), the first
 * step restarting every filter and observer. Header-only, vehicle-independent.
 */
#ifndef FDI_TEST_GEN_H
#define FDI_TEST_GEN_H

#include <stdbool.h>
#include <stdint.h>

#include "fdi_gen.h"

typedef struct
{
    const fdi_gen_set_t *set;
    uint32_t live;
    fdi_svf_t bank[FDI_GEN_MAX_BANK];
    fdi_obs_t obs[FDI_GEN_MAX_SLOTS];
    uint8_t at[FDI_GEN_MAX_SLOTS];
    uint8_t sens_at[FDI_GEN_MAX_SLOTS];
} test_set_t;

static inline void test_set_init(test_set_t *t, const fdi_gen_set_t *set, const fdi_gen_desc_t *descs)
{
    uint32_t k;
    uint32_t off = 0U;
    t->set = set;
    t->live = 0U;
    for (k = 0U; k < FDI_GEN_MAX_SLOTS; ++k)
    {
        t->at[k] = (uint8_t)k;
        t->sens_at[k] = (uint8_t)off;
        if (k < (uint32_t)set->n_slots)
        {
            off += fdi_gen_sens_count(&descs[k]);
        }
    }
}

/* One step of every slot of `run` at frame `in` (restart: the first step); r[slot], sens at sens_at[slot] when
   `sens` is non-NULL, the spread at spread[slot] when `spread` is non-NULL (the caller zeroes it). Returns the
   failed slots. */
static inline uint32_t test_set_step_spread(test_set_t *t, const fdi_gen_param_t *par, const fdi_frame_t *in,
                                            uint32_t run, bool restart, float *r, float *sens, float *spread)
{
    fdi_gen_io_t io;
    fdi_frame_t frame = *in;
    const uint32_t all = fdi_gen_derive(t->set, &frame, 0xFFFFFFFFU);
    uint32_t failed = fdi_gen_bank_step(t->set, t->bank, &par->svf, &frame, all, restart ? 0U : t->live);
    t->live = all & ~failed;
    io.par = par;
    io.in = &frame;
    io.bank = t->bank;
    io.obs = t->obs;
    io.r = r;
    io.at = t->at;
    io.sens = sens;
    io.sens_at = t->sens_at;
    io.run = run;
    io.restart = restart ? run : 0U;
    io.sens_mask = (sens != NULL) ? run : 0U;
    io.spread = spread;
    io.failed = 0U;
    t->set->step(&io);
    return io.failed | ((failed != 0U) ? run : 0U);
}

/* test_set_step_spread() without the spread. */
static inline uint32_t test_set_step(test_set_t *t, const fdi_gen_param_t *par, const fdi_frame_t *in, uint32_t run,
                                     bool restart, float *r, float *sens)
{
    return test_set_step_spread(t, par, in, run, restart, r, sens, NULL);
}

#endif /* FDI_TEST_GEN_H */
