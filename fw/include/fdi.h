/*
 * fdi.h - umbrella header of the on-vehicle fault diagnosis library (see fw/README.md).
 * Blocks: fdi_deriv / fdi_svf (filtered derivatives), fdi_obs (observer), fdi_gen (residual generators through
 * descriptors), fdi_eval (residual evaluation), fdi_est (a residual's slow offset), fdi_iso (isolation), fdi_diag
 * (the diagnoser), fdi_table (exported data), fdi_frame (the signal frame). A vehicle's signals, generators and
 * table come from its own target (fw/vehicles/<vehicle>/).
 */
#ifndef FDI_H
#define FDI_H

#include "fdi_deriv.h"
#include "fdi_diag.h"
#include "fdi_est.h"
#include "fdi_eval.h"
#include "fdi_float.h"
#include "fdi_frame.h"
#include "fdi_gen.h"
#include "fdi_iso.h"
#include "fdi_obs.h"
#include "fdi_static_assert.h"
#include "fdi_status.h"
#include "fdi_svf.h"
#include "fdi_table.h"

#endif /* FDI_H */
