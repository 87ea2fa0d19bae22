/* fdi_ecu.c - the ECU process core: frame checks, decoding, timeouts, fixed steps, diagnosis frame (fdi_ecu.h). */
#include "fdi_ecu.h"

#include <math.h>
#include <stddef.h>

#include "fdi_float.h"
#include "romo_can.h"
#include "romo_can_e2e.h"

#define E2E_COUNTER_MOD 15U /* profile 11 counter runs 0..14 */
#define STATUS_OK 0U
#define STATUS_DEGRADED 1U
#define BAR_TO_PA 1.0e5f
#define WARMUP_MARGIN_STEPS 20U
/* Isolation episodes (fdi_diag.h): a quiet test exonerates only after 3 s, the response window in which the
   analysis states the per-test fault sizes (fdi-tune fault-sizes: alarm within a 3 s step); an episode
   ends after 3 s without any alarm. */
#define ISO_SETTLE_STEPS 300U
#define EPISODE_CLEAR_STEPS 300U
#define TIMEOUT_CYCLES 3U
#define US_PER_MS 1000U

typedef struct
{
    fdi_ecu_msg_t msg;
    uint32_t can_id;
    uint16_t data_id;
    uint16_t cycle_ms;
    uint32_t signals; /* FDI_SIGM_* carried */
} msg_desc_t;

static const msg_desc_t msg_desc[FDI_ECU_N_MSGS] = {
    {FDI_ECU_MSG_MOTION_DEMAND, ROMO_CAN_MOTION_DEMAND_FRAME_ID,
     ROMO_CAN_E2E_MOTION_DEMAND_DATA_ID, ROMO_CAN_E2E_MOTION_DEMAND_CYCLE_MS, 0U},
    {FDI_ECU_MSG_IMU, ROMO_CAN_IMU_MOTION_FRAME_ID,
     ROMO_CAN_E2E_IMU_MOTION_DATA_ID, ROMO_CAN_E2E_IMU_MOTION_CYCLE_MS,
     FDI_SIGM_AX_M | FDI_SIGM_AY_M | FDI_SIGM_PSIDOT_M},
    {FDI_ECU_MSG_VEL, ROMO_CAN_VELOCITY_SENSOR_FRAME_ID,
     ROMO_CAN_E2E_VELOCITY_SENSOR_DATA_ID, ROMO_CAN_E2E_VELOCITY_SENSOR_CYCLE_MS,
     FDI_SIGM_VX_M | FDI_SIGM_VY_M},
    {FDI_ECU_MSG_WR1, ROMO_CAN_WHEEL_ROBOT1_FRAME_ID,
     ROMO_CAN_E2E_WHEEL_ROBOT1_DATA_ID, ROMO_CAN_E2E_WHEEL_ROBOT1_CYCLE_MS,
     FDI_SIGM_DELTA1_M | FDI_SIGM_ITM1_M | FDI_SIGM_OMEGA1_M},
    {FDI_ECU_MSG_WR2, ROMO_CAN_WHEEL_ROBOT2_FRAME_ID,
     ROMO_CAN_E2E_WHEEL_ROBOT2_DATA_ID, ROMO_CAN_E2E_WHEEL_ROBOT2_CYCLE_MS,
     FDI_SIGM_DELTA2_M | FDI_SIGM_ITM2_M | FDI_SIGM_OMEGA2_M},
    {FDI_ECU_MSG_WR3, ROMO_CAN_WHEEL_ROBOT3_FRAME_ID,
     ROMO_CAN_E2E_WHEEL_ROBOT3_DATA_ID, ROMO_CAN_E2E_WHEEL_ROBOT3_CYCLE_MS,
     FDI_SIGM_DELTA3_M | FDI_SIGM_ITM3_M | FDI_SIGM_OMEGA3_M},
    {FDI_ECU_MSG_WR4, ROMO_CAN_WHEEL_ROBOT4_FRAME_ID,
     ROMO_CAN_E2E_WHEEL_ROBOT4_DATA_ID, ROMO_CAN_E2E_WHEEL_ROBOT4_CYCLE_MS,
     FDI_SIGM_DELTA4_M | FDI_SIGM_ITM4_M | FDI_SIGM_OMEGA4_M},
    {FDI_ECU_MSG_BBW, ROMO_CAN_BRAKE_BY_WIRE_FRAME_ID,
     ROMO_CAN_E2E_BRAKE_BY_WIRE_DATA_ID, ROMO_CAN_E2E_BRAKE_BY_WIRE_CYCLE_MS,
     FDI_SIGM_P_F_M | FDI_SIGM_P_R_M},
};


