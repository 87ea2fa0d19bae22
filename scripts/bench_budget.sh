#!/usr/bin/env bash
# What a smaller diagnosis costs and gives up (prints numbers; not a test): for each BUDGET (operations per step, the
# cost unit of `fdi-analyze practical`), the tests that meet the most requirements of the practical selection within
# it (`--budget`), built as the ECU would ship them, next to the table that ships (the anchor, same run):
#   1. a scratch copy of the checkout's tracked files in build/budget/BUDGET/;
#   2. there: fdi-analyze practical --budget BUDGET (the [selection] of its thresholds file), fdi-tune calibrate (the
#      gates of those tests, ~5 min), fdi-analyze export-c (its generated C);
#   3. scripts/bench_fw.sh there: Cortex-M4F instructions per fdi_diag_step on the benchmark drive and the flash of the
#      diagnosis as the ECU links it;
#   4. with --quality: the ECU bindings built from that C and fdi-quality --vehicle romo there (25 faults x 5 scenarios
#      x 3 seeds at the required sizes + 30 min fault-free, ~15 min): its scenario table.
# Usage: scripts/bench_budget.sh [--quality] BUDGET [BUDGET ...]
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
quality=0
if [ "${1:-}" = "--quality" ]; then quality=1; shift; fi
if [ "$#" -eq 0 ]; then echo "usage: scripts/bench_budget.sh [--quality] BUDGET [BUDGET ...]" >&2; exit 2; fi
for b in "$@"; do
  case "$b" in ''|*[!0-9]*) echo "budget $b: operations per step, a whole number" >&2; exit 2 ;; esac
done
[ -x .venv/bin/python ] || bash scripts/bootstrap.sh
py="$top/.venv/bin/python"
# this run's output becomes section bench_budget of docs/results.md: scripts/results_doc.py runs the script under it
[ -n "${FDI_RESULTS_SECTION:-}" ] || exec "$py" scripts/results_doc.py bench_budget --run \
  --display "bash scripts/bench_budget.sh $*" -- bash scripts/bench_budget.sh "$@"
model=analysis/models/romo_grouped.toml
thresholds=analysis/models/romo_thresholds.toml

# m4_summary DIR: the M4 line of the generated ROMO table (the ECU's configuration) and the flash of bench_fw.sh in DIR.
m4_summary() {
  local out
  out="$(cd "$1" && bash scripts/bench_fw.sh 2>&1)"
  echo "$out" | grep -E "^m4: generated ROMO table, sensitivities off" | sed 's/^m4: generated ROMO table, sensitivities off: /  M4 /'
  echo "$out" | grep -E "^ROMO diagnosis as the ECU links it" | sed 's/^/  /'
}

echo "== the table that ships (anchor: the [selection] of $thresholds, fw/vehicles/romo/generated/)"
"$top/.venv/bin/fdi-analyze" practical "$model" --screening analysis/models/romo_screening.json.gz 2>&1 | \
  grep -E "^selected" | sed 's/^/  /'
m4_summary "$top"

for b in "$@"; do
  scr="$top/build/budget/$b"
  echo "== budget $b (scratch copy $scr)"
  rm -rf "$scr"
  mkdir -p "$scr"
  git ls-files -z | xargs -0 cp --parents -t "$scr"
  ln -s "$top/.venv" "$scr/.venv"
  (
    cd "$scr"
    "$top/.venv/bin/fdi-analyze" practical "$model" --screening analysis/models/romo_screening.json.gz --budget "$b" \
      --thresholds "$thresholds" 2>&1 | grep -E "^within the budget|^  MSO" | sed 's/^/  /'
    echo "  calibrating the gates of these tests (fdi-tune calibrate, ~5 min)"
    "$top/.venv/bin/fdi-tune" calibrate "$model" --thresholds "$thresholds" >calibrate.log 2>&1
    "$top/.venv/bin/fdi-analyze" export-c "$model" --thresholds "$thresholds" \
      --fault-sizes host_tools/scenarios/fault_sizes.toml --out fw/vehicles/romo/generated >export.log 2>&1
  )
  m4_summary "$scr"
  if [ "$quality" = 1 ]; then
    echo "  quality suite on this table (ECU bindings built from its C, ~15 min)"
    (
      cd "$scr"
      "$py" setup.py -q build_ext --inplace >build_ext.log 2>&1
      PYTHONPATH="$scr/analysis:$scr/host_tools" "$py" -m fdi_host.quality.cli --vehicle romo --out out/quality-romo \
        >quality.log 2>&1
      awk '/^\| scenario/ {on = 1} on && /^\|/ {print "  " $0} on && !/^\|/ {exit}' out/quality-romo/quality.md
    )
  fi
done
