#!/usr/bin/env bash
# The fleet quality suite's full run (issue 44's instrument; prints numbers, not a test):
#   1. set-up (scripts/bootstrap.sh) and the ECU bindings of the checkout;
#   2. fdi-quality --fleet N: N truth-plant vehicles drawn from the envelope (evaluation seeds 5001.., never a
#      calibration vehicle) x the eight scenarios, each with its fault-free drive and all faults of the table at the
#      required sizes (host_tools/scenarios/fault_sizes.toml), the model plant's same cases beside, then the
#      minimum-detectable-fault search; local processes (FDI_JOBS, default one per core) or a Dask scheduler
#      (FDI_SCHEDULER=tcp://host:8786)                         -> out/fleet/fleet.json, fleet.md, fleet.png
#   (fleet.png: detection/isolation per fault, minimum detectable fault against the required size, false alarms
#   per vehicle, alarm share per scenario; `fdi-quality --replot out/fleet/fleet.json` draws it again.
#   docs/fleet_quality.md and docs/fleet_quality.png are the committed copies of a run.)
# Usage: scripts/fleet_quality.sh [N] [TABLE] [fdi-quality options...]   (N: vehicles, default 27, which with each
#   vehicle and scenario driven fault-free on 3 noise seeds (--repetitions 3) give 6.4 h, more than the false-alarm
#   goal's 5 h; TABLE: romo; e.g. `scripts/fleet_quality.sh 27 romo --ecu adaptive=true --out out/fleet_adaptive`)
# Time: about 2 min of one core per vehicle (1,281 s on 2 cores for 27 with --no-sweep), plus the size sweep where a
#   fault is not masked.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
n="${1:-27}"
table="${2:-romo}"
case "$n" in ''|*[!0-9]*) echo "N: the number of vehicles, a whole number" >&2; exit 2 ;; esac
[ -x .venv/bin/python ] || bash scripts/bootstrap.sh
# this run's output becomes section fleet_quality (or $FDI_RESULTS_NAME) of docs/results.md: scripts/results_doc.py
# runs the script under it
[ -n "${FDI_RESULTS_SECTION:-}" ] || exec .venv/bin/python scripts/results_doc.py "${FDI_RESULTS_NAME:-fleet_quality}" \
  --run --markdown --display "bash scripts/fleet_quality.sh $*" -- bash scripts/fleet_quality.sh "$@"
.venv/bin/python -m pip install -q --no-deps --no-build-isolation -e .
args=(--fleet "$n" --vehicle "$table" --repetitions 3 --out out/fleet "${@:3}")
if [ -n "${FDI_SCHEDULER:-}" ]; then args+=(--scheduler "$FDI_SCHEDULER"); fi
if [ -n "${FDI_JOBS:-}" ]; then args+=(--workers "$FDI_JOBS"); fi
.venv/bin/fdi-quality "${args[@]}"
