/*
 * fdi_kin_table.h - a hand-made diagnosis table of the ROboMObil: the four kinematic tests MSO1..MSO4 of
 * Table II over the sensor faults f1..f5 (ax, ay, yaw rate, vx, vy), with the hand-written generators of
 * fdi_romo_kin.h. It uses exactly the fdi_table.h types of the generated table (generated/fdi_romo_table.c),
 * so it is also the reference example for the exporter.
 *
 *   test  MSO  faults       signals                      generator
 *   0     1    1,3,4,5      ax_m psidot_m vx_m vy_m      fdi_romo_kin_x_deriv
 *   1     2    2,3,4,5      ay_m psidot_m vx_m vy_m      fdi_romo_kin_y_deriv
 *   2     3    1,2,3,4      ax_m ay_m psidot_m vx_m      fdi_romo_kin_arr3
 *   3     4    1,2,3,5      ax_m ay_m psidot_m vy_m      fdi_romo_kin_arr4
 * Every fault has a unique signature, so every isolability class has one fault.
 * Memory: const data (flash) only, its size printed by scripts/bench_fw.sh.
 */
#ifndef FDI_KIN_TABLE_H
#define FDI_KIN_TABLE_H

#include "fdi_table.h"

extern const fdi_table_t fdi_kin_table;

#endif /* FDI_KIN_TABLE_H */
