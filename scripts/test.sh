#!/usr/bin/env bash
# Runs every test of the project from nothing: set-up, lint, type check, C library gates, Python tests.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
bash scripts/bootstrap.sh
# Rebuild the native parts of the Python package (cheap when nothing changed).
.venv/bin/python -m pip install -q --no-deps --no-build-isolation -e .
echo "== ruff"; .venv/bin/ruff check analysis host_tools tests
echo "== mypy"; .venv/bin/mypy
echo "== fw (C library)"; bash scripts/test_fw.sh
echo "== pytest"; .venv/bin/python -m pytest -q
