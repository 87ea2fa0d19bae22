/* fdi_ecu.c - the ECU process core: frame checks, decoding, timeouts, fixed steps, diagnosis frame (fdi_ecu.h). */
#include "fdi_ecu.h"

#include <math.h>
#include <stddef.h>

#include "fdi_float.h"

#define E2E_COUNTER_MOD 15U /* profile 11 counter runs 0..14 */
#define STATUS_OK 0U
#define STATUS_DEGRADED 1U
#define TIMEOUT_CYCLES 3U
#define US_PER_MS 1000U
#define MAX_ALIGN_US 60000000U /* 60 s: far below half the clock's wrap */

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

static int32_t msg_index(const fdi_ecu_bus_t *bus, uint32_t can_id)
{
    int32_t idx = -1;
    uint32_t i;
    for (i = 0U; i < (uint32_t)bus->n_msgs; ++i)
    {
        if (bus->msgs[i].can_id == can_id)
        {
            idx = (int32_t)i;
        }
    }
    return idx;
}

int32_t fdi_ecu_msg_index(const fdi_ecu_bus_t *bus, uint32_t can_id)
{
    return ((bus != NULL) && (bus->msgs != NULL)) ? msg_index(bus, can_id) : -1;
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

/* Slot of the k-th newest kept frame of m (k < n_kept). */
static uint32_t kept_slot(const fdi_ecu_msg_state_t *m, uint32_t k)
{
    return (((uint32_t)m->newest + FDI_ECU_HISTORY) - k) % FDI_ECU_HISTORY;
}

/* The values of message i at the instant s into the frame: linear between the two kept frames around s (when
   they are at most the message's timeout apart), else the kept frame nearest to s (the newest when s is after
   it or the frames around s are too far apart, the oldest when every kept frame is after s). */
static void aligned_values(fdi_ecu_t *self, uint32_t i, uint32_t s)
{
    const fdi_ecu_msg_state_t *m = &self->msg[i];
    const fdi_ecu_msg_desc_t *desc = &self->bus->msgs[i];
    uint32_t after = (uint32_t)m->newest; /* slot of the frame just after s (or the one taken) */
    uint32_t before = after;             /* slot of the newest frame at or before s */
    bool found = false;
    float w = 0.0f;                      /* weight of `after` */
    uint32_t k;
    for (k = 0U; (!found) && (k < (uint32_t)m->n_kept); ++k)
    {
        const uint32_t slot = kept_slot(m, k);
        if (time_diff(s, m->t_us[slot]) >= 0)
        {
            found = true;
            before = slot;
        }
        else
        {
            after = slot; /* also the oldest kept frame when none is at or before s */
        }
    }
    if (found && (before != after))
    {
        const int32_t span = time_diff(m->t_us[after], m->t_us[before]);
        if ((span > 0) && ((uint32_t)span <= self->timeout_us[i]))
        {
            w = (float)time_diff(s, m->t_us[before]) / (float)span;
        }
        else
        {
            w = 1.0f; /* a gap: the newer frame */
        }
    }
    else if (!found)
    {
        before = after; /* every kept frame is after s: the oldest */
    }
    else
    {
        /* s at or after the newest frame: it */
    }
    for (k = 0U; k < (uint32_t)desc->n_values; ++k)
    {
        const float a = m->value[before][k];
        self->in.value[desc->signal_index[k]] = a + (w * (m->value[after][k] - a));
    }
}

/* One diagnosis step at time t: timeouts, the signals of the step's instant, fdi_diag_step, result. */
static void run_step(fdi_ecu_t *self, uint32_t t)
{
    uint32_t validity = 0U;
    uint32_t i;
    for (i = 0U; i < (uint32_t)self->bus->n_msgs; ++i)
    {
        fdi_ecu_msg_state_t *m = &self->msg[i];
        bool fresh = false;
        if (m->n_kept > 0U)
        {
            aligned_values(self, i, t - self->align_us);
        }
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
            validity |= self->bus->msgs[i].signals;
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

/* How far behind its newest frame the kept frames of message m reach, one cycle of jitter spared (<= 60 s). */
static uint32_t covered_us(const fdi_ecu_msg_desc_t *m)
{
    const uint64_t cycles = (uint64_t)FDI_ECU_HISTORY - 2U;
    const uint64_t us = cycles * (uint64_t)m->cycle_ms * (uint64_t)US_PER_MS;
    return (us < (uint64_t)MAX_ALIGN_US) ? (uint32_t)us : MAX_ALIGN_US;
}

uint32_t fdi_ecu_align_us(const fdi_ecu_bus_t *bus)
{
    uint32_t longest = 0U;
    uint32_t cover = 0xFFFFFFFFU;
    uint32_t i;
    const uint32_t n = ((bus != NULL) && (bus->msgs != NULL) && ((uint32_t)bus->n_msgs <= FDI_ECU_MAX_MSGS))
                           ? (uint32_t)bus->n_msgs
                           : 0U;
    for (i = 0U; i < n; ++i)
    {
        const fdi_ecu_msg_desc_t *m = &bus->msgs[i];
        if (m->n_values > 0U)
        {
            const uint32_t cycle = (uint32_t)m->cycle_ms * US_PER_MS;
            const uint32_t reach = covered_us(m);
            longest = (cycle > longest) ? cycle : longest;
            cover = (reach < cover) ? reach : cover;
        }
    }
    return (longest < cover) ? longest : cover;
}

fdi_status_t fdi_ecu_config_default(fdi_ecu_config_t *cfg, const fdi_table_t *table, const fdi_ecu_bus_t *bus)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((cfg != NULL) && (table != NULL) && (bus != NULL) && (bus->msgs != NULL) &&
        ((uint32_t)bus->n_msgs <= FDI_ECU_MAX_MSGS))
    {
        st = fdi_diag_config_default(&cfg->diag, table);
        if (st == FDI_OK)
        {
            uint32_t i;
            cfg->bus = bus;
            for (i = 0U; i < FDI_ECU_MAX_MSGS; ++i)
            {
                cfg->timeout_us[i] = (i < (uint32_t)bus->n_msgs)
                                         ? (TIMEOUT_CYCLES * (uint32_t)bus->msgs[i].cycle_ms * US_PER_MS)
                                         : 0U;
            }
            cfg->max_delta_counter = 1U;
            cfg->max_catchup_steps = 100U;
            cfg->align_us = 0U; /* sample-and-hold; fdi_ecu_align_us(bus) aligns in time */
        }
    }
    return st;
}

static bool msg_ok(const fdi_ecu_msg_desc_t *m, uint32_t signal_universe)
{
    bool ok = (m->name != NULL) && (m->decode != NULL) && (m->dlc >= 2U) && (m->dlc <= FDI_ECU_FRAME_LEN) &&
              (m->cycle_ms > 0U) && (m->can_id <= 0x7FFU) && (m->n_values <= FDI_ECU_MAX_MSG_VALUES) &&
              ((m->n_values == 0U) || (m->signal_index != NULL));
    if (ok)
    {
        uint32_t mask = 0U;
        uint32_t k;
        for (k = 0U; ok && (k < (uint32_t)m->n_values); ++k)
        {
            const uint32_t idx = (uint32_t)m->signal_index[k];
            ok = (idx < FDI_FRAME_MAX_SIGNALS) && ((signal_universe & ((uint32_t)1U << idx)) != 0U);
            mask |= ok ? ((uint32_t)1U << idx) : 0U;
        }
        ok = ok && (mask == m->signals);
    }
    return ok;
}

static fdi_status_t bus_check(const fdi_ecu_bus_t *bus, const fdi_table_t *table)
{
    fdi_status_t st = FDI_BAD_ARG;
    if ((bus != NULL) && (table != NULL) && (bus->msgs != NULL) && (bus->name != NULL) &&
        (bus->encode_diag != NULL) && (bus->n_msgs >= 1U) && ((uint32_t)bus->n_msgs <= FDI_ECU_MAX_MSGS) &&
        (bus->diag_dlc >= 2U) && (bus->diag_dlc <= FDI_ECU_FRAME_LEN) &&
        ((uint32_t)table->n_signals <= FDI_FRAME_MAX_SIGNALS))
    {
        const uint32_t universe = fdi_frame_low_mask((uint32_t)table->n_signals);
        uint32_t i;
        st = FDI_OK;
        for (i = 0U; (st == FDI_OK) && (i < (uint32_t)bus->n_msgs); ++i)
        {
            const fdi_ecu_msg_desc_t *m = &bus->msgs[i];
            if (!msg_ok(m, universe) || (msg_index(bus, m->can_id) != (int32_t)i) || (m->can_id == bus->diag_id))
            {
                st = FDI_BAD_ARG; /* bad message, or its ID twice (msg_index finds the last), or the diag ID */
            }
        }
    }
    return st;
}

fdi_status_t fdi_ecu_bus_check(const fdi_ecu_bus_t *bus, const fdi_table_t *table)
{
    return bus_check(bus, table);
}

fdi_status_t fdi_ecu_init(fdi_ecu_t *self, const fdi_ecu_config_t *cfg)
{
    fdi_status_t st = FDI_BAD_ARG;
    uint32_t step_us = 0U;
    if ((self != NULL) && (cfg != NULL) && (cfg->diag.table != NULL) && (cfg->max_delta_counter >= 1U) &&
        (cfg->max_delta_counter < E2E_COUNTER_MOD) && (cfg->max_catchup_steps >= 1U) &&
        (bus_check(cfg->bus, cfg->diag.table) == FDI_OK))
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
            for (i = 0U; i < (uint32_t)cfg->bus->n_msgs; ++i)
            {
                const fdi_ecu_msg_desc_t *m = &cfg->bus->msgs[i];
                if ((cfg->timeout_us[i] == 0U) || (cfg->align_us > MAX_ALIGN_US) ||
                    ((m->n_values > 0U) && (cfg->align_us > covered_us(m))))
                {
                    st = FDI_BAD_ARG; /* no timeout, or the alignment reaches behind the message's history */
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
            if (t->tests[i].gen != NULL)
            {
                self->gen_mask |= (uint32_t)1U << i;
            }
        }
        for (i = 0U; i < FDI_FRAME_MAX_SIGNALS; ++i)
        {
            self->in.value[i] = 0.0f;
        }
        self->cnt.frames = 0U;
        self->cnt.steps = 0U;
        self->cnt.steps_skipped = 0U;
        self->cnt.tx_frames = 0U;
        for (r = 0U; r < FDI_ECU_N_REASONS; ++r)
        {
            self->cnt.rejected[r] = 0U;
        }
        for (i = 0U; i < FDI_ECU_MAX_MSGS; ++i)
        {
            const bool used = i < (uint32_t)cfg->bus->n_msgs;
            self->timeout_us[i] = used ? cfg->timeout_us[i] : 0U;
            self->msg[i].t_last_us = 0U;
            self->msg[i].newest = 0U;
            self->msg[i].n_kept = 0U;
            self->msg[i].last_counter = 0U;
            self->msg[i].seen = false;
            self->msg[i].have = false;
            self->msg[i].status_ok = false;
            self->msg[i].fresh = false;
            self->cnt.msg[i].can_id = used ? cfg->bus->msgs[i].can_id : 0U;
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
        self->align_us = cfg->align_us;
        self->next_us = 0U;
        self->last_us = 0U;
        self->max_catchup = cfg->max_catchup_steps;
        self->max_delta = cfg->max_delta_counter;
        self->tx_counter = 0U;
        self->started = false;
        self->tx_pending = false;
        self->bus = cfg->bus;
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
    const fdi_ecu_msg_desc_t *desc = &self->bus->msgs[idx];
    fdi_ecu_msg_state_t *m = &self->msg[idx];
    fdi_ecu_rx_info_t fi = {0U, 0U, false, {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f}};
    if (fdi_ecu_e2e_crc(desc->data_id, data, desc->dlc) != data[0])
    {
        reject(self, (int32_t)idx, FDI_ECU_REJ_BAD_CRC);
    }
    else
    {
        desc->decode(data, &fi);
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
                const uint32_t slot = (m->n_kept == 0U) ? 0U : (((uint32_t)m->newest + 1U) % FDI_ECU_HISTORY);
                uint32_t k;
                for (k = 0U; k < (uint32_t)desc->n_values; ++k)
                {
                    m->value[slot][k] = fi.value[k];
                }
                m->t_us[slot] = t_us;
                m->newest = (uint8_t)slot;
                if ((uint32_t)m->n_kept < FDI_ECU_HISTORY)
                {
                    m->n_kept++;
                }
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
        const int32_t idx = msg_index(self->bus, can_id);
        st = FDI_OK;
        run_due(self, t_us);
        self->cnt.frames++;
        if (idx < 0)
        {
            reject(self, -1, (can_id == self->bus->diag_id) ? FDI_ECU_REJ_OWN_FRAME : FDI_ECU_REJ_UNKNOWN_ID);
        }
        else
        {
            self->cnt.msg[idx].received++;
            if ((dlc != self->bus->msgs[idx].dlc) || (data == NULL))
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
            const fdi_ecu_diag_msg_t msg = {self->tx_counter, self->res.status, self->res.diag.alarm_mask,
                                            self->res.diag.iso.candidates, self->res.iso_class};
            fdi_ecu_frame_t *f = &tx->frame[0];
            uint32_t i;
            for (i = 0U; i < FDI_ECU_FRAME_LEN; ++i)
            {
                f->data[i] = 0U;
            }
            self->bus->encode_diag(&msg, f->data);
            f->data[0] = fdi_ecu_e2e_crc(self->bus->diag_data_id, f->data, self->bus->diag_dlc);
            f->can_id = self->bus->diag_id;
            f->dlc = self->bus->diag_dlc;
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
