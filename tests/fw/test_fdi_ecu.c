/*
 * test_fdi_ecu.c - the ECU core on synthetic CAN traffic of the reference vehicle (fdi_test_util.h):
 * arguments, the E2E CRC against the CRC8 SAE-J1850 check value, every reject reason (counted, ignored),
 * the alive counter wrap, timeouts -> "not evaluable", step scheduling (strict boundaries, catch-up limit,
 * time wrap-around, independence of the poll pattern), the time alignment of a step's signals, and the
 * diagnosis frame (E2E, counter, fields) for a fault-free drive and a drifting vx sensor (f4), on the ROMO bus
 * generated from dbc/romo.dbc; the bus description checks (fdi_ecu_bus_check).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "fdi_ecu.h"
#include "fdi_kin_table.h"
#include "fdi_romo_bus.h"
#include "fdi_romo_ecu.h"
#include "fdi_romo_kin.h"
#include "fdi_test_vehicle.h"

#define ID_MD 80U
#define ID_IMU 128U
#define ID_VEL 136U
#define ID_WR1 256U
#define ID_BBW 272U
#define DID_IMU 4224U
#define DID_VEL 4232U
#define DID_DIAG 4608U
#define MSG_IMU 1 /* index of IMU_Motion in fdi_romo_bus.msgs (messages in ID order) */
#define MSG_VEL 2

/* ------------------------------------------------------------------------------------------ frames */

static void put_i16(uint8_t *d, double v, double scale)
{
    double r = floor(v / scale + 0.5);
    int32_t raw;
    if (r > 32767.0)
    {
        r = 32767.0;
    }
    if (r < -32768.0)
    {
        r = -32768.0;
    }
    raw = (int32_t)r;
    d[0] = (uint8_t)((uint32_t)raw & 0xFFU);
    d[1] = (uint8_t)(((uint32_t)raw >> 8) & 0xFFU);
}

static void protect(uint8_t *d, uint16_t data_id, uint8_t counter, uint8_t status)
{
    d[1] = (uint8_t)((uint8_t)(status << 4) | (counter & 0x0FU));
    d[0] = fdi_ecu_e2e_crc(data_id, d, 8U);
}

static void imu_frame(uint8_t *d, const fdi_frame_t *in, uint8_t counter, uint8_t status)
{
    memset(d, 0, 8);
    put_i16(&d[2], (double)in->value[ROMO_SIG_AX_M], 0.001);
    put_i16(&d[4], (double)in->value[ROMO_SIG_AY_M], 0.001);
    put_i16(&d[6], (double)in->value[ROMO_SIG_PSIDOT_M], 0.0001);
    protect(d, DID_IMU, counter, status);
}

static void vel_frame(uint8_t *d, const fdi_frame_t *in, uint8_t counter)
{
    memset(d, 0, 8);
    put_i16(&d[2], (double)in->value[ROMO_SIG_VX_M], 0.001);
    put_i16(&d[4], (double)in->value[ROMO_SIG_VY_M], 0.001);
    protect(d, DID_VEL, counter, 0U);
}

/* Synthetic bus: IMU every 5 ms at offset 0, VEL every 10 ms at offset 1 ms (as in dbc/romo.dbc). */
typedef struct
{
    veh_meas_cfg_t mc;
    test_rng_t rng;
    uint8_t c_imu;
    uint8_t c_vel;
    uint32_t t0_us; /* bus time 0 */
    double f4_rate; /* m/s per s from f4_t */
    double f4_t;
    bool vel_silent;
    bool poll_each_frame;
    uint32_t n_tx;
    uint32_t last_tx_counter;
    uint8_t last_tx[8];
} bus_t;

static void bus_init(bus_t *b, uint32_t t0_us)
{
    int i;
    memset(b, 0, sizeof *b);
    for (i = 0; i < 5; ++i)
    {
        b->mc.noise[i] = (i == 2) ? 0.001 : ((i < 2) ? 0.02 : 0.01);
    }
    b->rng.s = 7U;
    b->t0_us = t0_us;
    b->f4_t = 1.0e9;
    b->poll_each_frame = true;
    b->last_tx_counter = 0xFFU;
}

static void bus_poll(fdi_ecu_t *e, bus_t *b, uint32_t t)
{
    fdi_ecu_tx_t tx;
    assert_int_equal(fdi_ecu_poll(e, t, &tx), FDI_OK);
    if (tx.n_frames == 1U)
    {
        const uint8_t c = (uint8_t)(tx.frame[0].data[1] & 0x0FU);
        assert_int_equal(tx.frame[0].can_id, 512U);
        assert_int_equal(tx.frame[0].dlc, 8U);
        assert_int_equal(tx.frame[0].data[0], fdi_ecu_e2e_crc(DID_DIAG, tx.frame[0].data, 8U));
        if (b->last_tx_counter != 0xFFU)
        {
            assert_int_equal(c, (b->last_tx_counter + 1U) % 15U);
        }
        b->last_tx_counter = c;
        memcpy(b->last_tx, tx.frame[0].data, 8);
        b->n_tx++;
    }
}