uint8_t fdi_ecu_e2e_crc(uint16_t data_id, const uint8_t *data, uint8_t len)
{
    /* CRC8 SAE-J1850 table, polynomial 0x1D */
    static const uint8_t crc_table[256] = {
        0x00U, 0x1DU, 0x3AU, 0x27U, 0x74U, 0x69U, 0x4EU, 0x53U, 0xE8U, 0xF5U, 0xD2U, 0xCFU, 0x9CU, 0x81U, 0xA6U, 0xBBU,
        0xCDU, 0xD0U, 0xF7U, 0xEAU, 0xB9U, 0xA4U, 0x83U, 0x9EU, 0x25U, 0x38U, 0x1FU, 0x02U, 0x51U, 0x4CU, 0x6BU, 0x76U,
        0x87U, 0x9AU, 0xBDU, 0xA0U, 0xF3U, 0xEEU, 0xC9U, 0xD4U, 0x6FU, 0x72U, 0x55U, 0x48U, 0x1BU, 0x06U, 0x21U, 0x3CU,
        0x4AU, 0x57U, 0x70U, 0x6DU, 0x3EU, 0x23U, 0x04U, 0x19U, 0xA2U, 0xBFU, 0x98U, 0x85U, 0xD6U, 0xCBU, 0xECU, 0xF1U,
        0x13U, 0x0EU, 0x29U, 0x34U, 0x67U, 0x7AU, 0x5DU, 0x40U, 0xFBU, 0xE6U, 0xC1U, 0xDCU, 0x8FU, 0x92U, 0xB5U, 0xA8U,
        0xDEU, 0xC3U, 0xE4U, 0xF9U, 0xAAU, 0xB7U, 0x90U, 0x8DU, 0x36U, 0x2BU, 0x0CU, 0x11U, 0x42U, 0x5FU, 0x78U, 0x65U,
        0x94U, 0x89U, 0xAEU, 0xB3U, 0xE0U, 0xFDU, 0xDAU, 0xC7U, 0x7CU, 0x61U, 0x46U, 0x5BU, 0x08U, 0x15U, 0x32U, 0x2FU,
        0x59U, 0x44U, 0x63U, 0x7EU, 0x2DU, 0x30U, 0x17U, 0x0AU, 0xB1U, 0xACU, 0x8BU, 0x96U, 0xC5U, 0xD8U, 0xFFU, 0xE2U,
        0x26U, 0x3BU, 0x1CU, 0x01U, 0x52U, 0x4FU, 0x68U, 0x75U, 0xCEU, 0xD3U, 0xF4U, 0xE9U, 0xBAU, 0xA7U, 0x80U, 0x9DU,
        0xEBU, 0xF6U, 0xD1U, 0xCCU, 0x9FU, 0x82U, 0xA5U, 0xB8U, 0x03U, 0x1EU, 0x39U, 0x24U, 0x77U, 0x6AU, 0x4DU, 0x50U,
        0xA1U, 0xBCU, 0x9BU, 0x86U, 0xD5U, 0xC8U, 0xEFU, 0xF2U, 0x49U, 0x54U, 0x73U, 0x6EU, 0x3DU, 0x20U, 0x07U, 0x1AU,
        0x6CU, 0x71U, 0x56U, 0x4BU, 0x18U, 0x05U, 0x22U, 0x3FU, 0x84U, 0x99U, 0xBEU, 0xA3U, 0xF0U, 0xEDU, 0xCAU, 0xD7U,
        0x35U, 0x28U, 0x0FU, 0x12U, 0x41U, 0x5CU, 0x7BU, 0x66U, 0xDDU, 0xC0U, 0xE7U, 0xFAU, 0xA9U, 0xB4U, 0x93U, 0x8EU,
        0xF8U, 0xE5U, 0xC2U, 0xDFU, 0x8CU, 0x91U, 0xB6U, 0xABU, 0x10U, 0x0DU, 0x2AU, 0x37U, 0x64U, 0x79U, 0x5EU, 0x43U,
        0xB2U, 0xAFU, 0x88U, 0x95U, 0xC6U, 0xDBU, 0xFCU, 0xE1U, 0x5AU, 0x47U, 0x60U, 0x7DU, 0x2EU, 0x33U, 0x14U, 0x09U,
        0x7FU, 0x62U, 0x45U, 0x58U, 0x0BU, 0x16U, 0x31U, 0x2CU, 0x97U, 0x8AU, 0xADU, 0xB0U, 0xE3U, 0xFEU, 0xD9U, 0xC4U,
    };
    uint8_t crc = 0U;
    if ((data != NULL) && (len >= 2U))
    {
        uint8_t i;
        crc = 0xFFU;
        crc = crc_table[(uint8_t)(crc ^ (uint8_t)(data_id & 0xFFU))];
        crc = crc_table[(uint8_t)(crc ^ (uint8_t)(data_id >> 8U))];
        for (i = 1U; i < len; ++i)
        {
            crc = crc_table[(uint8_t)(crc ^ data[i])];
        }
        crc = (uint8_t)(crc ^ 0xFFU);
    }
    return crc;
}

