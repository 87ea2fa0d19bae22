/*
 * fdi_kin_table.c - hand-made diagnosis table of the kinematic tests MSO1..MSO4 (see fdi_kin_table.h).
 * Data only. Variances and reaction sizes: generated/fdi_kin_calibration.h, from drives of the vehicle
 * simulator through the C ECU core at the design point below (100 Hz, 1 Hz derivative filters) by
 * `fdi-tune kin-calibration` (the rules of `fdi-tune calibrate` and `fault-sizes`; a test fails
 * when the header is stale).
 */
#include "fdi_kin_table.h"

#include <stddef.h>

#include "fdi_kin_calibration.h"
#include "fdi_romo_kin.h"
#include "fdi_romo_signals.h"

#define F1 0x01U /* ax sensor */
#define F2 0x02U /* ay sensor */
#define F3 0x04U /* yaw rate sensor */
#define F4 0x08U /* vx sensor */
#define F5 0x10U /* vy sensor */

static const char *const kin_fault_names[5] = {"f1 ax sensor", "f2 ay sensor", "f3 yaw rate sensor",
                                               "f4 vx sensor", "f5 vy sensor"};

/* A quiet test exonerates only after 3 s (300 steps at 10 ms): the window in which fdi-tune kin-calibration states
   the reaction sizes below (an alarm within 3 s of a step fault). */
#define FDI_KIN_RESPONSE_STEPS 300U

static const fdi_test_desc_t kin_tests[4] = {
    {.gen = &fdi_romo_kin_x_deriv, .interpretation = "Kinematics. Measured a_x & measured velocities", .mso_id = 1U,
     .fault_mask = F1 | F3 | F4 | F5,
     .input_mask = ROMO_SIGM_AX_M | ROMO_SIGM_PSIDOT_M | ROMO_SIGM_VX_M | ROMO_SIGM_VY_M,
     .gate = 5.0f, .variance = FDI_KIN_VARIANCE_1, .response_steps = FDI_KIN_RESPONSE_STEPS},
    {.gen = &fdi_romo_kin_y_deriv, .interpretation = "Kinematics. Measured a_y & measured velocities", .mso_id = 2U,
     .fault_mask = F2 | F3 | F4 | F5,
     .input_mask = ROMO_SIGM_AY_M | ROMO_SIGM_PSIDOT_M | ROMO_SIGM_VX_M | ROMO_SIGM_VY_M,
     .gate = 5.0f, .variance = FDI_KIN_VARIANCE_2, .response_steps = FDI_KIN_RESPONSE_STEPS},
    {.gen = &fdi_romo_kin_arr3, .interpretation = "Kinematics. No v_y measurement", .mso_id = 3U,
     .fault_mask = F1 | F2 | F3 | F4,
     .input_mask = ROMO_SIGM_AX_M | ROMO_SIGM_AY_M | ROMO_SIGM_PSIDOT_M | ROMO_SIGM_VX_M,
     .gate = 5.0f, .variance = FDI_KIN_VARIANCE_3, .response_steps = FDI_KIN_RESPONSE_STEPS},
    {.gen = &fdi_romo_kin_arr4, .interpretation = "Kinematics. No v_x measurement", .mso_id = 4U,
     .fault_mask = F1 | F2 | F3 | F5,
     .input_mask = ROMO_SIGM_AX_M | ROMO_SIGM_AY_M | ROMO_SIGM_PSIDOT_M | ROMO_SIGM_VY_M,
     .gate = 5.0f, .variance = FDI_KIN_VARIANCE_4, .response_steps = FDI_KIN_RESPONSE_STEPS},
};

/* Column j of the test fault masks: bit i = test i sees fault j. */
static const uint32_t kin_signature[5] = {0x0DU, 0x0EU, 0x0FU, 0x07U, 0x0BU};

/* Every signature is unique: each class is the fault itself. */
static const uint32_t kin_iso_class[5] = {F1, F2, F3, F4, F5};

/* Reaction sizes (fault j, test i) for exoneration (fdi_iso.h): a weak test (e.g. MSO1 for the yaw rate
   offset f3, which enters r1 only as vy * f3) does not clear the fault when it stays quiet. */
static const float kin_test_size[5 * 4] = FDI_KIN_TEST_SIZES;

const fdi_table_t fdi_kin_table = {
    FDI_TABLE_FORMAT_VERSION,
    {0.01f, 1.0f, 0.7071f, 2.0f},
    ROMO_SIG_COUNT,
    5U,
    4U,
    fdi_romo_signal_names,
    kin_fault_names,
    kin_tests,
    kin_signature,
    kin_iso_class,
    kin_test_size,
    FDI_KIN_EXONERATION_MARGIN,
    1.0f, /* no generator of this table gives sensitivities */
    NULL, /* no calibrated envelope: the kinematic relations hold in any motion */
};
