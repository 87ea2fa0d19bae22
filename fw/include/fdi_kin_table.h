/*
 * fdi_kin_table.h - a hand-made diagnosis table: the four kinematic tests MSO1..MSO4 of Table II over the
 * sensor faults f1..f5 (ax, ay, yaw rate, vx, vy). A stand-in until the analysis exporter writes
 * fw/generated/fdi_romo_table.c/.h; it uses exactly the fdi_table.h types, so it is also the reference
 * example for the exporter.
 *
 *   test  MSO  faults       signals                      generator
 *   0     1    1,3,4,5      ax_m psidot_m vx_m vy_m      FDI_GEN_KIN_X_DERIV
 *   1     2    2,3,4,5      ay_m psidot_m vx_m vy_m      FDI_GEN_KIN_Y_DERIV
 *   2     3    1,2,3,4      ax_m ay_m psidot_m vx_m      FDI_GEN_KIN_ARR3
 *   3     4    1,2,3,5      ax_m ay_m psidot_m vy_m      FDI_GEN_KIN_ARR4
 * Every fault has a unique signature, so every isolability class has one fault.
 * Memory: ~250 bytes of const data (flash).
 */
#ifndef FDI_KIN_TABLE_H
#define FDI_KIN_TABLE_H

#include "fdi_table.h"

extern const fdi_table_t fdi_kin_table;

#endif /* FDI_KIN_TABLE_H */
