#!/usr/bin/env bash
# The main job: set up from nothing, then run the analysis of the ROMO model (summary, JSON/Markdown report
# and plots under out/romo_quasistatic/).
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
bash scripts/bootstrap.sh
.venv/bin/python -m pip install -q --no-deps --no-build-isolation -e .
.venv/bin/fdi-analyze report analysis/models/romo_quasistatic.toml -o out/romo_quasistatic