/* Run the bus from ms k0 to k1 (exclusive), in 1 ms ticks. */
static void bus_run(fdi_ecu_t *e, bus_t *b, uint32_t k0, uint32_t k1)
{
    uint32_t k;
    for (k = k0; k < k1; ++k)
    {
        const uint32_t t = b->t0_us + k * 1000U;
        const double ts = (double)k * 1e-3;
        fdi_frame_t in;
        uint8_t d[8];
        b->mc.f[3] = (ts > b->f4_t) ? b->f4_rate * (ts - b->f4_t) : 0.0;
        veh_measure(ts, &b->mc, &b->rng, &in);
        if ((k % 5U) == 0U)
        {
            imu_frame(d, &in, b->c_imu, 0U);
            b->c_imu = (uint8_t)((b->c_imu + 1U) % 15U);
            assert_int_equal(fdi_ecu_rx(e, ID_IMU, 8U, d, t), FDI_OK);
            if (b->poll_each_frame)
            {
                bus_poll(e, b, t);
            }
        }
        if (((k % 10U) == 1U) && !b->vel_silent)
        {
            vel_frame(d, &in, b->c_vel);
            b->c_vel = (uint8_t)((b->c_vel + 1U) % 15U);
            assert_int_equal(fdi_ecu_rx(e, ID_VEL, 8U, d, t), FDI_OK);
            if (b->poll_each_frame)
            {
                bus_poll(e, b, t);
            }
        }
    }
}

static fdi_ecu_config_t kin_config(void)
{
    fdi_ecu_config_t c;
    assert_int_equal(fdi_romo_ecu_config_default(&c, &fdi_kin_table), FDI_OK);
    c.diag.gen_param[FDI_ROMO_KIN_PARAM_D_X] = (float)VEH_DX;
    c.diag.gen_param[FDI_ROMO_KIN_PARAM_D_Y] = (float)VEH_DY;
    return c;
}

/* Fields of an FDI_Diagnosis frame (little-endian bit layout of dbc/romo.dbc). */
typedef struct
{
    uint32_t status;
    uint32_t alarm;
    uint32_t candidates;
    uint32_t iso_class;
} diag_frame_t;

static diag_frame_t parse_diag(const uint8_t *d)
{
    uint64_t v = 0U;
    diag_frame_t f;
    int i;
    for (i = 7; i >= 0; --i)
    {
        v = (v << 8) | (uint64_t)d[i];
    }
    f.status = (uint32_t)((v >> 12) & 0xFU);
    f.alarm = (uint32_t)((v >> 16) & 0xFFFU);
    f.candidates = (uint32_t)((v >> 28) & 0x1FFFFFFU);
    f.iso_class = (uint32_t)((v >> 53) & 0xFFU);
    return f;
}

/* ------------------------------------------------------------------------------------------ tests */

