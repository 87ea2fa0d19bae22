/*
 * fdi_ecu.h - the ECU process core: CAN frames in, fixed-step diagnosis, diagnosis frames out.
 *
 * Portable (no OS call, no heap, no clock) and vehicle-independent: the bus it listens to is a const
 * description (fdi_ecu_bus_t) that a vehicle target generates from its DBC (fdi-analyze export-can: message
 * IDs, lengths, cycle times, E2E data IDs, which frame signals each message carries, and per message a decode
 * function: unpack, range checks, scaling to SI; plus the packing of the diagnosis frame). The front end
 * (fw/ecu/linux/fdi_ecu_socketcan.c, the Python bindings host_tools/fdi_host/ecu/bindings.py, or an ECU's CAN
 * driver) hands every received frame with its receive time to fdi_ecu_rx() and calls fdi_ecu_poll() after
 * every frame and on a timer.
 *
 * Reception (fdi_ecu_rx), per frame, in this order; the first failing check rejects the frame, which is
 * counted by reason (fdi_ecu_reason_t) and ignored (its values are not used, the message's timeout keeps
 * running, so a sender that only produces bad frames goes silent after its timeout):
 *   the bus's diagnosis frame ID (our own frame echoed by the bus) -> OWN_FRAME; any other ID that is not one
 *   of the bus's input messages (including extended/RTR/error flags in can_id) -> UNKNOWN_ID;
 *   dlc != the message's length -> BAD_DLC; E2E profile 11 CRC (CRC8 SAE-J1850 over the data ID low, high byte
 *   and bytes 1..dlc-1) -> BAD_CRC; alive counter 15 or any raw signal outside its DBC range (the decode
 *   function) -> OUT_OF_RANGE; counter equal to the last accepted one -> REPEATED_COUNTER; counter advanced by
 *   more than max_delta_counter (mod 15) -> COUNTER_JUMP (the receiver re-synchronises on it: a restarted sender
 *   costs one frame per message, and a sender whose counter keeps jumping is never accepted); sender status
 *   nibble other than OK/DEGRADED -> SENSOR_STATUS (the message's signals go invalid at once). The decoded
 *   values of an accepted frame (SI units) update the frame's signals of the message; the message is then fresh.
 *
 * Scheduling: fixed steps of dt = table design dt, step k at time T_k = t_first + k * dt where t_first is the
 * time of the first rx/poll call. Step k runs at the first rx or poll call with a time t > T_k (fdi_ecu_rx runs
 * it before taking its frame), so it sees exactly the frames received at t <= T_k, also when several frames
 * carry the same time stamp: the result does not depend on when or how often poll is called. A front end polls
 * after every frame and on a timer just after each step boundary (T_k + a few us) to bound the latency on a
 * silent bus. At each step:
 *   validity = union of the signal masks of the fresh messages, where a message is fresh when it was accepted
 *   at least once, its last frame had sender status OK/DEGRADED and T_k - t_last <= its timeout (default 3x
 *   the DBC cycle time); the frame's signals are those of one instant, s_k = T_k - align_us (time alignment,
 *   below); then fdi_diag_step(frame, validity), so tests reading a silent or invalid signal become "not
 *   evaluable" (and warm up again when it returns).
 * Time alignment: messages come at their own cycle times and phases, so the last frames of a step are of
 *   different instants, and in fast motion that difference alone makes a residual (a product of a yaw rate and
 *   a velocity read 5 ms apart). Each message keeps its last FDI_ECU_HISTORY accepted frames; a signal's value
 *   at s_k is linear between its message's two kept frames around s_k, or the newer of them when they are more
 *   than the message's timeout apart (a silent sender), the newest frame when s_k is after it, the oldest kept
 *   frame when every kept frame is after s_k (the first steps). fdi_ecu_align_us(bus) gives the alignment that
 *   brings every message's signals to one instant: the longest cycle time of the messages that carry frame
 *   signals (every message then has a frame at or before s_k), capped so that every such message's kept
 *   frames reach back to it ((FDI_ECU_HISTORY - 2) cycles); the diagnosis then lags the bus by align_us.
 *   The default, align_us 0, is sample-and-hold (each message's last frame), without lag. A table's gates hold
 *   only for the view they were calibrated on (the host tools' offline view of the ECU, with the same
 *   alignment): run a table with the alignment of its calibration (fw/ecu/README.md names it per vehicle).
 * If more than max_catchup_steps steps are due in one call (the host stalled or the clock jumped), the
 * oldest are skipped (counted) and the schedule restarts at the current time.
 * Time is uint32_t microseconds and may wrap (every ~71.6 min): all comparisons use modular differences,
 * so calls must come at least every 35 minutes. A time going backwards is treated as "no time passed".
 *
 * Output (fdi_ecu_poll): the diagnosis frame (the bus's diag ID, E2E profile 11 with its own counter, packed
 * by the bus's encode function) of the newest step run since the previous poll, n_frames 0 or 1:
 *   status         FAULT_ISOLATED (3) detected and isolated to one class; FAULT_DETECTED (2) detected, not
 *                  isolated (several classes or no single fault explains the alarms); else INPUT_INVALID (4)
 *                  when a test with a generator lacks valid inputs; else INIT (0) when a test with a
 *                  generator is still warming up or the table has no test with a generator; else NO_FAULT (1)
 *   alarm_mask     alarm mask of the tests;  candidates  candidate faults (bit j = fault j)
 *   iso_class      0 = nothing detected; 1..254 = isolated: the lowest fault number (j + 1) of the class;
 *                  255 = detected but not isolated.
 * (the encode function keeps the bits its DBC signals hold).
 *
 * Cost: rx = a CRC of the frame's bytes (one table look-up per byte), the unpack, one range check per signal and
 * the values kept; a step = fdi_diag_step + per message one timeout compare and a search of its kept frames, per
 * signal one interpolation + frame packing. Memory: sizeof(fdi_ecu_t) (scripts/bench_fw.sh prints it) = the
 * diagnoser (fdi_diag_t) and its result (fdi_diag_result_t), a frame (fdi_frame_t), per message slot its counters
 * and FDI_ECU_HISTORY kept frames, and the ECU's own state; caller-owned. Flash: a 256-entry table of uint8_t for
 * the CRC.
 */
