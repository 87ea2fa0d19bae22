/*
 * bench_m4.c - bare-metal benchmark on qemu mps2-an386 (Cortex-M4F) with semihosting output.
 *
 * Under `qemu-system-arm -icount shift=0` the virtual clock advances 1 ns per guest instruction, and
 * SysTick (processor clock, 25 MHz on mps2) therefore counts one tick per 40 instructions. The harness
 * (1) calibrates with a loop of known length (2 instructions per iteration), (2) for each table of
 * bench_signals.h times N fdi_diag_step calls on precomputed frames as one block, (3) prints ticks * 40 / N.
 * Quantisation: 40 instructions per block, i.e. < 0.1 instruction per step for N = 1000.
 */
#include <stdint.h>

#include "bench_signals.h"
#include "fdi_diag.h"

#define N_STEPS 1000U
#define WARM_STEPS 400U
#define CAL_LOOPS 100000U
#define INSN_PER_TICK 40U /* 1 ns per instruction (shift 0) / 25 MHz */

#define SYST_CSR (*(volatile uint32_t *)0xE000E010U)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014U)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018U)

void bench_exit(int code);

static fdi_frame_t frames[WARM_STEPS + N_STEPS];
static fdi_diag_t diag;

static void semi_call(uint32_t op, const void *arg)
{
    register uint32_t r0 __asm("r0") = op;
    register const void *r1 __asm("r1") = arg;
    __asm volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
}

static void put(const char *s)
{
    semi_call(0x04U, s); /* SYS_WRITE0 */
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

void bench_exit(int code)
{
    const uint32_t block[2] = {0x20026U, (uint32_t)code}; /* ADP_Stopped_ApplicationExit */
    semi_call(0x20U, block);                              /* SYS_EXIT_EXTENDED: exit status = code */
    for (;;)
    {
    }
}

static uint32_t ticks_since(uint32_t start)
{
    return (start - SYST_CVR) & 0x00FFFFFFU;
}

static void cal_loop(uint32_t n)
{
    __asm volatile("1: subs %0, %0, #1\n\tbne 1b" : "+r"(n) : : "cc");
}

/* Instructions per fdi_diag_step of table k (0 on failure); *res gets the last result. */
static uint32_t bench_table_steps(uint32_t k, uint32_t t_empty, fdi_diag_result_t *res)
{
    const char *name = "";
    const fdi_diag_config_t cfg = bench_config(bench_table(k, &name));
    uint32_t i;
    uint32_t t0;
    uint32_t insns = 0U;
    int rc = (fdi_diag_init(&diag, &cfg) == FDI_OK) ? 0 : 1;
    for (i = 0U; (rc == 0) && (i < WARM_STEPS); ++i) /* past the warm-up: every test evaluated */
    {
        rc = (fdi_diag_step(&diag, &frames[i], ROMO_SIGM_ALL) == FDI_OK) ? 0 : 2;
    }
    t0 = SYST_CVR;
    for (i = 0U; (rc == 0) && (i < N_STEPS); ++i)
    {
        rc = (fdi_diag_step(&diag, &frames[WARM_STEPS + i], ROMO_SIGM_ALL) == FDI_OK) ? 0 : 2;
    }
    insns = ((ticks_since(t0) - t_empty) * INSN_PER_TICK) / N_STEPS;
    if ((rc == 0) && (fdi_diag_result(&diag, res) == FDI_OK))
    {
        put("m4: fdi_diag_step insns/step ");
        put_u(insns);
        put(" (");
        put(name);
        put(", N ");
        put_u(N_STEPS);
        put(", evaluable mask ");
        put_u(res->evaluable_mask);
        put(", alarm mask ");
        put_u(res->alarm_mask);
        put(")\n");
    }
    return (rc == 0) ? insns : 0U;
}

int main(void)
{
    fdi_diag_result_t res;
    uint32_t k;
    uint32_t t0;
    uint32_t t_empty;
    uint32_t t_cal;
    int rc = 0;
    for (k = 0U; k < (WARM_STEPS + N_STEPS); ++k)
    {
        bench_frame((float)k * BENCH_DT, &frames[k]);
    }
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
    for (k = 0U; (rc == 0) && (k < BENCH_N_TABLES); ++k)
    {
        rc = (bench_table_steps(k, t_empty, &res) > 0U) ? 0 : (int)(k + 1U);
    }
    put("m4: sizeof(fdi_diag_t) ");
    put_u((uint32_t)sizeof diag);
    put(" bytes, sizeof(fdi_gen_t) ");
    put_u((uint32_t)sizeof(fdi_gen_t));
    put(" bytes\n");
    return rc;
}