static int32_t msg_index(uint32_t can_id)
{
    int32_t idx = -1;
    uint32_t i;
    for (i = 0U; i < FDI_ECU_N_MSGS; ++i)
    {
        if (msg_desc[i].can_id == can_id)
        {
            idx = (int32_t)i;
        }
    }
    return idx;
}

int32_t fdi_ecu_msg_index(uint32_t can_id)
{
    return msg_index(can_id);
}

/* Signed difference a - b of two wrapping microsecond times. */
static int32_t time_diff(uint32_t a, uint32_t b)
{
    const uint32_t d = a - b;
    int32_t out;
    if (d > 0x7FFFFFFFU)
    {
        const uint32_t neg = 0xFFFFFFFFU - d; /* 0 .. 0x7FFFFFFE */
        out = -1 - (int32_t)neg;
    }
    else
    {
        out = (int32_t)d;
    }
    return out;
}

static bool ready(const fdi_ecu_t *self)
{
    return (self != NULL) && (self->table != NULL);
}

/* ------------------------------------------------------------------------------------------ decoding */

typedef struct
{
    uint8_t counter;
    uint8_t status;
    bool in_range;
} frame_info_t;

/* Unpack message idx (dlc checked by the caller) into *in (only the message's signals) and *fi. */
static void decode(uint32_t idx, const uint8_t *data, fdi_inputs_t *in, frame_info_t *fi)
{
    switch (msg_desc[idx].msg)
    {
    case FDI_ECU_MSG_MOTION_DEMAND: {
        struct romo_can_motion_demand_t m;
        (void)romo_can_motion_demand_unpack(&m, data, FDI_ECU_FRAME_LEN);
        fi->counter = m.md_counter;
        fi->status = m.md_status;
        fi->in_range = romo_can_motion_demand_md_counter_is_in_range(m.md_counter) &&
                       romo_can_motion_demand_md_speed_is_in_range(m.md_speed) &&
                       romo_can_motion_demand_md_side_slip_is_in_range(m.md_side_slip) &&
                       romo_can_motion_demand_md_yaw_rate_is_in_range(m.md_yaw_rate);
        break;
    }
    case FDI_ECU_MSG_IMU: {
        struct romo_can_imu_motion_t m;
        (void)romo_can_imu_motion_unpack(&m, data, FDI_ECU_FRAME_LEN);
        fi->counter = m.imu_counter;
        fi->status = m.imu_status;
        fi->in_range = romo_can_imu_motion_imu_counter_is_in_range(m.imu_counter) &&
                       romo_can_imu_motion_imu_accel_x_is_in_range(m.imu_accel_x) &&
                       romo_can_imu_motion_imu_accel_y_is_in_range(m.imu_accel_y) &&
                       romo_can_imu_motion_imu_yaw_rate_is_in_range(m.imu_yaw_rate);
        in->ax_m = romo_can_imu_motion_imu_accel_x_decode(m.imu_accel_x);
        in->ay_m = romo_can_imu_motion_imu_accel_y_decode(m.imu_accel_y);
        in->psidot_m = romo_can_imu_motion_imu_yaw_rate_decode(m.imu_yaw_rate);
        break;
    }
    case FDI_ECU_MSG_VEL: {
        struct romo_can_velocity_sensor_t m;
        (void)romo_can_velocity_sensor_unpack(&m, data, FDI_ECU_FRAME_LEN);
        fi->counter = m.vel_counter;
        fi->status = m.vel_status;
        fi->in_range = romo_can_velocity_sensor_vel_counter_is_in_range(m.vel_counter) &&
                       romo_can_velocity_sensor_vel_vel_x_is_in_range(m.vel_vel_x) &&
                       romo_can_velocity_sensor_vel_vel_y_is_in_range(m.vel_vel_y);
        in->vx_m = romo_can_velocity_sensor_vel_vel_x_decode(m.vel_vel_x);
        in->vy_m = romo_can_velocity_sensor_vel_vel_y_decode(m.vel_vel_y);
        break;
    }
    case FDI_ECU_MSG_WR1: {
        struct romo_can_wheel_robot1_t m;
        (void)romo_can_wheel_robot1_unpack(&m, data, FDI_ECU_FRAME_LEN);
        fi->counter = m.wr1_counter;
        fi->status = m.wr1_status;
        fi->in_range = romo_can_wheel_robot1_wr1_counter_is_in_range(m.wr1_counter) &&
                       romo_can_wheel_robot1_wr1_steer_angle_is_in_range(m.wr1_steer_angle) &&
                       romo_can_wheel_robot1_wr1_motor_current_is_in_range(m.wr1_motor_current) &&
                       romo_can_wheel_robot1_wr1_wheel_speed_is_in_range(m.wr1_wheel_speed);
        in->delta1_m = romo_can_wheel_robot1_wr1_steer_angle_decode(m.wr1_steer_angle);
        in->iTM1_m = romo_can_wheel_robot1_wr1_motor_current_decode(m.wr1_motor_current);
        in->omega1_m = romo_can_wheel_robot1_wr1_wheel_speed_decode(m.wr1_wheel_speed);
        break;
    }
    case FDI_ECU_MSG_WR2: {
        struct romo_can_wheel_robot2_t m;
        (void)romo_can_wheel_robot2_unpack(&m, data, FDI_ECU_FRAME_LEN);
        fi->counter = m.wr2_counter;
        fi->status = m.wr2_status;
        fi->in_range = romo_can_wheel_robot2_wr2_counter_is_in_range(m.wr2_counter) &&
                       romo_can_wheel_robot2_wr2_steer_angle_is_in_range(m.wr2_steer_angle) &&
                       romo_can_wheel_robot2_wr2_motor_current_is_in_range(m.wr2_motor_current) &&
                       romo_can_wheel_robot2_wr2_wheel_speed_is_in_range(m.wr2_wheel_speed);
        in->delta2_m = romo_can_wheel_robot2_wr2_steer_angle_decode(m.wr2_steer_angle);
        in->iTM2_m = romo_can_wheel_robot2_wr2_motor_current_decode(m.wr2_motor_current);
        in->omega2_m = romo_can_wheel_robot2_wr2_wheel_speed_decode(m.wr2_wheel_speed);
        break;
    }
    case FDI_ECU_MSG_WR3: {
        struct romo_can_wheel_robot3_t m;
        (void)romo_can_wheel_robot3_unpack(&m, data, FDI_ECU_FRAME_LEN);
        fi->counter = m.wr3_counter;
        fi->status = m.wr3_status;
        fi->in_range = romo_can_wheel_robot3_wr3_counter_is_in_range(m.wr3_counter) &&
                       romo_can_wheel_robot3_wr3_steer_angle_is_in_range(m.wr3_steer_angle) &&
                       romo_can_wheel_robot3_wr3_motor_current_is_in_range(m.wr3_motor_current) &&
                       romo_can_wheel_robot3_wr3_wheel_speed_is_in_range(m.wr3_wheel_speed);
        in->delta3_m = romo_can_wheel_robot3_wr3_steer_angle_decode(m.wr3_steer_angle);
        in->iTM3_m = romo_can_wheel_robot3_wr3_motor_current_decode(m.wr3_motor_current);
        in->omega3_m = romo_can_wheel_robot3_wr3_wheel_speed_decode(m.wr3_wheel_speed);
        break;
    }
    case FDI_ECU_MSG_WR4: {
        struct romo_can_wheel_robot4_t m;
        (void)romo_can_wheel_robot4_unpack(&m, data, FDI_ECU_FRAME_LEN);
        fi->counter = m.wr4_counter;
        fi->status = m.wr4_status;
        fi->in_range = romo_can_wheel_robot4_wr4_counter_is_in_range(m.wr4_counter) &&
                       romo_can_wheel_robot4_wr4_steer_angle_is_in_range(m.wr4_steer_angle) &&
                       romo_can_wheel_robot4_wr4_motor_current_is_in_range(m.wr4_motor_current) &&
                       romo_can_wheel_robot4_wr4_wheel_speed_is_in_range(m.wr4_wheel_speed);
        in->delta4_m = romo_can_wheel_robot4_wr4_steer_angle_decode(m.wr4_steer_angle);
        in->iTM4_m = romo_can_wheel_robot4_wr4_motor_current_decode(m.wr4_motor_current);
        in->omega4_m = romo_can_wheel_robot4_wr4_wheel_speed_decode(m.wr4_wheel_speed);
        break;
    }
    default: { /* FDI_ECU_MSG_BBW, the last message */
        struct romo_can_brake_by_wire_t m;
        (void)romo_can_brake_by_wire_unpack(&m, data, FDI_ECU_FRAME_LEN);
        fi->counter = m.bbw_counter;
        fi->status = m.bbw_status;
        fi->in_range = romo_can_brake_by_wire_bbw_counter_is_in_range(m.bbw_counter) &&
                       romo_can_brake_by_wire_bbw_pressure_front_is_in_range(m.bbw_pressure_front) &&
                       romo_can_brake_by_wire_bbw_pressure_rear_is_in_range(m.bbw_pressure_rear);
        in->P_f_m = romo_can_brake_by_wire_bbw_pressure_front_decode(m.bbw_pressure_front) * BAR_TO_PA;
        in->P_r_m = romo_can_brake_by_wire_bbw_pressure_rear_decode(m.bbw_pressure_rear) * BAR_TO_PA;
        break;
    }
    }
}