static void test_bad_args(void **state)
{
    fdi_ecu_t e;
    fdi_ecu_config_t c = kin_config();
    fdi_ecu_tx_t tx;
    fdi_ecu_counters_t cnt;
    fdi_ecu_result_t res;
    uint8_t d[8] = {0};
    (void)state;
    fdi_ecu_bus_t bus = fdi_romo_bus;
    fdi_ecu_msg_desc_t msgs[FDI_ECU_MAX_MSGS];
    uint32_t i;
    assert_int_equal(fdi_ecu_config_default(NULL, &fdi_kin_table, &fdi_romo_bus), FDI_BAD_ARG);
    assert_int_equal(fdi_ecu_config_default(&c, NULL, &fdi_romo_bus), FDI_BAD_ARG);
    assert_int_equal(fdi_ecu_config_default(&c, &fdi_kin_table, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_romo_ecu_config_default(NULL, &fdi_kin_table), FDI_BAD_ARG);
    /* bus descriptions the core refuses */
    assert_int_equal(fdi_ecu_bus_check(&fdi_romo_bus, &fdi_kin_table), FDI_OK);
    assert_int_equal(fdi_ecu_bus_check(NULL, &fdi_kin_table), FDI_BAD_ARG);
    assert_int_equal(fdi_ecu_bus_check(&fdi_romo_bus, NULL), FDI_BAD_ARG);
    for (i = 0U; i < (uint32_t)fdi_romo_bus.n_msgs; ++i)
    {
        msgs[i] = fdi_romo_bus.msgs[i];
    }
    bus.msgs = msgs;
    assert_int_equal(fdi_ecu_bus_check(&bus, &fdi_kin_table), FDI_OK);
    msgs[2].can_id = msgs[1].can_id; /* an ID twice */
    assert_int_equal(fdi_ecu_bus_check(&bus, &fdi_kin_table), FDI_BAD_ARG);
    msgs[2] = fdi_romo_bus.msgs[2];
    msgs[2].signals |= ROMO_SIGM_OMEGA1_M; /* mask != indices */
    assert_int_equal(fdi_ecu_bus_check(&bus, &fdi_kin_table), FDI_BAD_ARG);
    msgs[2] = fdi_romo_bus.msgs[2];
    msgs[2].decode = NULL;
    assert_int_equal(fdi_ecu_bus_check(&bus, &fdi_kin_table), FDI_BAD_ARG);
    msgs[2] = fdi_romo_bus.msgs[2];
    msgs[2].dlc = 9U;
    assert_int_equal(fdi_ecu_bus_check(&bus, &fdi_kin_table), FDI_BAD_ARG);
    msgs[2] = fdi_romo_bus.msgs[2];
    msgs[2].can_id = fdi_romo_bus.diag_id; /* the diagnosis frame as an input */
    assert_int_equal(fdi_ecu_bus_check(&bus, &fdi_kin_table), FDI_BAD_ARG);
    msgs[2] = fdi_romo_bus.msgs[2];
    bus.encode_diag = NULL;
    assert_int_equal(fdi_ecu_bus_check(&bus, &fdi_kin_table), FDI_BAD_ARG);
    bus.encode_diag = fdi_romo_bus.encode_diag;
    bus.n_msgs = (uint8_t)(FDI_ECU_MAX_MSGS + 1U);
    assert_int_equal(fdi_ecu_bus_check(&bus, &fdi_kin_table), FDI_BAD_ARG);
    assert_int_equal(fdi_ecu_config_default(&c, &fdi_kin_table, &bus), FDI_BAD_ARG);
    bus.n_msgs = fdi_romo_bus.n_msgs;
    c = kin_config();
    c.bus = NULL;
    assert_int_equal(fdi_ecu_init(&e, &c), FDI_BAD_ARG);
    c = kin_config();
    assert_int_equal(fdi_ecu_init(NULL, &c), FDI_BAD_ARG);
    assert_int_equal(fdi_ecu_init(&e, NULL), FDI_BAD_ARG);
    c.timeout_us[3] = 0U;
    assert_int_equal(fdi_ecu_init(&e, &c), FDI_BAD_ARG);
    c = kin_config();
    c.max_delta_counter = 0U;
    assert_int_equal(fdi_ecu_init(&e, &c), FDI_BAD_ARG);
    c.max_delta_counter = 15U;
    assert_int_equal(fdi_ecu_init(&e, &c), FDI_BAD_ARG);
    c = kin_config();
    c.max_catchup_steps = 0U;
    assert_int_equal(fdi_ecu_init(&e, &c), FDI_BAD_ARG);
    c = kin_config();
    c.diag.warmup_steps = 10U; /* shorter than the settling time: fdi_diag_init refuses */
    assert_int_equal(fdi_ecu_init(&e, &c), FDI_BAD_ARG);
    /* a failed init leaves an instance every call refuses */
    assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 8U, d, 0U), FDI_BAD_ARG);
    assert_int_equal(fdi_ecu_poll(&e, 0U, &tx), FDI_BAD_ARG);
    assert_int_equal(tx.n_frames, 0U);
    assert_int_equal(fdi_ecu_counters(&e, &cnt), FDI_BAD_ARG);
    assert_int_equal(fdi_ecu_result(&e, &res), FDI_BAD_ARG);
    c = kin_config();
    assert_int_equal(fdi_ecu_init(&e, &c), FDI_OK);
    assert_int_equal(fdi_ecu_rx(NULL, ID_IMU, 8U, d, 0U), FDI_BAD_ARG);
    assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 8U, NULL, 0U), FDI_BAD_ARG);
    assert_int_equal(fdi_ecu_poll(&e, 0U, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_ecu_counters(&e, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_ecu_result(&e, NULL), FDI_BAD_ARG);
    assert_int_equal(fdi_ecu_counters(&e, &cnt), FDI_OK);
    assert_int_equal(cnt.frames, 0U); /* rejected calls counted nothing */
    /* an empty frame with NULL data is a frame with a bad DLC, not an error */
    assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 0U, NULL, 0U), FDI_OK);
    assert_int_equal(fdi_ecu_counters(&e, &cnt), FDI_OK);
    assert_int_equal(cnt.rejected[FDI_ECU_REJ_BAD_DLC], 1U);
    assert_int_equal(fdi_ecu_e2e_crc(1U, NULL, 8U), 0U);
    assert_int_equal(fdi_ecu_e2e_crc(1U, d, 1U), 0U);
}

/* CRC8 SAE-J1850 check value: CRC("123456789") = 0x4B; the data ID supplies "12", bytes 1..7 "3456789". */
static void test_e2e_crc_check_value(void **state)
{
    const uint8_t d[8] = {0x00U, '3', '4', '5', '6', '7', '8', '9'};
    (void)state;
    assert_int_equal(fdi_ecu_e2e_crc((uint16_t)('1' | ('2' << 8)), d, 8U), 0x4BU);
    assert_int_equal(fdi_ecu_msg_index(&fdi_romo_bus, ID_IMU), 1);
    assert_int_equal(fdi_ecu_msg_index(&fdi_romo_bus, ID_BBW), 7);
    assert_int_equal(fdi_ecu_msg_index(&fdi_romo_bus, 512U), -1);
    assert_int_equal(fdi_ecu_msg_index(&fdi_romo_bus, 0x80000080U), -1); /* extended-frame flag */
    assert_int_equal(fdi_ecu_msg_index(NULL, ID_IMU), -1);
}

