/*
 * fuzz_ecu.c - libFuzzer harness of the ECU core: CAN frame ingestion + fixed-step diagnosis
 * (fdi_ecu_rx / fdi_ecu_poll, fw/ecu) on the kinematic table, or the generated ROMO table.
 *
 * The bus carries the nominal traffic of dbc/romo.dbc (IMU 5 ms, velocity 10 ms, wheel robots 5 ms, brake
 * 20 ms, motion demand 20 ms) with fault-free values of the reference vehicle (tests/fw/fdi_test_util.h,
 * no noise, quantised by the DBC scaling) and correct E2E headers. The input drives a sequence of
 * operations on it, starting from a warmed-up state (3.5 s of clean traffic, the clock 0.5 s before the uint32
 * microsecond wrap): time advances, jumps and time stamps going backwards,
 * dropped frames and silent senders, arbitrary frames (any ID, DLC 0..15, any bytes; a frame of an input
 * ID that happens to carry a valid CRC gets its CRC flipped, so arbitrary content is never a value),
 * repeated and jumping alive counters, sender status nibbles, bursts of one message at the same time, raw
 * counter 15, swapped (reordered) frames, and NULL arguments.
 * Invariants after every call:
 *  - no crash and no sanitizer report; rx and poll return FDI_OK (BAD_ARG for NULL);
 *  - counters add up: per message received = accepted + rejected; total frames = sum of the per-message
 *    received + unknown ID + own frame;
 *  - the step's validity only holds signals of messages that were accepted;
 *  - kinematic table: fault-free values never isolate a fault (FDI_Status never FAULT_ISOLATED, no
 *    candidate);
 *  - at most one diagnosis frame per poll, the bus's diagnosis ID, DLC 8, with a valid E2E CRC.
 */
#include <math.h>
#include <stdbool.h>

#include "fdi_ecu.h"
#include "fdi_kin_table.h"
#include "fdi_romo_table.h"
#include "fdi_test_vehicle.h"
#include "fuzz_input.h"
#include "fdi_romo_bus.h"
#include "fdi_romo_ecu.h"
#include "fdi_romo_kin.h"

#define N_MSG 8U /* the ROMO bus (generated from dbc/romo.dbc): IDs, cycle times, data IDs and signals from it */

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion */
FDI_STATIC_ASSERT(FDI_ROMO_BUS_N_MSGS == N_MSG, fuzz_sa_romo_msgs);

#define msg_id(m) (fdi_romo_bus.msgs[(m)].can_id)
#define msg_cycle_us(m) ((uint32_t)fdi_romo_bus.msgs[(m)].cycle_ms * 1000U)
#define msg_data_id(m) (fdi_romo_bus.msgs[(m)].data_id)
#define msg_sig(m) (fdi_romo_bus.msgs[(m)].signals)

typedef struct
{
    fdi_ecu_t ecu;
    const fdi_table_t *table;
    uint32_t t_us;           /* ECU clock (wraps) */
    double tv;               /* vehicle time [s], monotonic */
    uint32_t next_us[N_MSG]; /* next nominal frame, relative to the start (no wrap: elapsed time) */
    uint32_t elapsed_us;
    uint8_t counter[N_MSG];  /* alive counter of the last frame sent */
    uint8_t status[N_MSG];   /* sender status nibble of the next frames */
    uint32_t silent_until[N_MSG];
    uint32_t accepted_sig;   /* signals of messages accepted at least once */
} bus_t;

static int16_t q16(double v, double scale)
{
    double r = floor(v / scale + 0.5);
    r = (r > 32767.0) ? 32767.0 : ((r < -32768.0) ? -32768.0 : r);
    return (int16_t)r;
}

static void put16(uint8_t *d, uint32_t at, int16_t v)
{
    const uint16_t u = (uint16_t)v;
    d[at] = (uint8_t)(u & 0xFFU);
    d[at + 1U] = (uint8_t)(u >> 8);
}