/* ------------------------------------------------------------------------------------------ stepping */

static uint8_t iso_class_code(const fdi_table_t *t, const fdi_iso_result_t *iso)
{
    uint8_t code = 0U;
    if (iso->detected)
    {
        code = (uint8_t)FDI_ECU_CLASS_NOT_ISOLATED;
        if (iso->isolated && (iso->class_mask != 0U))
        {
            uint32_t j = 0U;
            while ((j < (uint32_t)t->n_faults) && ((iso->class_mask & ((uint32_t)1U << j)) == 0U))
            {
                ++j;
            }
            if (j < 254U)
            {
                code = (uint8_t)(j + 1U);
            }
        }
    }
    return code;
}

static fdi_ecu_status_t diag_status(const fdi_ecu_t *self, uint32_t validity)
{
    const fdi_diag_result_t *d = &self->res.diag;
    uint32_t inputs_ok = 0U;
    uint32_t i;
    fdi_ecu_status_t st;
    for (i = 0U; i < (uint32_t)self->table->n_tests; ++i)
    {
        const uint32_t need = self->table->tests[i].input_mask;
        if ((validity & need) == need)
        {
            inputs_ok |= (uint32_t)1U << i;
        }
    }
    if (d->iso.detected)
    {
        st = d->iso.isolated ? FDI_ECU_STATUS_FAULT_ISOLATED : FDI_ECU_STATUS_FAULT_DETECTED;
    }
    else if ((self->gen_mask & ~inputs_ok) != 0U)
    {
        st = FDI_ECU_STATUS_INPUT_INVALID;
    }
    else if ((self->gen_mask == 0U) || ((self->gen_mask & ~d->evaluable_mask) != 0U))
    {
        st = FDI_ECU_STATUS_INIT;
    }
    else
    {
        st = FDI_ECU_STATUS_NO_FAULT;
    }
    return st;
}