static void expect_rejects(const fdi_ecu_t *e, const uint32_t *want)
{
    fdi_ecu_counters_t c;
    uint32_t r;
    assert_int_equal(fdi_ecu_counters(e, &c), FDI_OK);
    for (r = 0U; r < FDI_ECU_N_REASONS; ++r)
    {
        if (c.rejected[r] != want[r])
        {
            print_error("reason %u: %u rejected, expected %u\n", r, c.rejected[r], want[r]);
        }
        assert_int_equal(c.rejected[r], want[r]);
    }
}

/* Each reject reason once, in order; a frame is rejected for the first failing check only. */
static void test_reject_reasons(void **state)
{
    fdi_ecu_t e;
    const fdi_ecu_config_t c = kin_config();
    fdi_frame_t in;
    uint8_t d[8];
    uint32_t want[FDI_ECU_N_REASONS] = {0U};
    fdi_ecu_counters_t cnt;
    fdi_ecu_result_t res;
    veh_meas_cfg_t mc;
    test_rng_t rng = {1U};
    (void)state;
    memset(&mc, 0, sizeof mc);
    veh_measure(0.0, &mc, &rng, &in);
    assert_int_equal(fdi_ecu_init(&e, &c), FDI_OK);

    imu_frame(d, &in, 3U, 0U);
    assert_int_equal(fdi_ecu_rx(&e, 0x7FFU, 8U, d, 100U), FDI_OK);
    want[FDI_ECU_REJ_UNKNOWN_ID]++;
    assert_int_equal(fdi_ecu_rx(&e, 0x80000000U | ID_IMU, 8U, d, 100U), FDI_OK); /* extended flag */
    want[FDI_ECU_REJ_UNKNOWN_ID]++;
    assert_int_equal(fdi_ecu_rx(&e, 512U, 8U, d, 100U), FDI_OK);
    want[FDI_ECU_REJ_OWN_FRAME]++;
    assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 7U, d, 100U), FDI_OK);
    want[FDI_ECU_REJ_BAD_DLC]++;
    assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 64U, d, 100U), FDI_OK); /* CAN FD length: data not read */
    want[FDI_ECU_REJ_BAD_DLC]++;
    d[5] ^= 0x10U;
    assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 8U, d, 100U), FDI_OK);
    want[FDI_ECU_REJ_BAD_CRC]++;
    assert_int_equal(fdi_ecu_rx(&e, ID_VEL, 8U, d, 100U), FDI_OK); /* right CRC for IMU, wrong data ID */
    want[FDI_ECU_REJ_BAD_CRC]++;
    imu_frame(d, &in, 15U, 0U); /* counter 15 is outside 0..14 */
    assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 8U, d, 100U), FDI_OK);
    want[FDI_ECU_REJ_OUT_OF_RANGE]++;
    expect_rejects(&e, want);

    imu_frame(d, &in, 3U, 0U);
    assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 8U, d, 200U), FDI_OK); /* first valid frame: accepted */
    assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 8U, d, 300U), FDI_OK);
    want[FDI_ECU_REJ_REPEATED_COUNTER]++;
    imu_frame(d, &in, 5U, 0U);
    assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 8U, d, 400U), FDI_OK);
    want[FDI_ECU_REJ_COUNTER_JUMP]++;
    imu_frame(d, &in, 6U, 0U); /* re-synchronised on the jump: accepted */
    assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 8U, d, 500U), FDI_OK);
    imu_frame(d, &in, 7U, 1U); /* DEGRADED: still usable */
    assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 8U, d, 600U), FDI_OK);
    imu_frame(d, &in, 8U, 2U); /* LOCAL_FAULT: rejected, signals invalid at once */
    assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 8U, d, 700U), FDI_OK);
    want[FDI_ECU_REJ_SENSOR_STATUS]++;
    expect_rejects(&e, want);

    assert_int_equal(fdi_ecu_counters(&e, &cnt), FDI_OK);
    assert_int_equal(cnt.frames, 14U);
    assert_int_equal(cnt.msg[MSG_IMU].can_id, ID_IMU);
    assert_int_equal(cnt.msg[MSG_IMU].received, 10U);
    assert_int_equal(cnt.msg[MSG_IMU].accepted, 3U);
    assert_int_equal(cnt.msg[MSG_IMU].rejected[FDI_ECU_REJ_BAD_CRC], 1U);
    assert_int_equal(cnt.msg[MSG_VEL].rejected[FDI_ECU_REJ_BAD_CRC], 1U);
    assert_int_equal(cnt.msg[MSG_IMU].rejected[FDI_ECU_REJ_UNKNOWN_ID], 0U);

    /* the IMU's LOCAL_FAULT status makes its signals invalid at the next step, before any timeout */
    {
        fdi_ecu_tx_t tx;
        assert_int_equal(fdi_ecu_poll(&e, 100U + 10001U, &tx), FDI_OK);
        assert_int_equal(fdi_ecu_result(&e, &res), FDI_OK);
        assert_int_equal(res.step, 1U);
        assert_int_equal(res.validity & (ROMO_SIGM_AX_M | ROMO_SIGM_AY_M | ROMO_SIGM_PSIDOT_M), 0U);
        assert_int_equal(res.status, FDI_ECU_STATUS_INPUT_INVALID);
    }
}

