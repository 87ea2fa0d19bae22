/* main.c - installed-package smoke test: the generic core with the vehicle targets (fdi::romo_can: validate the
   shipped kinematic table, init a diagnoser and step it once, init the ECU core on the ROMO bus; fdi::three_tank:
   validate its table and init a diagnoser with the defaults). Built with FDI_CONSUMER_MISMATCH (capacities other
   than the library's, CMakeLists.txt), it succeeds only when fdi_diag_init refuses it with FDI_BAD_LAYOUT. */
#include <stdio.h>
#include <string.h>

#include "fdi.h"
#include "fdi_kin_table.h"
#include "fdi_romo_ecu.h"
#include "fdi_romo_kin.h"
#include "fdi_romo_signals.h"
#include "fdi_three_tank_table.h"

#ifdef FDI_CONSUMER_MISMATCH
int main(void)
{
    static fdi_diag_t d;
    fdi_diag_config_t c;
    fdi_diag_layout_t lib;
    const fdi_diag_layout_t here = fdi_diag_layout_here();
    int rc = 1;
    if ((fdi_diag_config_default(&c, &fdi_three_tank_table) == FDI_OK) && (fdi_diag_layout(&lib) == FDI_OK))
    {
        const fdi_status_t st = fdi_diag_init(&d, &c);
        printf("consumer: FDI_DIAG_MAX_TESTS %u (library %u), sizeof(fdi_diag_t) %u (library %u): fdi_diag_init "
               "returned %d\n",
               (unsigned)here.max_tests, (unsigned)lib.max_tests, (unsigned)here.size_diag, (unsigned)lib.size_diag,
               (int)st);
        if (st == FDI_BAD_LAYOUT)
        {
            printf("consumer: mismatching layout refused (FDI_BAD_LAYOUT)\n");
            rc = 0;
        }
    }
    return rc;
}
#else
int main(void)
{
    static fdi_ecu_t ecu;
    fdi_ecu_config_t ecfg;
    fdi_diag_t d;
    fdi_frame_t in;
    fdi_diag_config_t c;
    int rc = 1;
    memset(&in, 0, sizeof in);
    memset(&c, 0, sizeof c);
    c.table = &fdi_kin_table;
    c.gen_param[FDI_ROMO_KIN_PARAM_D_X] = FDI_ROMO_KIN_D_X;
    c.gen_param[FDI_ROMO_KIN_PARAM_D_Y] = FDI_ROMO_KIN_D_Y;
    c.cusum_k = 1.5f;
    c.cusum_h = 150.0f;
    c.set_count = 10U;
    c.clear_count = 100U;
    c.warmup_steps = 320U;
    c.reentry_steps = 50U;
    c.mode = FDI_ISO_EXONERATION;
    c.noise_allowance = 3.0f;
    c.episode_clear_steps = 300U;
    if ((fdi_table_check(&fdi_kin_table) == FDI_OK) && (fdi_diag_init(&d, &c) == FDI_OK) &&
        (fdi_diag_step(&d, &in, ROMO_SIGM_ALL) == FDI_OK) &&
        (fdi_romo_ecu_config_default(&ecfg, &fdi_kin_table) == FDI_OK) && (fdi_ecu_init(&ecu, &ecfg) == FDI_OK) &&
        (fdi_diag_config_default(&c, &fdi_three_tank_table) == FDI_OK) && (fdi_diag_init(&d, &c) == FDI_OK))
    {
        printf("consumer: fdi found and linked, %u tests, ROMO bus of %u messages, three-tank table of %u tests\n",
               (unsigned)fdi_kin_table.n_tests, (unsigned)fdi_romo_bus.n_msgs, (unsigned)fdi_three_tank_table.n_tests);
        rc = 0;
    }
    return rc;
}
#endif
