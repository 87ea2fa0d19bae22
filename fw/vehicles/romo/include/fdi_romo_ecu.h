/*
 * fdi_romo_ecu.h - the ECU core (fdi_ecu.h) on the ROboMObil bus: the generic defaults for a ROMO table on the
 * bus generated from dbc/romo.dbc (generated/can/fdi_romo_bus.h), with the run-time parameters of the
 * hand-written kinematic generators (fdi_romo_kin.h: velocity sensor position d_x, d_y of the ROMO model).
 * Cost: none at run time. Memory: none.
 */
#ifndef FDI_ROMO_ECU_H
#define FDI_ROMO_ECU_H

#include "fdi_ecu.h"
#include "fdi_romo_bus.h"

/* fdi_ecu_config_default(cfg, table, &fdi_romo_bus) with gen_param[FDI_ROMO_KIN_PARAM_D_X/_D_Y] set to
   FDI_ROMO_KIN_D_X/_D_Y. Statuses as fdi_ecu_config_default. */
fdi_status_t fdi_romo_ecu_config_default(fdi_ecu_config_t *cfg, const fdi_table_t *table);

#endif /* FDI_ROMO_ECU_H */
