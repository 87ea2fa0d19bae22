/*
 * fdi_signals.h - the signal frame: the 19 measured signals of the ROboMObil dual-track model.
 *
 * Each signal has a bit position (0..18, in the order of fdi_inputs_t) and a mask FDI_SIGM_<name>.
 * A validity bitmask with the same bit layout accompanies every frame: bit set = the sample is fresh and
 * plausible (the caller's CAN layer clears it on timeout, checksum or range errors). Generators declare the
 * signals they read as such a mask; the diagnoser reports a test "not evaluable" when any of them is invalid.
 *
 * fdi_signals_finite_mask() returns the mask of signals whose value is finite: 19 bit tests per call.
 * Memory: fdi_inputs_t is 19 floats (76 bytes).
 */
#ifndef FDI_SIGNALS_H
#define FDI_SIGNALS_H

#include <stdint.h>


#define FDI_SIG_COUNT 19U

#define FDI_SIGM_AX_M 0x00000001U /* bit 0 */
#define FDI_SIGM_AY_M 0x00000002U
#define FDI_SIGM_PSIDOT_M 0x00000004U
#define FDI_SIGM_VX_M 0x00000008U
#define FDI_SIGM_VY_M 0x00000010U
#define FDI_SIGM_DELTA1_M 0x00000020U
#define FDI_SIGM_DELTA2_M 0x00000040U
#define FDI_SIGM_DELTA3_M 0x00000080U
#define FDI_SIGM_DELTA4_M 0x00000100U
#define FDI_SIGM_ITM1_M 0x00000200U
#define FDI_SIGM_ITM2_M 0x00000400U
#define FDI_SIGM_ITM3_M 0x00000800U
#define FDI_SIGM_ITM4_M 0x00001000U
#define FDI_SIGM_P_F_M 0x00002000U
#define FDI_SIGM_P_R_M 0x00004000U
#define FDI_SIGM_OMEGA1_M 0x00008000U
#define FDI_SIGM_OMEGA2_M 0x00010000U
#define FDI_SIGM_OMEGA3_M 0x00020000U
#define FDI_SIGM_OMEGA4_M 0x00040000U
#define FDI_SIGM_ALL 0x0007FFFFU

/*
 * One sample of every measured signal, SI units: accelerations [m/s^2], yaw rate [rad/s], velocities at
 * the sensor [m/s], steering angles [rad], traction motor currents [A], brake pressures [Pa], wheel speeds
 * [rad/s]. Field order = bit order of the FDI_SIGM_* masks.
 */
typedef struct
{
    float ax_m;
    float ay_m;
    float psidot_m;
    float vx_m;
    float vy_m;
    float delta1_m;
    float delta2_m;
    float delta3_m;
    float delta4_m;
    float iTM1_m;
    float iTM2_m;
    float iTM3_m;
    float iTM4_m;
    float P_f_m;
    float P_r_m;
    float omega1_m;
    float omega2_m;
    float omega3_m;
    float omega4_m;
} fdi_inputs_t;

/* Mask of the signals of *in that are finite (bit layout as FDI_SIGM_*). in == NULL gives 0 (nothing usable). */
uint32_t fdi_signals_finite_mask(const fdi_inputs_t *in);

#endif /* FDI_SIGNALS_H */
