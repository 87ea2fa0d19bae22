/*
 * bench_host.c - host benchmark: one table through the drive of bench_drive.h, every fdi_diag_step called through
 * the wrapper of its phase (bench_phase_step.h: bench_step_warmup, _fault_free, _episode, _undecided). Run under
 * `valgrind --tool=callgrind --collect-atstart=no --toggle-collect='bench_step_*'` (scripts/bench_fw.sh): the
 * inclusive instruction count of a wrapper divided by its step count (printed) is the cost per step of that phase.
 * Usage: bench_host DRIVE.bin TABLE(0 kinematic, 1 ROMO) SENSITIVITIES(0, 1)
 */
#include <stdio.h>
#include <stdlib.h>

#include "bench_drive.h"
#include "bench_phase_step.h"
#include "fdi_diag.h"
#include "fdi_gen.h"

static uint32_t words[BENCH_WORDS];

int main(int argc, char **argv)
{
    static fdi_diag_t d;
    static fdi_diag_result_t res;
    bench_drive_t drive;
    const char *name = "";
    const long which = (argc > 2) ? strtol(argv[2], NULL, 10) : 1L;
    const bool sens = (argc > 3) && (strtol(argv[3], NULL, 10) != 0L);
    const fdi_table_t *table = bench_table((which == 0L) ? 0U : 1U, &name);
    const fdi_diag_config_t cfg = bench_config(table, sens);
    uint32_t count[BENCH_N_PHASES] = {0U, 0U, 0U, 0U};
    bool settled = false;
    uint32_t digest = BENCH_DIGEST_START;
    uint32_t k;
    size_t n_words = 0U;
    int rc = 0;
    FILE *f = (argc > 1) ? fopen(argv[1], "rb") : NULL;
    if (f != NULL)
    {
        n_words = fread(words, sizeof(uint32_t), BENCH_WORDS, f);
        (void)fclose(f);
    }
    if (!bench_drive_open(&drive, words, (uint32_t)n_words))
    {
        fprintf(stderr, "usage: bench_host DRIVE.bin TABLE SENS (a drive of host_tools/bench/fw_bench_drive.py)\n");
        return 1;
    }
    if ((fdi_diag_init(&d, &cfg) != FDI_OK) || (fdi_diag_result(&d, &res) != FDI_OK))
    {
        return 2;
    }
    for (k = 0U; (rc == 0) && (k < drive.n_steps); ++k)
    {
        fdi_frame_t in;
        const uint32_t validity = bench_drive_frame(&drive, k, &in);
        const bench_phase_t ph = bench_phase(table, &res, k, drive.fault_step, &settled);
        const fdi_status_t st = bench_phase_step(&d, ph, &in, validity);
        count[ph]++;
        if ((st != FDI_OK) || (fdi_diag_result(&d, &res) != FDI_OK))
        {
            rc = 3;
        }
        digest = bench_digest(digest, table, &res);
    }
    printf("steps %u %s, sensitivities %s: warm-up %u, fault-free %u, episode %u, undecided %u steps; "
           "sizeof(fdi_diag_t) %zu; results digest %08x\n",
           (unsigned)drive.n_steps, name, sens ? "on" : "off", (unsigned)count[BENCH_WARMUP],
           (unsigned)count[BENCH_FAULT_FREE], (unsigned)count[BENCH_EPISODE], (unsigned)count[BENCH_UNDECIDED],
           sizeof d, (unsigned)digest);
    return rc;
}