/* The fault-free frame of message m at the current vehicle time, with the given alive counter. */
static void make_frame(const bus_t *b, uint32_t m, uint8_t counter, uint8_t *d)
{
    fdi_frame_t x;
    veh_meas_cfg_t mc;
    test_rng_t rng = {1U};
    uint32_t i;
    memset(&mc, 0, sizeof mc);
    if ((m == 1U) || (m == 2U))
    {
        veh_measure(b->tv, &mc, &rng, &x);
    }
    else
    {
        x.value[ROMO_SIG_DELTA1_M] = 0.05f; /* wheel, brake, demand values: the constants of veh_measure() */
        x.value[ROMO_SIG_ITM1_M] = 20.0f;
        x.value[ROMO_SIG_OMEGA1_M] = 50.0f;
    }
    memset(d, 0, 8U);
    d[1] = (uint8_t)((counter & 0x0FU) | (uint8_t)(b->status[m] << 4));
    switch (m)
    {
    case 0U: /* motion demand: speed, side slip, yaw rate (not used by the diagnosis) */
        put16(d, 2U, q16(VEH_VX0, 0.001));
        put16(d, 4U, 0);
        put16(d, 6U, q16(VEH_W0, 0.0001));
        break;
    case 1U:
        put16(d, 2U, q16((double)x.value[ROMO_SIG_AX_M], 0.001));
        put16(d, 4U, q16((double)x.value[ROMO_SIG_AY_M], 0.001));
        put16(d, 6U, q16((double)x.value[ROMO_SIG_PSIDOT_M], 0.0001));
        break;
    case 2U:
        put16(d, 2U, q16((double)x.value[ROMO_SIG_VX_M], 0.001));
        put16(d, 4U, q16((double)x.value[ROMO_SIG_VY_M], 0.001));
        break;
    case 7U:
        for (i = 2U; i < 6U; ++i)
        {
            d[i] = 0U; /* 0 bar */
        }
        break;
    default: /* wheel robots: steering angle, motor current, wheel speed */
        put16(d, 2U, q16((double)x.value[ROMO_SIG_DELTA1_M], 0.0001));
        put16(d, 4U, q16((double)x.value[ROMO_SIG_ITM1_M], 0.01));
        put16(d, 6U, q16((double)x.value[ROMO_SIG_OMEGA1_M], 0.005));
        break;
    }
    d[0] = fdi_ecu_e2e_crc(msg_data_id(m), d, 8U);
}

static void check(bus_t *b, const fdi_ecu_tx_t *tx)
{
    fdi_ecu_counters_t c;
    fdi_ecu_result_t r;
    uint32_t m;
    uint32_t k;
    uint32_t sum_rx = 0U;
    FUZZ_CHECK(fdi_ecu_counters(&b->ecu, &c) == FDI_OK, "counters");
    FUZZ_CHECK(fdi_ecu_result(&b->ecu, &r) == FDI_OK, "result");
    for (m = 0U; m < N_MSG; ++m)
    {
        uint32_t rej = 0U;
        for (k = 0U; k < FDI_ECU_N_REASONS; ++k)
        {
            rej += c.msg[m].rejected[k];
        }
        FUZZ_CHECK(c.msg[m].received == c.msg[m].accepted + rej, "message %u: received %u != accepted %u + rejected %u",
                   m, c.msg[m].received, c.msg[m].accepted, rej);
        sum_rx += c.msg[m].received;
        if (c.msg[m].accepted > 0U)
        {
            b->accepted_sig |= msg_sig(m);
        }
    }
    FUZZ_CHECK(c.frames == sum_rx + c.rejected[FDI_ECU_REJ_UNKNOWN_ID] + c.rejected[FDI_ECU_REJ_OWN_FRAME],
               "frames %u != %u + unknown + own", c.frames, sum_rx);
    FUZZ_CHECK((r.validity & ~b->accepted_sig) == 0U, "validity %08x holds never-accepted signals", r.validity);
    FUZZ_CHECK((r.diag.alarm_mask & ~r.diag.evaluable_mask) == 0U, "alarm outside evaluable");
    if (b->table == &fdi_kin_table)
    {
        FUZZ_CHECK(r.status != (uint8_t)FDI_ECU_STATUS_FAULT_ISOLATED && !r.diag.iso.isolated &&
                       r.diag.iso.candidates == 0U,
                   "fault-free values isolated a fault: candidates %08x at step %u (alarms %03x)",
                   r.diag.iso.candidates, r.step, r.diag.alarm_mask);
    }
    if (tx != NULL)
    {
        FUZZ_CHECK(tx->n_frames <= 1U, "n_frames %u", tx->n_frames);
        if (tx->n_frames == 1U)
        {
            FUZZ_CHECK(tx->frame[0].can_id == fdi_romo_bus.diag_id && tx->frame[0].dlc == 8U, "diagnosis frame id/dlc");
            FUZZ_CHECK(tx->frame[0].data[0] ==
                           fdi_ecu_e2e_crc(fdi_romo_bus.diag_data_id, tx->frame[0].data, 8U),
                       "diagnosis frame CRC");
        }
    }
}