/* The alive counter wraps 14 -> 0; with max_delta_counter 2 one lost frame is tolerated; a restarted sender
   costs one frame. */
static void test_counter_wrap_and_delta(void **state)
{
    fdi_ecu_t e;
    fdi_ecu_config_t c = kin_config();
    fdi_frame_t in;
    uint8_t d[8];
    uint32_t k;
    fdi_ecu_counters_t cnt;
    veh_meas_cfg_t mc;
    test_rng_t rng = {1U};
    (void)state;
    memset(&mc, 0, sizeof mc);
    veh_measure(0.0, &mc, &rng, &in);
    c.max_delta_counter = 2U;
    assert_int_equal(fdi_ecu_init(&e, &c), FDI_OK);
    for (k = 0U; k < 40U; ++k)
    {
        imu_frame(d, &in, (uint8_t)((k + 10U) % 15U), 0U);
        if (k != 20U) /* frame 20 lost: counter advances by 2, allowed */
        {
            assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 8U, d, k * 5000U), FDI_OK);
        }
    }
    imu_frame(d, &in, (uint8_t)((40U + 10U + 2U) % 15U), 0U); /* 3 ahead: a jump even with delta 2 */
    assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 8U, d, 40U * 5000U), FDI_OK);
    assert_int_equal(fdi_ecu_counters(&e, &cnt), FDI_OK);
    assert_int_equal(cnt.msg[MSG_IMU].accepted, 39U);
    assert_int_equal(cnt.rejected[FDI_ECU_REJ_COUNTER_JUMP], 1U);
    assert_int_equal(cnt.rejected[FDI_ECU_REJ_REPEATED_COUNTER], 0U);
    /* the sender restarts: silent for longer than the IMU timeout (15 ms), then its counter starts anywhere:
       the first frame is a jump and the new reference, the next one in sequence is accepted */
    imu_frame(d, &in, 3U, 0U);
    assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 8U, d, 40U * 5000U + 15001U), FDI_OK);
    imu_frame(d, &in, 4U, 0U);
    assert_int_equal(fdi_ecu_rx(&e, ID_IMU, 8U, d, 40U * 5000U + 20001U), FDI_OK);
    assert_int_equal(fdi_ecu_counters(&e, &cnt), FDI_OK);
    assert_int_equal(cnt.msg[MSG_IMU].accepted, 40U);
    assert_int_equal(cnt.rejected[FDI_ECU_REJ_COUNTER_JUMP], 2U);
}

/* Steps at t_first + k * 10 ms, run by the first call with t > T_k; one frame per poll; catch-up limit. */
static void scheduling(uint32_t t0)
{
    fdi_ecu_t e;
    fdi_ecu_config_t c = kin_config();
    fdi_ecu_tx_t tx;
    fdi_ecu_result_t res;
    fdi_ecu_counters_t cnt;
    c.max_catchup_steps = 50U;
    assert_int_equal(fdi_ecu_init(&e, &c), FDI_OK);
    assert_int_equal(fdi_ecu_poll(&e, t0, &tx), FDI_OK); /* starts the clock */
    assert_int_equal(tx.n_frames, 0U);
    assert_int_equal(fdi_ecu_poll(&e, t0 + 10000U, &tx), FDI_OK); /* T_1 = t0 + 10 ms: not yet (strict) */
    assert_int_equal(tx.n_frames, 0U);
    assert_int_equal(fdi_ecu_poll(&e, t0 + 10001U, &tx), FDI_OK);
    assert_int_equal(tx.n_frames, 1U);
    assert_int_equal(fdi_ecu_result(&e, &res), FDI_OK);
    assert_int_equal(res.step, 1U);
    assert_int_equal(res.t_us, t0 + 10000U);
    assert_int_equal(fdi_ecu_poll(&e, t0 + 10002U, &tx), FDI_OK); /* nothing new */
    assert_int_equal(tx.n_frames, 0U);
    assert_int_equal(fdi_ecu_poll(&e, t0 + 50001U, &tx), FDI_OK); /* 4 steps due, one frame (the newest) */
    assert_int_equal(tx.n_frames, 1U);
    assert_int_equal(fdi_ecu_result(&e, &res), FDI_OK);
    assert_int_equal(res.step, 5U);
    assert_int_equal(res.t_us, t0 + 50000U);
    assert_int_equal(fdi_ecu_poll(&e, t0 + 40000U, &tx), FDI_OK); /* time going back: nothing */
    assert_int_equal(tx.n_frames, 0U);
    /* a 2 s stall: 50 steps run, the other 150 skipped, schedule restarts at the stall's end */
    assert_int_equal(fdi_ecu_poll(&e, t0 + 2050001U, &tx), FDI_OK);
    assert_int_equal(fdi_ecu_counters(&e, &cnt), FDI_OK);
    assert_int_equal(cnt.steps, 55U);
    assert_int_equal(cnt.steps_skipped, 150U);
    assert_int_equal(cnt.tx_frames, 3U);
    assert_int_equal(fdi_ecu_poll(&e, t0 + 2060001U, &tx), FDI_OK);
    assert_int_equal(tx.n_frames, 0U);
    assert_int_equal(fdi_ecu_poll(&e, t0 + 2060002U, &tx), FDI_OK);
    assert_int_equal(tx.n_frames, 1U);
    assert_int_equal(fdi_ecu_result(&e, &res), FDI_OK);
    assert_int_equal(res.t_us, t0 + 2060001U);
    /* a stall ending exactly on a boundary (t = T_k is not due): 50 run, 10 skipped, not 11 */
    assert_int_equal(fdi_ecu_poll(&e, t0 + 2670001U, &tx), FDI_OK);
    assert_int_equal(fdi_ecu_counters(&e, &cnt), FDI_OK);
    assert_int_equal(cnt.steps, 106U);
    assert_int_equal(cnt.steps_skipped, 160U);
}