/* One diagnosis step at time t: timeouts, fdi_diag_step, result. */
static void run_step(fdi_ecu_t *self, uint32_t t)
{
    uint32_t validity = 0U;
    uint32_t i;
    for (i = 0U; i < FDI_ECU_N_MSGS; ++i)
    {
        fdi_ecu_msg_state_t *m = &self->msg[i];
        bool fresh = false;
        if (m->have && m->status_ok)
        {
            const int32_t age = time_diff(t, m->t_last_us);
            fresh = (age <= 0) || ((uint32_t)age <= self->timeout_us[i]);
        }
        if (m->fresh && !fresh && m->have && m->status_ok)
        {
            self->cnt.msg[i].timeouts++;
        }
        m->fresh = fresh;
        if (fresh)
        {
            validity |= msg_desc[i].signals;
        }
    }
    (void)fdi_diag_step(&self->diag, &self->in, validity); /* cannot fail: initialised instance, non-NULL */
    (void)fdi_diag_result(&self->diag, &self->res.diag);
    self->cnt.steps++;
    self->res.step++;
    self->res.t_us = t;
    self->res.validity = validity;
    self->res.status = (uint8_t)diag_status(self, validity);
    self->res.iso_class = iso_class_code(self->table, &self->res.diag.iso);
    self->tx_pending = true;
}

