/*
 * bench_m4.c - bare-metal benchmark on qemu mps2-an386 (Cortex-M4F) with semihosting input and output.
 *
 * Under `qemu-system-arm -icount shift=0` the virtual clock advances 1 ns per guest instruction, and
 * SysTick (processor clock, 25 MHz on mps2) therefore counts one tick per 40 instructions. The harness
 * (1) calibrates with a loop of known length (2 instructions per iteration), (2) reads the drive of
 * bench_drive.h (file fdi_bench_drive.bin in qemu's working directory, semihosting), (3) for each table of
 * bench_drive.h, with sensitivities off and on, times every fdi_diag_step call and prints per phase the mean
 * instructions per step (ticks * 40 / steps) and the largest single step over the whole drive.
 * Quantisation: 40 instructions per reading (the mean over hundreds of steps is far finer; the largest step is
 * exact to 40 instructions).
 * Profile build (scripts/profile_m4.sh): -DBENCH_PROFILE runs only the configuration BENCH_ONLY (table * 2 +
 * sensitivities) and calls fdi_diag_step through one never-inlined function per phase (bench_step_<phase> of
 * bench_phase_step.h), so that an instruction trace attributes every step to its phase (fw/bench/m4/profile.py).
 */
#include <stdint.h>

#include "bench_drive.h"
#ifdef BENCH_PROFILE
#include "bench_phase_step.h"
#endif
#include "fdi_diag.h"
#include "fdi_ecu.h"

#define CAL_LOOPS 100000U
#define INSN_PER_TICK 40U /* 1 ns per instruction (shift 0) / 25 MHz */

#define SYST_CSR (*(volatile uint32_t *)0xE000E010U)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014U)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018U)

void bench_exit(int code);

static uint32_t words[BENCH_WORDS];
static fdi_diag_t diag;