#ifndef FDI_ECU_H
#define FDI_ECU_H

#include <stdbool.h>
#include <stdint.h>

#include "fdi_diag.h"
#include "fdi_frame.h"
#include "fdi_static_assert.h"
#include "fdi_status.h"
#include "fdi_table.h"

/* FDI_ECU_MAX_MSGS (input messages of a bus), FDI_ECU_HISTORY (accepted frames kept per message for the time
   alignment): overridable capacities of fdi_capacity.h (the fdi library's, included by fdi_diag.h) */
#define FDI_ECU_FRAME_LEN 8U      /* classic CAN: at most 8 data bytes */
#define FDI_ECU_MAX_MSG_VALUES 8U /* frame signals one message can carry */

/* What a message's decode function reports about one frame (its CRC already checked). */
typedef struct
{
    uint8_t counter;  /* E2E alive counter */
    uint8_t status;   /* sender status nibble (0 OK, 1 DEGRADED, other: values not usable) */
    bool in_range;    /* counter and every raw signal within its DBC range */
    float value[FDI_ECU_MAX_MSG_VALUES]; /* the message's frame signals in SI units, in signal_index order */
} fdi_ecu_rx_info_t;

/* Unpack one frame of the message (dlc bytes, checked by the caller) into *info. Cannot fail. */
typedef void (*fdi_ecu_decode_fn_t)(const uint8_t *data, fdi_ecu_rx_info_t *info);

/* One input message of the bus (generated from the DBC). */
typedef struct
{
    const char *name;             /* DBC message name */
    uint32_t can_id;              /* 11-bit ID (no flags) */
    uint8_t dlc;                  /* 1..FDI_ECU_FRAME_LEN */
    uint16_t data_id;             /* E2E profile 11 data ID */
    uint16_t cycle_ms;            /* DBC cycle time, > 0 */
    uint8_t n_values;             /* frame signals it carries, 0..FDI_ECU_MAX_MSG_VALUES */
    const uint8_t *signal_index;  /* n_values frame indices (fdi_frame.h), NULL when n_values is 0 */
    uint32_t signals;             /* the same as a mask */
    fdi_ecu_decode_fn_t decode;   /* non-NULL */
} fdi_ecu_msg_desc_t;

/* The contents of one diagnosis frame, packed by the bus's encode function. */
typedef struct
{
    uint8_t counter;      /* E2E alive counter 0..14 */
    uint8_t status;       /* fdi_ecu_status_t */
    uint32_t alarm_mask;  /* tests in alarm */
    uint32_t candidates;  /* candidate faults */
    uint8_t iso_class;    /* see the header comment */
} fdi_ecu_diag_msg_t;

/* Pack the diagnosis frame into data[0..dlc-1] (byte 0, the CRC, left 0: the core fills it). Cannot fail. */
typedef void (*fdi_ecu_encode_fn_t)(const fdi_ecu_diag_msg_t *msg, uint8_t *data);

