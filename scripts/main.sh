#!/usr/bin/env bash
# The main job, from nothing: set-up, then
#   1. structural analysis of the ROMO model (summary, DM, isolability)   -> out/romo_quasistatic/
#   2. all MSO sets of the grouped model, fault matrices, minimal selections -> out/romo_grouped/
#   3. a simulated drive with the paper's faults f4, f5, f6 and ARR3/ARR4   -> out/fig6/
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
bash scripts/bootstrap.sh
.venv/bin/python -m pip install -q --no-deps --no-build-isolation -e .
echo "== 1. structural analysis"
.venv/bin/fdi-analyze report analysis/models/romo_quasistatic.toml -o out/romo_quasistatic
echo "== 2. MSO sets and selection"
.venv/bin/fdi-analyze select analysis/models/romo_grouped.toml -o out/romo_grouped
echo "== 3. simulated faulty drive (paper Fig. 6)"
.venv/bin/fdi-sim fig6 --out-dir out/fig6