static uint32_t semi_call(uint32_t op, const void *arg)
{
    register uint32_t r0 __asm("r0") = op;
    register const void *r1 __asm("r1") = arg;
    __asm volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

static void put(const char *s)
{
    (void)semi_call(0x04U, s); /* SYS_WRITE0 */
}

static void put_u(uint32_t v)
{
    char buf[12];
    uint32_t i = 11U;
    buf[11] = '\0';
    do
    {
        --i;
        buf[i] = (char)('0' + (char)(v % 10U));
        v /= 10U;
    } while ((v != 0U) && (i > 0U));
    put(&buf[i]);
}

static void put_x(uint32_t v)
{
    static const char hex[] = "0123456789abcdef";
    char buf[9];
    uint32_t i;
    for (i = 0U; i < 8U; ++i)
    {
        buf[i] = hex[(v >> (28U - (4U * i))) & 0xFU];
    }
    buf[8] = '\0';
    put(buf);
}

void bench_exit(int code)
{
    const uint32_t block[2] = {0x20026U, (uint32_t)code}; /* ADP_Stopped_ApplicationExit */
    (void)semi_call(0x20U, block);                        /* SYS_EXIT_EXTENDED: exit status = code */
    for (;;)
    {
    }
}

/* The drive file into words[]; the number of words read (0 on failure). */
static uint32_t read_drive(void)
{
    static const char name[] = "fdi_bench_drive.bin";
    const uint32_t open_args[3] = {(uint32_t)(uintptr_t)name, 0U, (uint32_t)(sizeof name - 1U)}; /* mode "r" */
    const uint32_t h = semi_call(0x01U, open_args);                                            /* SYS_OPEN */
    uint32_t n = 0U;
    if (h != 0xFFFFFFFFU)
    {
        const uint32_t read_args[3] = {h, (uint32_t)(uintptr_t)words, (uint32_t)sizeof words};
        const uint32_t left = semi_call(0x06U, read_args); /* SYS_READ: bytes not read */
        n = ((uint32_t)sizeof words - left) / 4U;
        (void)semi_call(0x02U, &h); /* SYS_CLOSE */
    }
    return n;
}

static uint32_t ticks_since(uint32_t start)
{
    return (start - SYST_CVR) & 0x00FFFFFFU;
}

static void cal_loop(uint32_t n)
{
    __asm volatile("1: subs %0, %0, #1\n\tbne 1b" : "+r"(n) : : "cc");
}

static void put_phase(const char *what, uint32_t ticks, uint32_t steps)
{
    put(what);
    if (steps > 0U)
    {
        put_u((uint32_t)(((uint64_t)ticks * INSN_PER_TICK) / steps));
    }
    else
    {
        put("-");
    }
}

#ifdef BENCH_PROFILE
#define BENCH_STEP(ph, in, v) bench_phase_step(&diag, (ph), (in), (v))
#else
#define BENCH_STEP(ph, in, v) fdi_diag_step(&diag, (in), (v))
#endif

/* Table k through the drive; false on a failing call. */
static bool bench_table_drive(const bench_drive_t *drive, uint32_t k, bool sens, uint32_t t_empty)
{
    static fdi_diag_result_t res;
    const char *name = "";
    const fdi_table_t *table = bench_table(k, &name);
    const fdi_diag_config_t cfg = bench_config(table, sens);
    uint32_t ticks[BENCH_N_PHASES] = {0U, 0U, 0U, 0U};
    uint32_t count[BENCH_N_PHASES] = {0U, 0U, 0U, 0U};
    uint32_t worst = 0U;
    uint32_t worst_step = 0U;
    uint32_t digest = BENCH_DIGEST_START;
    bool settled = false;
    bool ok = (fdi_diag_init(&diag, &cfg) == FDI_OK) && (fdi_diag_result(&diag, &res) == FDI_OK);
    uint32_t i;
    for (i = 0U; ok && (i < drive->n_steps); ++i)
    {
        fdi_frame_t in;
        const uint32_t validity = bench_drive_frame(drive, i, &in);
        const bench_phase_t ph = bench_phase(table, &res, i, drive->fault_step, &settled);
        const uint32_t t0 = SYST_CVR;
        const fdi_status_t st = BENCH_STEP(ph, &in, validity);
        const uint32_t t = ticks_since(t0) - t_empty;
        ticks[ph] += t;
        count[ph]++;
        if (t > worst)
        {
            worst = t;
            worst_step = i;
        }
        ok = (st == FDI_OK) && (fdi_diag_result(&diag, &res) == FDI_OK);
        digest = bench_digest(digest, table, &res);
    }
    if (ok)
    {
        put("m4: ");
        put(name);
        put(sens ? ", sensitivities on: " : ", sensitivities off: ");
        put_phase("fault-free ", ticks[BENCH_FAULT_FREE], count[BENCH_FAULT_FREE]);
        put_phase(", episode ", ticks[BENCH_EPISODE], count[BENCH_EPISODE]);
        put_phase(", undecided ", ticks[BENCH_UNDECIDED], count[BENCH_UNDECIDED]);
        put_phase(", warm-up ", ticks[BENCH_WARMUP], count[BENCH_WARMUP]);
        put(", worst ");
        put_u(worst * INSN_PER_TICK);
        put(" (step ");
        put_u(worst_step);
        put(") instructions/step; steps fault-free ");
        put_u(count[BENCH_FAULT_FREE]);
        put(", episode ");
        put_u(count[BENCH_EPISODE]);
        put(", undecided ");
        put_u(count[BENCH_UNDECIDED]);
        put("; results digest ");
        put_x(digest);
        put("\n");
    }
    return ok;
}

int main(void)
{
    bench_drive_t drive;
    uint32_t k;
    uint32_t t0;
    uint32_t t_empty;
    uint32_t t_cal;
    int rc = 0;
    SYST_RVR = 0x00FFFFFFU;
    SYST_CVR = 0U;
    SYST_CSR = 5U; /* enable, processor clock, no interrupt */
    t0 = SYST_CVR;
    t_empty = ticks_since(t0);
    t0 = SYST_CVR;
    cal_loop(CAL_LOOPS);
    t_cal = ticks_since(t0);
    put("m4: calibration loop expected ");
    put_u(2U * CAL_LOOPS);
    put(" insns, measured ");
    put_u((t_cal - t_empty) * INSN_PER_TICK);
    put("\n");
    if (!bench_drive_open(&drive, words, read_drive()))
    {
        put("m4: cannot read fdi_bench_drive.bin (run qemu in the directory of the drive)\n");
        rc = 10;
    }
#ifdef BENCH_PROFILE
    for (k = BENCH_ONLY; (rc == 0) && (k < (BENCH_ONLY + 1U)); ++k)
#else
    for (k = 0U; (rc == 0) && (k < (2U * BENCH_N_TABLES)); ++k)
#endif
    {
        rc = bench_table_drive(&drive, k / 2U, (k % 2U) != 0U, t_empty) ? 0 : (int)(k + 1U);
    }
    put("m4: sizeof(fdi_diag_t) ");
    put_u((uint32_t)sizeof diag);
    put(" bytes, sizeof(fdi_diag_result_t) ");
    put_u((uint32_t)sizeof(fdi_diag_result_t));
    put(" bytes, sizeof(fdi_ecu_t) ");
    put_u((uint32_t)sizeof(fdi_ecu_t));
    put(" bytes\n");
    return rc;
}
