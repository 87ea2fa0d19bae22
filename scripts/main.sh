#!/usr/bin/env bash
# The main job, from nothing: set-up, then
#   1. structural analysis of the ROMO model (summary, DM, isolability)   -> out/romo_quasistatic/
#   2. all MSO sets of the grouped model, fault matrices, minimal selections -> out/romo_grouped/
#   3. generated C: diagnosis tables + CAN codec (scripts/generate.sh)     -> fw/vehicles/*/generated/
#      and the generator report (per test: residual, causality, fault sizes) -> out/romo_grouped/generators.md
#   4. build: the C library and ECU (CMake, build/main) and the Python bindings (pip install -e .)
#   5. a simulated drive with the paper's faults f4, f5, f6 and ARR3/ARR4   -> out/fig6/
#   6. a drive with a sequence of injected faults LIVE over the bus (vcan where the kernel has AF_CAN,
#      otherwise python-can udp_multicast in a private network namespace): simulator, ECU process and
#      monitor as separate processes; prints the score table             -> out/live/
# FDI_MAIN_TABLE selects the ECU's diagnosis table for step 6: romo (default; the generated residual generators of
# the practical selection, [selection] of analysis/models/romo_thresholds.toml) or kin (the hand-written kinematic
# tests MSO1..4).
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
bash scripts/bootstrap.sh
.venv/bin/python -m pip install -q --no-deps --no-build-isolation -e .
echo "== 1. structural analysis"
.venv/bin/fdi-analyze report analysis/models/romo_quasistatic.toml -o out/romo_quasistatic
echo "== 2. MSO sets and selection"
.venv/bin/fdi-analyze select analysis/models/romo_grouped.toml -o out/romo_grouped
echo "== 3. generated C (diagnosis table, CAN codec)"
bash scripts/generate.sh
echo "== 4. build (C library + ECU, Python bindings)"
cmake -S . -B build/main -DCMAKE_BUILD_TYPE=Release -DFDI_BUILD_TESTS=OFF -DFDI_BUILD_BENCH=OFF >/dev/null
cmake --build build/main -j "${FDI_JOBS:-2}" >/dev/null
.venv/bin/python -m pip install -q --no-deps --no-build-isolation -e .
echo "== 5. simulated faulty drive (paper Fig. 6)"
.venv/bin/fdi-sim fig6 --out-dir out/fig6
echo "== 6. live drive over the bus: f4 (vx sensor), f22 (wheel-1 speed sensor), f10 (wheel-1 motor torque), f6 (wheel-1 steering offset), f11 (wheel-2 motor torque)"
# Each fault at its required size (host_tools/scenarios/fault_sizes.toml [requirement]) lasts 5 s and the next
# starts 8 s later: the ECU ends an isolation episode 3 s after the last alarm (fw/include/fdi_diag.h). The drive
# ends 3 s after the last fault (the monitor's scoring grace).
.venv/bin/fdi-live --scenario fig6 --no-scenario-faults --duration 65 --vehicle "${FDI_MAIN_TABLE:-romo}" \
  --fault f4@5s:0.6:end=10s --fault f22@18s:3.0:end=23s --fault f10@31s:150:end=36s --fault f6@44s:0.06:end=49s \
  --fault f11@57s:150:end=62s \
  --out-dir out/live
