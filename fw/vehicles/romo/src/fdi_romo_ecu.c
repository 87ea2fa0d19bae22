/* fdi_romo_ecu.c - ECU defaults on the ROMO bus (see fdi_romo_ecu.h). */
#include "fdi_romo_ecu.h"

#include <stddef.h>

#include "fdi_romo_kin.h"

fdi_status_t fdi_romo_ecu_config_default(fdi_ecu_config_t *cfg, const fdi_table_t *table)
{
    const fdi_status_t st = fdi_ecu_config_default(cfg, table, &fdi_romo_bus);
    if (st == FDI_OK)
    {
        cfg->diag.gen_param[FDI_ROMO_KIN_PARAM_D_X] = FDI_ROMO_KIN_D_X;
        cfg->diag.gen_param[FDI_ROMO_KIN_PARAM_D_Y] = FDI_ROMO_KIN_D_Y;
    }
    return st;
}
