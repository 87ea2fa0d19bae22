/*
 * bench_host.c - host benchmark: steps one fdi_diag N times on precomputed frames, for one table (0: the
 * kinematic table, 1: the generated ROMO table). Run under `valgrind --tool=callgrind
 * --toggle-collect=fdi_diag_step` (scripts/bench_fw.sh): the collected instruction count divided by N is the cost
 * per step. Usage: bench_host [N] [table]
 */
#include <stdio.h>
#include <stdlib.h>

#include "bench_signals.h"
#include "fdi_diag.h"
#include "fdi_gen.h"

#define MAX_N 100000L

static fdi_frame_t frames[MAX_N];

int main(int argc, char **argv)
{
    fdi_diag_t d;
    fdi_diag_result_t res;
    const char *name = "";
    const long which = (argc > 2) ? strtol(argv[2], NULL, 10) : 0L;
    const fdi_table_t *table = bench_table((which == 1L) ? 1U : 0U, &name);
    const fdi_diag_config_t cfg = bench_config(table);
    long n = (argc > 1) ? strtol(argv[1], NULL, 10) : 10000L;
    long k;
    int rc = 0;
    if ((n < 1L) || (n > MAX_N))
    {
        n = 10000L;
    }
    for (k = 0; k < n; ++k)
    {
        bench_frame((float)k * BENCH_DT, &frames[k]);
    }
    if (fdi_diag_init(&d, &cfg) != FDI_OK)
    {
        rc = 1;
    }
    for (k = 0; (rc == 0) && (k < n); ++k)
    {
        if (fdi_diag_step(&d, &frames[k], ROMO_SIGM_ALL) != FDI_OK)
        {
            rc = 2;
        }
    }
    if ((rc == 0) && (fdi_diag_result(&d, &res) == FDI_OK))
    {
        printf("steps %ld %s: %u tests, evaluable 0x%X alarms 0x%X sizeof(fdi_diag_t) %zu sizeof(fdi_gen_t) %zu\n", n,
               name, (unsigned)table->n_tests, (unsigned)res.evaluable_mask, (unsigned)res.alarm_mask, sizeof d,
               sizeof(fdi_gen_t));
    }
    return rc;
}