/* Run the steps due by t: those with T_k < t (a step sees exactly the frames with t <= T_k). */
static void run_due(fdi_ecu_t *self, uint32_t t)
{
    uint32_t n = 0U;
    bool more = true;
    if (!self->started)
    {
        self->started = true;
        self->next_us = t + self->step_us;
        self->last_us = t;
    }
    if (time_diff(t, self->last_us) > 0)
    {
        self->last_us = t;
    }
    while (more)
    {
        const int32_t d = time_diff(t, self->next_us);
        more = d > 0;
        if (more)
        {
            if (n >= (uint32_t)self->max_catchup)
            {
                /* resynchronise: skip the steps still due, next step one period after t */
                const uint32_t skipped = (((uint32_t)d - 1U) / self->step_us) + 1U; /* T_k < t: ceil(d / step) */
                self->cnt.steps_skipped += skipped;
                self->next_us = t + self->step_us;
                more = false;
            }
            else
            {
                run_step(self, self->next_us);
                self->next_us += self->step_us;
                ++n;
            }
        }
    }
}

/* ------------------------------------------------------------------------------------------ API */

fdi_status_t fdi_ecu_config_default(fdi_ecu_config_t *cfg, const fdi_table_t *table)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((cfg != NULL) && (table != NULL))
    {
        const fdi_table_design_t *d = &table->design;
        const float rate = d->zeta * 6.28318530717959f * d->cutoff_hz;
        st = FDI_BAD_TABLE;
        if ((rate > 0.0f) && (d->obs_gain > 0.0f) && (d->dt > 0.0f))
        {
            const float t_svf = (2.0f * FDI_DIAG_SETTLE_TAUS) / rate;
            const float t_obs = FDI_DIAG_SETTLE_TAUS / d->obs_gain;
            const float n = ceilf(((t_svf > t_obs) ? t_svf : t_obs) / d->dt);
            if (fdi_float_is_finite(n) && (n < 60000.0f))
            {
                uint32_t i;
                cfg->diag.table = table;
                cfg->diag.d_x = FDI_ECU_DEFAULT_D_X;
                cfg->diag.d_y = FDI_ECU_DEFAULT_D_Y;
                cfg->diag.cusum_k = 1.5f;
                cfg->diag.cusum_h = 150.0f;
                cfg->diag.set_count = 10U;
                cfg->diag.clear_count = 100U;
                cfg->diag.warmup_steps = (uint16_t)((uint32_t)n + WARMUP_MARGIN_STEPS);
                cfg->diag.mode = FDI_ISO_EXONERATION;
                cfg->diag.iso_settle_steps = ISO_SETTLE_STEPS;
                cfg->diag.episode_clear_steps = EPISODE_CLEAR_STEPS;
                for (i = 0U; i < FDI_ECU_N_MSGS; ++i)
                {
                    cfg->timeout_us[i] = TIMEOUT_CYCLES * (uint32_t)msg_desc[i].cycle_ms * US_PER_MS;
                }
                cfg->max_delta_counter = 1U;
                cfg->max_catchup_steps = 100U;
                st = FDI_OK;
            }
        }
    }
    return st;
}

