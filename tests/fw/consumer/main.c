/* main.c - installed-library smoke test: validate the shipped table, init a diagnoser, step it once. */
#include <stdio.h>
#include <string.h>

#include "fdi.h"

int main(void)
{
    fdi_diag_t d;
    fdi_inputs_t in;
    fdi_diag_config_t c;
    int rc = 1;
    memset(&in, 0, sizeof in);
    c.table = &fdi_kin_table;
    c.d_x = 1.2f;
    c.d_y = 0.3f;
    c.cusum_k = 1.5f;
    c.cusum_h = 150.0f;
    c.set_count = 10U;
    c.clear_count = 100U;
    c.warmup_steps = 320U;
    c.mode = FDI_ISO_EXONERATION;
    c.iso_settle_steps = 300U;
    c.episode_clear_steps = 300U;
    if ((fdi_table_check(&fdi_kin_table) == FDI_OK) && (fdi_diag_init(&d, &c) == FDI_OK) &&
        (fdi_diag_step(&d, &in, FDI_SIGM_ALL) == FDI_OK))
    {
        printf("consumer: fdi found and linked, %u tests\n", (unsigned)fdi_kin_table.n_tests);
        rc = 0;
    }
    return rc;
}