/* A vehicle's bus (generated from its DBC: fdi_<vehicle>_bus.h). */
typedef struct
{
    const char *name;
    uint8_t n_msgs;                  /* 1..FDI_ECU_MAX_MSGS */
    const fdi_ecu_msg_desc_t *msgs;  /* n_msgs input messages */
    uint32_t diag_id;                /* the diagnosis frame's ID */
    uint8_t diag_dlc;                /* 2..FDI_ECU_FRAME_LEN */
    uint16_t diag_data_id;           /* its E2E profile 11 data ID */
    fdi_ecu_encode_fn_t encode_diag; /* non-NULL */
} fdi_ecu_bus_t;

/* Reasons a received frame is rejected (index into the reject counters). */
typedef enum
{
    FDI_ECU_REJ_UNKNOWN_ID = 0,
    FDI_ECU_REJ_OWN_FRAME = 1,
    FDI_ECU_REJ_BAD_DLC = 2,
    FDI_ECU_REJ_BAD_CRC = 3,
    FDI_ECU_REJ_OUT_OF_RANGE = 4,
    FDI_ECU_REJ_REPEATED_COUNTER = 5,
    FDI_ECU_REJ_COUNTER_JUMP = 6,
    FDI_ECU_REJ_SENSOR_STATUS = 7
} fdi_ecu_reason_t;

#define FDI_ECU_N_REASONS 8U

/* FDI_Status values of the diagnosis frame (VAL_ table DiagStatus of the DBC). */
typedef enum
{
    FDI_ECU_STATUS_INIT = 0,
    FDI_ECU_STATUS_NO_FAULT = 1,
    FDI_ECU_STATUS_FAULT_DETECTED = 2,
    FDI_ECU_STATUS_FAULT_ISOLATED = 3,
    FDI_ECU_STATUS_INPUT_INVALID = 4
} fdi_ecu_status_t;

#define FDI_ECU_CLASS_NOT_ISOLATED 255U

typedef struct
{
    const fdi_ecu_bus_t *bus;             /* the vehicle's bus; must outlive the instance */
    fdi_diag_config_t diag;               /* table (its design dt is the step), generator parameters, CUSUM, ... */
    uint32_t timeout_us[FDI_ECU_MAX_MSGS]; /* per message of the bus: silence after which its signals go invalid, > 0 */
    uint8_t max_delta_counter;            /* 1..14: largest accepted alive-counter advance (1 = no loss) */
    uint16_t max_catchup_steps;           /* >= 1: steps run at most per call before resynchronising */
    uint32_t align_us;                    /* step k's signals are those of the instant T_k - align_us (header
                                             comment); 0: each message's last frame (sample-and-hold) */
} fdi_ecu_config_t;

typedef struct
{
    uint32_t can_id;
    uint32_t received;  /* frames with this ID */
    uint32_t accepted;  /* frames whose values were used */
    uint32_t timeouts;  /* fresh -> silent transitions */
    uint32_t rejected[FDI_ECU_N_REASONS];
} fdi_ecu_msg_counters_t;

typedef struct
{
    uint32_t frames;                       /* every fdi_ecu_rx call with a valid instance */
    uint32_t rejected[FDI_ECU_N_REASONS];  /* all IDs (UNKNOWN_ID and OWN_FRAME only here) */
    uint32_t steps;                        /* diagnosis steps run */
    uint32_t steps_skipped;                /* steps dropped by the catch-up limit */
    uint32_t tx_frames;                    /* diagnosis frames handed out by fdi_ecu_poll */
    fdi_ecu_msg_counters_t msg[FDI_ECU_MAX_MSGS]; /* per message of the bus (n_msgs used) */
} fdi_ecu_counters_t;

typedef struct
{
    uint32_t step;            /* number of steps run (0: none yet) */
    uint32_t t_us;            /* time T_k of the last step */
    uint32_t validity;        /* frame signal mask used by the last step */
    uint8_t status;           /* fdi_ecu_status_t */
    uint8_t iso_class;        /* FDI_IsolationClass as sent */
    fdi_diag_result_t diag;   /* alarm / evaluable masks, residuals, ratios, candidates, classes */
} fdi_ecu_result_t;

typedef struct
{
    uint32_t can_id;
    uint8_t dlc;
    uint8_t data[FDI_ECU_FRAME_LEN];
} fdi_ecu_frame_t;

typedef struct
{
    uint8_t n_frames; /* 0 or 1 */
    fdi_ecu_frame_t frame[1];
} fdi_ecu_tx_t;

typedef struct
{
    uint32_t t_us[FDI_ECU_HISTORY];                          /* receive times of the kept frames */
    float value[FDI_ECU_HISTORY][FDI_ECU_MAX_MSG_VALUES];    /* their decoded values */
    uint8_t newest;   /* index of the newest kept frame */
    uint8_t n_kept;   /* kept frames, 0..FDI_ECU_HISTORY */
    uint32_t t_last_us;
    uint8_t last_counter;
    bool seen;      /* a frame passed the E2E check at least once (counter reference valid) */
    bool have;      /* values accepted at least once */
    bool status_ok; /* last E2E-valid frame had sender status OK/DEGRADED */
    bool fresh;     /* state at the last step (for timeout counting) */
} fdi_ecu_msg_state_t;

