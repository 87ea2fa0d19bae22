#!/usr/bin/env bash
# Regenerates every committed generated file from its source (tests fail when a committed copy is stale):
#   analysis/models/romo_thresholds.toml [selection], [generated], [estimation]  <- the screening of the candidates +
#     the truth-plant calibration fleet;
#   fw/vehicles/romo/generated/fdi_romo_{table,generators,signals}.{h,c}  <- analysis/models/romo_grouped.toml +
#     romo_thresholds.toml + fault sizes;  fdi_kin_calibration.h <- simulated drives;
#   fw/vehicles/romo/generated/can/  <- dbc/romo.dbc (cantools code + the ECU core's bus description);
#   fw/include/generated/fdi_capacity.h  <- fdi_analysis.export.capacity (the library's capacities, one source);
#   host_tools/fdi_host/ecu/fdi_py_seam.h  <- fdi_analysis.export.seam (the host ECU's Python/C questions, named);
#   the shipped vehicles' plugin glue fdi_<vehicle>_plugin.c  <- host_tools/vehicles/<vehicle>.toml (fdi-vehicle glue);
#   fw/vehicles/three_tank/generated/  <- analysis/models/three_tank.toml + three_tank_thresholds.toml + fault sizes,
#     whose generated tables come from drives of the generic simulator (host_tools/scenarios/three_tank.toml)
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
[ -x .venv/bin/fdi-analyze ] || bash scripts/bootstrap.sh
romo=fw/vehicles/romo/generated
tank=fw/vehicles/three_tank/generated
# fw/include/generated/fdi_capacity.h  <- the capacities' defaults and ranges (CMake's cache options read them too)
.venv/bin/python -m fdi_analysis.export.capacity --out fw/include/generated/fdi_capacity.h
# host_tools/fdi_host/ecu/fdi_py_seam.h  <- the questions the ctypes bindings ask the host ECU library, by name
.venv/bin/python -m fdi_analysis.export.seam --out host_tools/fdi_host/ecu/fdi_py_seam.h
for vehicle in host_tools/vehicles/*.toml; do  # the shipped vehicles' plugin glue (setup.py builds the plugins)
  .venv/bin/fdi-vehicle glue "$(basename "$vehicle" .toml)" >/dev/null
done
# analysis/models/romo_screening.json.gz  <- every realizable candidate's fault-to-noise ratio at the required fault
#   sizes along the fault-free drives, sigmas over the calibration's noise seeds (~22 min on 2 workers; only with
#   FDI_SCREEN=1; tests/analysis/test_screening_current.py checks that its criterion is this code's)
if [ "${FDI_SCREEN:-0}" = 1 ]; then
  .venv/bin/fdi-tune screen analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml \
    --sizes host_tools/scenarios/fault_sizes.toml --out analysis/models/romo_screening.json.gz
fi
# analysis/models/romo_thresholds.toml [selection]  <- the practical selection from the screening (MaxSAT, ~15 s;
#   the report in out/practical/)
.venv/bin/fdi-analyze practical analysis/models/romo_grouped.toml --screening analysis/models/romo_screening.json.gz \
  --thresholds analysis/models/romo_thresholds.toml -o out/practical
# analysis/models/romo_thresholds.toml [generated], [estimation], [envelope_limits]  <- the fault-free drives of the
#   truth-plant calibration vehicles 1 .. 12 in every fleet scenario, their CAN frames as the ECU's steps see them
#   (fdi_host.can.ecu_view), each test with its on-line estimator and adaptive threshold (what it estimates, its sigma;
#   fdi_host.tuning.fleet_calibration; ~7 min; checked by test_calibration_current.py)
.venv/bin/fdi-tune calibrate analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml \
  --fleet 12
# host_tools/scenarios/fault_sizes.toml [per_test.*]  <- step-fault sweep through the generators in cornering, the
# pairs it leaves without a size in the other scenarios [per_test_scenario.*] (~25 min; only with FDI_SWEEP_SIZES=1;
# extra information next to the [requirement] sizes; tests/analysis/test_residual_faults.py checks the committed
# sizes against the thresholds)
if [ "${FDI_SWEEP_SIZES:-0}" = 1 ]; then
  .venv/bin/fdi-tune fault-sizes analysis/models/romo_grouped.toml \
    --thresholds analysis/models/romo_thresholds.toml --sizes host_tools/scenarios/fault_sizes.toml
fi
# fw/vehicles/romo/generated/fdi_romo_{table,generators,signals}.{h,c}  <- model + thresholds (realizable MSOs only)
#   + the per-test fault sizes (which quiet tests may exonerate which fault); not committed: the generator report
#   out/romo_grouped/generators.{md,json,png} (per test: residual equation, causality, inputs, stated fault sizes)
.venv/bin/fdi-analyze export-c analysis/models/romo_grouped.toml \
  --thresholds analysis/models/romo_thresholds.toml --fault-sizes host_tools/scenarios/fault_sizes.toml \
  --out "$romo" --report out/romo_grouped
# fw/vehicles/romo/generated/fdi_kin_calibration.h  <- the hand-written kinematic table's variances and reaction
#   sizes from simulated drives through the C ECU core (~4 min)
.venv/bin/fdi-tune kin-calibration --out "$romo/fdi_kin_calibration.h"
# fw/vehicles/romo/generated/can/romo_can.{h,c}, fdi_romo_bus.{h,c}  <- dbc/romo.dbc (cantools generate_c_source;
#   the bus of the ECU core: messages, their frame signals and decoding, the diagnosis frame)
.venv/bin/fdi-analyze export-can analysis/models/romo_grouped.toml --dbc dbc/romo.dbc --out "$romo/can"
# analysis/models/three_tank_thresholds.toml [generated], [observer]  <- fault-free drives of the generic simulator
#   (~1 min); host_tools/scenarios/three_tank_fault_sizes.toml [per_test.*]  <- the step-fault sweep (~1 min)
.venv/bin/fdi-tune calibrate --vehicle three_tank    # its thresholds, scenario and fault sizes: host_tools/vehicles
.venv/bin/fdi-tune fault-sizes --vehicle three_tank
# fw/vehicles/three_tank/generated/fdi_three_tank_{table,generators,signals}.{h,c}
.venv/bin/fdi-analyze export-c analysis/models/three_tank.toml \
  --thresholds analysis/models/three_tank_thresholds.toml --fault-sizes host_tools/scenarios/three_tank_fault_sizes.toml \
  --out "$tank" --name fdi_three_tank_table