static void test_scheduling(void **state)
{
    (void)state;
    scheduling(1000U);
    scheduling(0xFFFFFF00U); /* the microsecond clock wraps during the test */
}

/* Fault-free drive: no detection ever, NO_FAULT after warm-up; the frame matches the result. */
static void test_fault_free_drive(void **state)
{
    fdi_ecu_t e;
    const fdi_ecu_config_t c = kin_config();
    bus_t b;
    fdi_ecu_result_t res;
    fdi_ecu_counters_t cnt;
    diag_frame_t f;
    uint32_t k;
    (void)state;
    bus_init(&b, 0xFFF00000U); /* wraps after ~1 s */
    assert_int_equal(fdi_ecu_init(&e, &c), FDI_OK);
    for (k = 0U; k < 60U; ++k)
    {
        bus_run(&e, &b, k * 1000U, (k + 1U) * 1000U);
        assert_int_equal(fdi_ecu_result(&e, &res), FDI_OK);
        assert_false(res.diag.iso.detected);
        f = parse_diag(b.last_tx);
        assert_int_equal(f.status, res.status);
        assert_int_equal(f.alarm, 0U);
        assert_int_equal(f.candidates, 0U);
        assert_int_equal(f.iso_class, 0U);
        if (k < 3U)
        {
            assert_int_equal(res.status, FDI_ECU_STATUS_INIT); /* warming up (3.2 s) */
        }
        if (k > 4U)
        {
            assert_int_equal(res.status, FDI_ECU_STATUS_NO_FAULT);
            assert_int_equal(res.diag.evaluable_mask, 0xFU);
        }
    }
    assert_int_equal(fdi_ecu_counters(&e, &cnt), FDI_OK);
    assert_int_equal(cnt.steps, 5999U); /* the last boundary (60 s) is not crossed yet */
    assert_int_equal(cnt.tx_frames, cnt.steps);
    assert_int_equal(b.n_tx, cnt.steps);
    assert_int_equal(cnt.msg[MSG_IMU].accepted, 12000U);
    assert_int_equal(cnt.msg[MSG_VEL].accepted, 6000U);
    assert_int_equal(cnt.msg[MSG_VEL].timeouts, 0U);
}

/* VelocitySensor silent for 1 s: after its 30 ms timeout every kinematic test is not evaluable. */
static void test_timeout_not_evaluable(void **state)
{
    fdi_ecu_t e;
    const fdi_ecu_config_t c = kin_config();
    bus_t b;
    fdi_ecu_result_t res;
    fdi_ecu_counters_t cnt;
    (void)state;
    bus_init(&b, 5000U);
    assert_int_equal(fdi_ecu_init(&e, &c), FDI_OK);
    bus_run(&e, &b, 0U, 5000U);
    assert_int_equal(fdi_ecu_result(&e, &res), FDI_OK);
    assert_int_equal(res.diag.evaluable_mask, 0xFU);
    b.vel_silent = true; /* last VEL frame at 4.991 s */
    bus_run(&e, &b, 5000U, 5026U); /* only IMU frames now: the step at 5.02 s runs with the frame at 5.025 s */
    assert_int_equal(fdi_ecu_result(&e, &res), FDI_OK);
    assert_int_equal(res.t_us, 5000U + 5020000U); /* step at 5.02 s: 29 ms old, fresh */
    assert_int_equal(res.diag.evaluable_mask, 0xFU);
    bus_run(&e, &b, 5026U, 5036U);
    assert_int_equal(fdi_ecu_result(&e, &res), FDI_OK);
    assert_int_equal(res.t_us, 5000U + 5030000U); /* 39 ms old: timed out */
    assert_int_equal(res.diag.evaluable_mask, 0U);
    assert_int_equal(res.validity & (ROMO_SIGM_VX_M | ROMO_SIGM_VY_M), 0U);
    assert_int_equal(res.status, FDI_ECU_STATUS_INPUT_INVALID);
    assert_int_equal(parse_diag(b.last_tx).status, FDI_ECU_STATUS_INPUT_INVALID);
    bus_run(&e, &b, 5036U, 6000U);
    b.vel_silent = false;
    bus_run(&e, &b, 6000U, 7000U); /* back, warming up */
    assert_int_equal(fdi_ecu_result(&e, &res), FDI_OK);
    assert_int_equal(res.diag.evaluable_mask, 0U);
    assert_int_equal(res.status, FDI_ECU_STATUS_INIT);
    bus_run(&e, &b, 7000U, 10000U);
    assert_int_equal(fdi_ecu_result(&e, &res), FDI_OK);
    assert_int_equal(res.diag.evaluable_mask, 0xFU);
    assert_false(res.diag.iso.detected);
    assert_int_equal(fdi_ecu_counters(&e, &cnt), FDI_OK);
    assert_int_equal(cnt.msg[MSG_VEL].timeouts, 1U);
    assert_int_equal(cnt.msg[MSG_IMU].timeouts, 0U);
}