static void rx_checked(bus_t *b, uint32_t id, const uint8_t *data, uint8_t dlc, uint32_t t_us, bool full_check)
{
    fdi_ecu_tx_t tx;
    uint8_t *copy = NULL;
    if (dlc > 0U)
    {
        copy = (uint8_t *)malloc(dlc); /* exact size: ASan sees any read beyond the DLC */
        FUZZ_CHECK(copy != NULL, "malloc");
        memcpy(copy, data, dlc);
    }
    FUZZ_CHECK(fdi_ecu_rx(&b->ecu, id, dlc, (dlc > 0U) ? copy : data, t_us) == FDI_OK, "rx");
    free(copy);
    FUZZ_CHECK(fdi_ecu_poll(&b->ecu, t_us, &tx) == FDI_OK, "poll");
    if (full_check || (tx.n_frames > 0U))
    {
        check(b, &tx);
    }
}

static void rx(bus_t *b, uint32_t id, const uint8_t *data, uint8_t dlc, uint32_t t_us)
{
    rx_checked(b, id, data, dlc, t_us, true);
}

static void send_valid(bus_t *b, uint32_t m, uint32_t t_us)
{
    uint8_t d[8];
    b->counter[m] = (uint8_t)((b->counter[m] + 1U) % 15U);
    make_frame(b, m, b->counter[m], d);
    rx_checked(b, msg_id(m), d, 8U, t_us, false); /* checked when a step ran (a diagnosis frame) */
}

