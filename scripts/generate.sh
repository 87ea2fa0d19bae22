#!/usr/bin/env bash
# Regenerates every committed generated file from its source (tests fail when a committed copy is stale):
#   fw/generated/fdi_romo_table.{h,c}   <- analysis/models/romo_grouped.toml + romo_thresholds.toml
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
[ -x .venv/bin/fdi-analyze ] || bash scripts/bootstrap.sh
.venv/bin/fdi-analyze export-c analysis/models/romo_grouped.toml \
  --thresholds analysis/models/romo_thresholds.toml --out fw/generated