/* One ms tick of a ramp bus: IMU (5 ms, offset 0) with a_x = 0.2 m/s^2 per s, VEL (10 ms, offset 1 ms) with
   v_x = 1 m/s per s (both exact in the DBC's quantisation), VEL silent while `vel_silent`; polled after each frame. */
static void ramp_tick(fdi_ecu_t *e, uint32_t t0, uint32_t k, uint8_t *c_imu, uint8_t *c_vel, bool vel_silent)
{
    fdi_frame_t in;
    fdi_ecu_tx_t tx;
    uint8_t d[8];
    memset(&in, 0, sizeof in);
    in.value[ROMO_SIG_AX_M] = 2.0e-4f * (float)k;
    in.value[ROMO_SIG_VX_M] = 1.0e-3f * (float)k;
    if ((k % 5U) == 0U)
    {
        imu_frame(d, &in, *c_imu, 0U);
        *c_imu = (uint8_t)((*c_imu + 1U) % 15U);
        assert_int_equal(fdi_ecu_rx(e, ID_IMU, 8U, d, t0 + (k * 1000U)), FDI_OK);
        assert_int_equal(fdi_ecu_poll(e, t0 + (k * 1000U), &tx), FDI_OK);
    }
    if (((k % 10U) == 1U) && !vel_silent)
    {
        vel_frame(d, &in, *c_vel);
        *c_vel = (uint8_t)((*c_vel + 1U) % 15U);
        assert_int_equal(fdi_ecu_rx(e, ID_VEL, 8U, d, t0 + (k * 1000U)), FDI_OK);
        assert_int_equal(fdi_ecu_poll(e, t0 + (k * 1000U), &tx), FDI_OK);
    }
}

/* The ramps at the ms instant s of the bus (before its first frames: the first frame's values). */
static float ramp_ax(double s_ms)
{
    return (float)(2.0e-4 * ((s_ms > 0.0) ? s_ms : 0.0));
}

static float ramp_vx(double s_ms)
{
    return (float)(1.0e-3 * ((s_ms > 1.0) ? s_ms : 1.0));
}

/* Time alignment: a step's signals are those of the instant T_k - align_us, linear between the two frames of
   each message around it (fdi_ecu_align_us: the longest cycle of the ROMO bus's signal messages, 20 ms);
   align 0, the default, holds each message's last frame; every kept frame after the instant: the oldest; frames around the
   instant farther apart than the timeout (a silent sender): the newer one; an align beyond what a message's
   kept frames cover is refused. The microsecond clock wraps during the run. */
static void test_time_alignment(void **state)
{
    const uint32_t t0 = 0xFFFF0000U;
    fdi_ecu_t e;
    fdi_ecu_config_t c = kin_config();
    fdi_ecu_result_t res;
    uint32_t steps_seen = 0U;
    uint32_t pass;
    (void)state;
    assert_int_equal(c.align_us, 0U);
    assert_int_equal(fdi_ecu_align_us(&fdi_romo_bus), 20000U);
    assert_int_equal(fdi_ecu_align_us(NULL), 0U);
    for (pass = 0U; pass < 2U; ++pass)
    {
        uint8_t c_imu = 0U;
        uint8_t c_vel = 0U;
        uint32_t last_step = 0U;
        uint32_t k;
        c.align_us = (pass == 0U) ? fdi_ecu_align_us(&fdi_romo_bus) : 0U;
        assert_int_equal(fdi_ecu_init(&e, &c), FDI_OK);
        for (k = 0U; k < 1000U; ++k)
        {
            const bool silent = (k > 500U) && (k < 560U); /* VEL frames of 0.511 .. 0.551 s lost */
            ramp_tick(&e, t0, k, &c_imu, &c_vel, silent);
            assert_int_equal(fdi_ecu_result(&e, &res), FDI_OK);
            if (res.step != last_step)
            {
                const double T = (double)(res.t_us - t0) / 1000.0; /* ms of the bus */
                const double s_ms = T - ((double)c.align_us / 1000.0);
                double vx_ms; /* the instant whose v_x ramp value the step must hold */
                last_step = res.step;
                steps_seen++;
                assert_int_equal(res.t_us - t0, res.step * 10000U);
                if (pass == 0U)
                {
                    assert_float_equal(e.in.value[ROMO_SIG_AX_M], ramp_ax(s_ms), 2.0e-6f);
                    vx_ms = s_ms;
                    if ((s_ms > 491.0) && (s_ms < 561.0))
                    {
                        vx_ms = 561.0; /* the frames around s are 70 ms apart (timeout 30 ms): the newer */
                    }
                    if (T < 561.0 + 0.5)
                    {
                        vx_ms = ((s_ms > 491.0) && (s_ms < 561.0)) ? 491.0 : vx_ms; /* not received yet */
                    }
                }
                else
                {
                    const double imu_ms = floor(T / 5.0) * 5.0;
                    const double vel_ms = floor((T - 1.0) / 10.0) * 10.0 + 1.0;
                    assert_float_equal(e.in.value[ROMO_SIG_AX_M], ramp_ax(imu_ms), 2.0e-6f);
                    vx_ms = ((vel_ms > 491.0) && (vel_ms < 561.0)) ? 491.0 : vel_ms;
                }
                assert_float_equal(e.in.value[ROMO_SIG_VX_M], ramp_vx(vx_ms), 2.0e-5f);
            }
        }
    }
    assert_true(steps_seen > 190U);
    /* 6 kept frames of the 5 ms messages cover (6 - 2) x 5 ms behind the newest */
    c = kin_config();
    c.align_us = 20001U;
    assert_int_equal(fdi_ecu_init(&e, &c), FDI_BAD_ARG);
    c.align_us = 0xFFFFFFFFU;
    assert_int_equal(fdi_ecu_init(&e, &c), FDI_BAD_ARG);
}