typedef struct
{
    fdi_diag_t diag;
    const fdi_table_t *table;
    const fdi_ecu_bus_t *bus;
    fdi_frame_t in;
    fdi_ecu_msg_state_t msg[FDI_ECU_MAX_MSGS];
    uint32_t timeout_us[FDI_ECU_MAX_MSGS];
    uint32_t align_us;
    uint32_t gen_mask;  /* tests with a generator */
    uint32_t step_us;
    uint32_t next_us;   /* time of the next step */
    uint32_t last_us;   /* latest time seen */
    uint16_t max_catchup;
    uint8_t max_delta;
    uint8_t tx_counter;
    bool started;
    bool tx_pending;
    fdi_ecu_counters_t cnt;
    fdi_ecu_result_t res;
} fdi_ecu_t; /* opaque by convention */

/* Defaults for `table` on `bus`: the diagnoser's defaults (fdi_diag_config_default: CUSUM k 1.5, h 150, set 10,
   clear 100, warm-up = settling time + 20 steps, exoneration after a 3 s settle window, episodes ending after 3 s
   without alarm, generator parameters 0, no sensitivities), timeouts 3x the DBC cycle times, max_delta_counter 1,
   max_catchup_steps 100, align_us 0 (sample-and-hold; header comment). BAD_ARG on NULL or a bus with more than
   FDI_ECU_MAX_MSGS messages; BAD_TABLE when the table's design point has no finite settling time. */
fdi_status_t fdi_ecu_config_default(fdi_ecu_config_t *cfg, const fdi_table_t *table, const fdi_ecu_bus_t *bus);

/* A usable bus: counts within capacity, lengths 1..8, decode/encode non-NULL, each message's signal indices
   below the table's n_signals and equal to its mask, no ID twice, the diag ID not an input. FDI_OK or
   FDI_BAD_ARG. */
fdi_status_t fdi_ecu_bus_check(const fdi_ecu_bus_t *bus, const fdi_table_t *table);

/* BAD_ARG: NULL, a bus failing fdi_ecu_bus_check, zero timeout, max_delta_counter outside 1..14,
   max_catchup_steps 0, align_us beyond 60 s or (FDI_ECU_HISTORY - 2) cycles of a message with frame signals,
   table dt not a whole number of microseconds in 100 us..10 s; others from fdi_diag_init(). A failed init
   leaves an instance that every other call refuses with BAD_ARG. */
fdi_status_t fdi_ecu_init(fdi_ecu_t *self, const fdi_ecu_config_t *cfg);

/* One received frame at t_us. Rejections are counted, not errors (FDI_OK). BAD_ARG: self NULL or not
   initialised, or data NULL with dlc > 0 (nothing counted). */
fdi_status_t fdi_ecu_rx(fdi_ecu_t *self, uint32_t can_id, uint8_t dlc, const uint8_t *data, uint32_t t_us);

/* Run the steps due by t_us; tx gets the diagnosis frame of the newest step if any ran since the last
   poll. BAD_ARG on NULL / uninitialised (tx->n_frames set to 0 when tx is not NULL). */
fdi_status_t fdi_ecu_poll(fdi_ecu_t *self, uint32_t t_us, fdi_ecu_tx_t *tx);

/* Copies of the counters and of the last step's result. BAD_ARG on NULL / uninitialised. */
fdi_status_t fdi_ecu_counters(const fdi_ecu_t *self, fdi_ecu_counters_t *out);
fdi_status_t fdi_ecu_result(const fdi_ecu_t *self, fdi_ecu_result_t *out);

/* The alignment (us) that takes every message's signals at one instant (header comment, time alignment): the
   longest cycle time of the bus's messages that carry frame signals, capped at (FDI_ECU_HISTORY - 2) cycles of
   each of them; 0 for a NULL or oversized bus or one without signals. Cannot fail. */
uint32_t fdi_ecu_align_us(const fdi_ecu_bus_t *bus);

/* Index in bus->msgs of an input CAN ID, or -1 (also for a NULL bus). Cannot fail. */
int32_t fdi_ecu_msg_index(const fdi_ecu_bus_t *bus, uint32_t can_id);

/* CRC8 SAE-J1850 (poly 0x1D, init 0xFF, xor-out 0xFF) of the profile 11 header: data ID low byte, high
   byte, then data[1..len-1]. len >= 2 and data non-NULL, else 0. Cannot fail. */
uint8_t fdi_ecu_e2e_crc(uint16_t data_id, const uint8_t *data, uint8_t len);

#endif /* FDI_ECU_H */
