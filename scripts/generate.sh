#!/usr/bin/env bash
# Regenerates every committed generated file from its source (tests fail when a committed copy is stale):
#   fw/generated/fdi_romo_table.{h,c}, fdi_romo_generators.{h,c}   <- analysis/models/romo_grouped.toml +
#     romo_thresholds.toml + fault sizes;  fdi_kin_calibration.h <- simulated drives;  can/ <- dbc/romo.dbc
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
[ -x .venv/bin/fdi-analyze ] || bash scripts/bootstrap.sh
# analysis/models/romo_thresholds.toml [generated]  <- fault-free simulated drives, their CAN frames as the ECU's
#   steps see them (fdi_host.can.ecu_view), through the generators (~1.5 min; checked by test_calibration_current.py)
.venv/bin/fdi-tune calibrate analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml
# host_tools/scenarios/fault_sizes.toml [per_test.*]  <- step-fault sweep through the generators in cornering, the
# pairs it leaves without a size in the other scenarios [per_test_scenario.*] (~25 min; only with FDI_SWEEP_SIZES=1;
# tests/analysis/test_residual_faults.py checks the committed sizes against the thresholds);
# then analysis/models/romo_thresholds.toml [augment]  <- tests added for the faults that no test of the structural
# selection detects within its limit (~1 min); when that changed the tests, calibrate and sweep again
if [ "${FDI_SWEEP_SIZES:-0}" = 1 ]; then
  sweep_sizes() {
    .venv/bin/fdi-tune fault-sizes analysis/models/romo_grouped.toml \
      --thresholds analysis/models/romo_thresholds.toml --sizes host_tools/scenarios/fault_sizes.toml
  }
  augment_tests() { sed -n '/^\[augment\]/,/^\]/p' analysis/models/romo_thresholds.toml | grep -v '^ *#' || true; }
  sweep_sizes
  tests_before="$(augment_tests)"
  .venv/bin/fdi-tune augment analysis/models/romo_grouped.toml \
    --thresholds analysis/models/romo_thresholds.toml --sizes host_tools/scenarios/fault_sizes.toml
  if [ "$(augment_tests)" != "$tests_before" ]; then
    .venv/bin/fdi-tune calibrate analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml
    sweep_sizes
  fi
fi
# fw/generated/fdi_romo_table.{h,c}, fdi_romo_generators.{h,c}  <- model + thresholds (realizable MSOs only)
#   + the per-test fault sizes (which quiet tests may exonerate which fault); not committed: the generator report
#   out/romo_grouped/generators.{md,json,png} (per test: residual equation, causality, inputs, stated fault sizes)
.venv/bin/fdi-analyze export-c analysis/models/romo_grouped.toml \
  --thresholds analysis/models/romo_thresholds.toml --fault-sizes host_tools/scenarios/fault_sizes.toml \
  --out fw/generated --report out/romo_grouped
# fw/generated/fdi_kin_calibration.h  <- the hand-written kinematic table's variances and reaction sizes from
#   simulated drives through the C ECU core (~4 min)
.venv/bin/fdi-tune kin-calibration --out fw/generated/fdi_kin_calibration.h
# fw/generated/can/romo_can.{h,c}, romo_can_e2e.h   <- dbc/romo.dbc (cantools generate_c_source + E2E data IDs)
.venv/bin/python fw/ecu/tools/gen_romo_can.py --dbc dbc/romo.dbc --out fw/generated/can