/* f4 drifting 0.05 m/s per s from 30 s: isolated as f4 by 60 s; the frame carries class 4. Polling only on a
   25 ms timer gives the same results step by step. */
static void test_vx_drift_isolated(void **state)
{
    fdi_ecu_t e;
    fdi_ecu_t e2;
    const fdi_ecu_config_t c = kin_config();
    bus_t b;
    bus_t b2;
    fdi_ecu_result_t res;
    fdi_ecu_result_t res2;
    diag_frame_t f;
    uint32_t k;
    double first = -1.0;
    (void)state;
    bus_init(&b, 0U);
    bus_init(&b2, 0U);
    b.f4_rate = 0.05;
    b.f4_t = 30.0;
    b2.f4_rate = 0.05;
    b2.f4_t = 30.0;
    b2.poll_each_frame = false;
    assert_int_equal(fdi_ecu_init(&e, &c), FDI_OK);
    assert_int_equal(fdi_ecu_init(&e2, &c), FDI_OK);
    for (k = 0U; k < 2400U; ++k) /* 60 s in 25 ms slices */
    {
        bus_run(&e, &b, k * 25U, (k + 1U) * 25U);
        bus_run(&e2, &b2, k * 25U, (k + 1U) * 25U);
        bus_poll(&e2, &b2, (k + 1U) * 25000U - 999U); /* timer poll, 1 us after the last frame's ms */
        assert_int_equal(fdi_ecu_result(&e, &res), FDI_OK);
        assert_int_equal(fdi_ecu_result(&e2, &res2), FDI_OK);
        if (res2.step == res.step)
        {
            assert_int_equal(res2.diag.alarm_mask, res.diag.alarm_mask);
            assert_int_equal(res2.diag.iso.candidates, res.diag.iso.candidates);
            assert_memory_equal(res2.diag.residual, res.diag.residual, sizeof res.diag.residual);
        }
        if ((double)k * 0.025 < 30.0)
        {
            assert_false(res.diag.iso.detected);
        }
        else if (res.diag.iso.detected && (first < 0.0))
        {
            first = (double)k * 0.025 - 30.0;
        }
    }
    print_message("f4 drift detected %.3f s after onset\n", first);
    assert_true((first >= 0.0) && (first < 10.0));
    assert_int_equal(fdi_ecu_result(&e, &res), FDI_OK);
    assert_true(res.diag.iso.isolated);
    assert_int_equal(res.diag.iso.candidates, 0x08U);
    assert_int_equal(res.diag.alarm_mask, fdi_kin_table.fault_signature[3]);
    assert_int_equal(res.status, FDI_ECU_STATUS_FAULT_ISOLATED);
    assert_int_equal(res.iso_class, 4U);
    f = parse_diag(b.last_tx);
    assert_int_equal(f.status, FDI_ECU_STATUS_FAULT_ISOLATED);
    assert_int_equal(f.alarm, fdi_kin_table.fault_signature[3]);
    assert_int_equal(f.candidates, 0x08U);
    assert_int_equal(f.iso_class, 4U);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_args),          cmocka_unit_test(test_e2e_crc_check_value),
        cmocka_unit_test(test_reject_reasons),    cmocka_unit_test(test_counter_wrap_and_delta),
        cmocka_unit_test(test_scheduling),        cmocka_unit_test(test_fault_free_drive),
        cmocka_unit_test(test_timeout_not_evaluable), cmocka_unit_test(test_vx_drift_isolated),
        cmocka_unit_test(test_time_alignment),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