/* Advance the clock by dt_us, sending the nominal frames that fall due (unless the sender is silent). */
static void advance(bus_t *b, uint32_t dt_us)
{
    const uint32_t end = b->elapsed_us + dt_us;
    for (;;)
    {
        uint32_t m;
        uint32_t best = N_MSG;
        for (m = 0U; m < N_MSG; ++m)
        {
            if ((b->next_us[m] <= end) && ((best == N_MSG) || (b->next_us[m] < b->next_us[best])))
            {
                best = m;
            }
        }
        if (best == N_MSG)
        {
            break;
        }
        b->t_us += b->next_us[best] - b->elapsed_us;
        b->tv += (double)(b->next_us[best] - b->elapsed_us) * 1e-6;
        b->elapsed_us = b->next_us[best];
        b->next_us[best] += msg_cycle_us(best);
        if (b->elapsed_us >= b->silent_until[best])
        {
            send_valid(b, best, b->t_us);
        }
    }
    b->t_us += end - b->elapsed_us;
    b->tv += (double)(end - b->elapsed_us) * 1e-6;
    b->elapsed_us = end;
    {
        fdi_ecu_tx_t tx;
        FUZZ_CHECK(fdi_ecu_poll(&b->ecu, b->t_us, &tx) == FDI_OK, "poll");
        check(b, &tx);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Warmed-up start states, one per (table, max_delta_counter): 3.5 s of clean traffic, computed once, so each
   input starts where the tests are evaluable. The clock starts 4 s before the uint32 wrap. */
static bus_t warm[2][14];
static bool have_warm[2][14];

static const bus_t *warm_start(uint32_t tab, uint32_t delta)
{
    if (!have_warm[tab][delta])
    {
        bus_t *w = &warm[tab][delta];
        fdi_ecu_config_t cfg;
        uint32_t m;
        memset(w, 0, sizeof *w);
        w->table = (tab != 0U) ? &fdi_romo_table : &fdi_kin_table;
        FUZZ_CHECK(fdi_romo_ecu_config_default(&cfg, w->table) == FDI_OK, "config_default");
        cfg.diag.gen_param[FDI_ROMO_KIN_PARAM_D_X] = (float)VEH_DX;
        cfg.diag.gen_param[FDI_ROMO_KIN_PARAM_D_Y] = (float)VEH_DY;
        cfg.max_delta_counter = (uint8_t)(1U + delta);
        FUZZ_CHECK(fdi_ecu_init(&w->ecu, &cfg) == FDI_OK, "init");
        w->t_us = 0xFFFFFFFFU - 4000000U;
        for (m = 0U; m < N_MSG; ++m)
        {
            w->next_us[m] = (uint32_t)m * 700U;
        }
        advance(w, 3500000U);
        {
            fdi_ecu_result_t r;
            FUZZ_CHECK(fdi_ecu_result(&w->ecu, &r) == FDI_OK, "result");
            FUZZ_CHECK((w->table != &fdi_kin_table) || (r.diag.evaluable_mask == 0x0FU),
                       "kin tests not evaluable after 3.5 s of clean traffic: %03x", r.diag.evaluable_mask);
        }
        have_warm[tab][delta] = true;
    }
    return &warm[tab][delta];
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_in_t in = {data, size};
    static bus_t b;
    int ops = 0;
    const uint8_t setup = fz_u8(&in);
    b = *warm_start(((setup & 0x80U) != 0U) ? 1U : 0U, (uint32_t)(setup & 0x0FU) % 14U);
    FUZZ_CHECK(fdi_ecu_rx(NULL, 128U, 8U, data, 0U) == FDI_BAD_ARG, "rx NULL self");
    FUZZ_CHECK(fdi_ecu_rx(&b.ecu, 128U, 8U, NULL, 0U) == FDI_BAD_ARG, "rx NULL data");
    FUZZ_CHECK(fdi_ecu_poll(NULL, 0U, NULL) == FDI_BAD_ARG, "poll NULL");
    while ((in.n > 0U) && (ops < 400))
    {
        const uint8_t op = fz_u8(&in);
        const uint32_t mm = (uint32_t)fz_u8(&in) % N_MSG;
        uint8_t d[16];
        ++ops;
        switch (op % 12U)
        {
        case 0U:
        case 1U:
        case 2U: /* nominal traffic for up to 25.5 ms */
            advance(&b, (uint32_t)fz_u8(&in) * 100U);
            break;
        case 3U: /* a sender goes silent for up to 2.55 s */
            b.silent_until[mm] = b.elapsed_us + (uint32_t)fz_u8(&in) * 10000U;
            break;
        case 4U: /* arbitrary frame; never a valid-CRC frame of an input message */
        {
            const uint8_t sel = fz_u8(&in);
            const uint32_t id = ((sel & 1U) != 0U) ? msg_id(mm) : ((sel & 2U) != 0U ? fdi_romo_bus.diag_id : fz_u32(&in));
            const uint8_t dlc = (uint8_t)(fz_u8(&in) % 16U);
            uint32_t i;
            for (i = 0U; i < 16U; ++i)
            {
                d[i] = fz_u8(&in);
            }
            if ((fdi_ecu_msg_index(&fdi_romo_bus, id) >= 0) && (dlc == 8U) &&
                (d[0] == fdi_ecu_e2e_crc(msg_data_id((uint32_t)fdi_ecu_msg_index(&fdi_romo_bus, id)), d, 8U)))
            {
                d[0] ^= 0x01U;
            }
            rx(&b, id, d, dlc, b.t_us);
            break;
        }
        case 5U: /* repeated alive counter (same counter, current values) */
            make_frame(&b, mm, b.counter[mm], d);
            rx(&b, msg_id(mm), d, 8U, b.t_us);
            break;
        case 6U: /* alive counter jump */
            b.counter[mm] = (uint8_t)((b.counter[mm] + 1U + (uint32_t)fz_u8(&in) % 14U) % 15U);
            break;
        case 7U: /* sender status nibble (OK, DEGRADED, LOCAL_FAULT, INIT, ..., INVALID) */
            b.status[mm] = (uint8_t)(fz_u8(&in) & 0x0FU);
            break;
        case 8U: /* burst: up to 20 frames of one message at the same time stamp */
        {
            const uint32_t n = 1U + (uint32_t)fz_u8(&in) % 20U;
            uint32_t i;
            for (i = 0U; i < n; ++i)
            {
                send_valid(&b, mm, b.t_us);
            }
            break;
        }
        case 9U: /* clock jump forward up to ~4 s without traffic, or a time stamp going backwards */
        {
            const uint32_t j = fz_u32(&in) & 0x003FFFFFU;
            if ((op & 0x10U) != 0U)
            {
                make_frame(&b, mm, (uint8_t)((b.counter[mm] + 1U) % 15U), d);
                rx(&b, msg_id(mm), d, 8U, b.t_us - (j & 0xFFFFFU));
            }
            else
            {
                uint32_t k;
                b.t_us += j;
                b.tv += (double)j * 1e-6;
                b.elapsed_us += j;
                for (k = 0U; k < N_MSG; ++k)
                {
                    b.next_us[k] = b.elapsed_us + msg_cycle_us(k);
                }
                advance(&b, 0U);
            }
            break;
        }
        case 10U: /* raw alive counter 15 (out of range) with a valid CRC */
            make_frame(&b, mm, 15U, d);
            rx(&b, msg_id(mm), d, 8U, b.t_us);
            break;
        default: /* reordered: the next two frames of a message arrive swapped */
        {
            uint8_t d2[8];
            const uint8_t c1 = (uint8_t)((b.counter[mm] + 1U) % 15U);
            const uint8_t c2 = (uint8_t)((b.counter[mm] + 2U) % 15U);
            make_frame(&b, mm, c1, d);
            make_frame(&b, mm, c2, d2);
            rx(&b, msg_id(mm), d2, 8U, b.t_us);
            rx(&b, msg_id(mm), d, 8U, b.t_us);
            b.counter[mm] = c2;
            break;
        }
        }
    }
    return 0;
}
