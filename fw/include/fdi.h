/*
 * fdi.h - umbrella header of the on-vehicle fault diagnosis library (see fw/README.md).
 * Blocks: fdi_deriv / fdi_svf (filtered derivatives), fdi_obs (observer), fdi_gen (residual generators),
 * fdi_eval (residual evaluation), fdi_iso (isolation), fdi_diag (the diagnoser), fdi_table (exported data).
 */
#ifndef FDI_H
#define FDI_H

#include "fdi_deriv.h"
#include "fdi_diag.h"
#include "fdi_eval.h"
#include "fdi_float.h"
#include "fdi_gen.h"
#include "fdi_iso.h"
#include "fdi_kin_table.h"
#include "fdi_obs.h"
#include "fdi_signals.h"
#include "fdi_status.h"
#include "fdi_svf.h"
#include "fdi_table.h"

#endif /* FDI_H */