fdi_status_t fdi_ecu_init(fdi_ecu_t *self, const fdi_ecu_config_t *cfg)
{
    fdi_status_t st = FDI_BAD_ARG;
    uint32_t step_us = 0U;
    if ((self != NULL) && (cfg != NULL) && (cfg->diag.table != NULL) && (cfg->max_delta_counter >= 1U) &&
        (cfg->max_delta_counter < E2E_COUNTER_MOD) && (cfg->max_catchup_steps >= 1U))
    {
        const float dt = cfg->diag.table->design.dt;
        st = FDI_OK;
        if (!fdi_float_is_finite(dt) || (dt < 1.0e-4f) || (dt > 10.0f))
        {
            st = FDI_BAD_ARG;
        }
        else
        {
            const float us = dt * 1.0e6f;
            step_us = (uint32_t)(us + 0.5f);
            if (fabsf(us - (float)step_us) > (1.0e-3f * us))
            {
                st = FDI_BAD_ARG; /* dt must be a whole number of microseconds (to float precision) */
            }
        }
        if (st == FDI_OK)
        {
            uint32_t i;
            for (i = 0U; i < FDI_ECU_N_MSGS; ++i)
            {
                if (cfg->timeout_us[i] == 0U)
                {
                    st = FDI_BAD_ARG;
                }
            }
        }
    }
    if (st == FDI_OK)
    {
        st = fdi_diag_init(&self->diag, &cfg->diag);
    }
    if (st == FDI_OK)
    {
        const fdi_table_t *t = cfg->diag.table;
        uint32_t i;
        uint32_t r;
        self->gen_mask = 0U;
        for (i = 0U; i < (uint32_t)t->n_tests; ++i)
        {
            if (t->tests[i].kind != FDI_GEN_NONE)
            {
                self->gen_mask |= (uint32_t)1U << i;
            }
        }
        self->in = (fdi_inputs_t){0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f,
                                  0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
        self->cnt.frames = 0U;
        self->cnt.steps = 0U;
        self->cnt.steps_skipped = 0U;
        self->cnt.tx_frames = 0U;
        for (r = 0U; r < FDI_ECU_N_REASONS; ++r)
        {
            self->cnt.rejected[r] = 0U;
        }
        for (i = 0U; i < FDI_ECU_N_MSGS; ++i)
        {
            self->timeout_us[i] = cfg->timeout_us[i];
            self->msg[i].t_last_us = 0U;
            self->msg[i].last_counter = 0U;
            self->msg[i].seen = false;
            self->msg[i].have = false;
            self->msg[i].status_ok = false;
            self->msg[i].fresh = false;
            self->cnt.msg[i].can_id = msg_desc[i].can_id;
            self->cnt.msg[i].received = 0U;
            self->cnt.msg[i].accepted = 0U;
            self->cnt.msg[i].timeouts = 0U;
            for (r = 0U; r < FDI_ECU_N_REASONS; ++r)
            {
                self->cnt.msg[i].rejected[r] = 0U;
            }
        }
        (void)fdi_diag_result(&self->diag, &self->res.diag);
        self->res.step = 0U;
        self->res.t_us = 0U;
        self->res.validity = 0U;
        self->res.status = (uint8_t)FDI_ECU_STATUS_INIT;
        self->res.iso_class = 0U;
        self->step_us = step_us;
        self->next_us = 0U;
        self->last_us = 0U;
        self->max_catchup = cfg->max_catchup_steps;
        self->max_delta = cfg->max_delta_counter;
        self->tx_counter = 0U;
        self->started = false;
        self->tx_pending = false;
        self->table = t;
    }
    else if (self != NULL)
    {
        self->table = NULL;
    }
    else
    {
        /* nothing to mark */
    }
    return st;
}

static void reject(fdi_ecu_t *self, int32_t idx, fdi_ecu_reason_t why)
{
    self->cnt.rejected[why]++;
    if (idx >= 0)
    {
        self->cnt.msg[idx].rejected[why]++;
    }
}

/* E2E, range, sequence and status checks of an input frame of message idx, then its values. */
static void accept_frame(fdi_ecu_t *self, uint32_t idx, const uint8_t *data, uint32_t t_us)
{
    fdi_ecu_msg_state_t *m = &self->msg[idx];
    fdi_inputs_t in = self->in;
    frame_info_t fi = {0U, 0U, false};
    if (fdi_ecu_e2e_crc(msg_desc[idx].data_id, data, (uint8_t)FDI_ECU_FRAME_LEN) != data[0])
    {
        reject(self, (int32_t)idx, FDI_ECU_REJ_BAD_CRC);
    }
    else
    {
        decode(idx, data, &in, &fi);
        if (!fi.in_range)
        {
            reject(self, (int32_t)idx, FDI_ECU_REJ_OUT_OF_RANGE);
        }
        else
        {
            const uint32_t delta =
                ((uint32_t)fi.counter + E2E_COUNTER_MOD - (uint32_t)m->last_counter) % E2E_COUNTER_MOD;
            const bool first = !m->seen;
            m->seen = true;
            m->last_counter = fi.counter;
            if (!first && (delta == 0U))
            {
                reject(self, (int32_t)idx, FDI_ECU_REJ_REPEATED_COUNTER);
            }
            else if (!first && (delta > (uint32_t)self->max_delta))
            {
                reject(self, (int32_t)idx, FDI_ECU_REJ_COUNTER_JUMP);
            }
            else if ((fi.status != STATUS_OK) && (fi.status != STATUS_DEGRADED))
            {
                m->status_ok = false; /* the sender says its values are not usable: invalid at once */
                reject(self, (int32_t)idx, FDI_ECU_REJ_SENSOR_STATUS);
            }
            else
            {
                self->in = in;
                m->status_ok = true;
                m->have = true;
                m->t_last_us = t_us;
                self->cnt.msg[idx].accepted++;
            }
        }
    }
}

fdi_status_t fdi_ecu_rx(fdi_ecu_t *self, uint32_t can_id, uint8_t dlc, const uint8_t *data, uint32_t t_us)
{
    fdi_status_t st = FDI_BAD_ARG;
    if (ready(self) && ((data != NULL) || (dlc == 0U)))
    {
        const int32_t idx = msg_index(can_id);
        st = FDI_OK;
        run_due(self, t_us);
        self->cnt.frames++;
        if (idx < 0)
        {
            reject(self, -1, (can_id == FDI_ECU_DIAG_ID) ? FDI_ECU_REJ_OWN_FRAME : FDI_ECU_REJ_UNKNOWN_ID);
        }
        else
        {
            self->cnt.msg[idx].received++;
            if (dlc != FDI_ECU_FRAME_LEN)
            {
                reject(self, idx, FDI_ECU_REJ_BAD_DLC);
            }
            else
            {
                accept_frame(self, (uint32_t)idx, data, t_us);
            }
        }
    }
    return st;
}

fdi_status_t fdi_ecu_poll(fdi_ecu_t *self, uint32_t t_us, fdi_ecu_tx_t *tx)
{
    fdi_status_t st = FDI_BAD_ARG;
    if (tx != NULL)
    {
        tx->n_frames = 0U;
    }
    if (ready(self) && (tx != NULL))
    {
        st = FDI_OK;
        run_due(self, t_us);
        if (self->tx_pending)
        {
            struct romo_can_fdi_diagnosis_t msg;
            fdi_ecu_frame_t *f = &tx->frame[0];
            uint32_t i;
            for (i = 0U; i < FDI_ECU_FRAME_LEN; ++i)
            {
                f->data[i] = 0U;
            }
            (void)romo_can_fdi_diagnosis_init(&msg);
            msg.fdi_crc = 0U;
            msg.fdi_counter = self->tx_counter;
            msg.fdi_status = self->res.status;
            msg.fdi_alarm_mask = (uint16_t)(self->res.diag.alarm_mask & 0x0FFFU);
            msg.fdi_candidate_faults = self->res.diag.iso.candidates & 0x01FFFFFFU;
            msg.fdi_isolation_class = self->res.iso_class;
            (void)romo_can_fdi_diagnosis_pack(f->data, &msg, FDI_ECU_FRAME_LEN);
            f->data[0] = fdi_ecu_e2e_crc((uint16_t)ROMO_CAN_E2E_FDI_DIAGNOSIS_DATA_ID, f->data,
                                         (uint8_t)FDI_ECU_FRAME_LEN);
            f->can_id = FDI_ECU_DIAG_ID;
            f->dlc = (uint8_t)FDI_ECU_FRAME_LEN;
            tx->n_frames = 1U;
            self->tx_counter = (uint8_t)(((uint32_t)self->tx_counter + 1U) % E2E_COUNTER_MOD);
            self->tx_pending = false;
            self->cnt.tx_frames++;
        }
    }
    return st;
}

fdi_status_t fdi_ecu_counters(const fdi_ecu_t *self, fdi_ecu_counters_t *out)
{
    fdi_status_t st = FDI_BAD_ARG;
    if (ready(self) && (out != NULL))
    {
        *out = self->cnt;
        st = FDI_OK;
    }
    return st;
}

fdi_status_t fdi_ecu_result(const fdi_ecu_t *self, fdi_ecu_result_t *out)
{
    fdi_status_t st = FDI_BAD_ARG;
    if (ready(self) && (out != NULL))
    {
        *out = self->res;
        st = FDI_OK;
    }
    return st;
}
