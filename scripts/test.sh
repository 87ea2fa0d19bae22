#!/usr/bin/env bash
# Runs every test of the project from nothing: set-up, lint, type check, C library gates, Python tests.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
bash scripts/bootstrap.sh
# Rebuild the native parts of the Python package (cheap when nothing changed).
.venv/bin/python -m pip install -q --no-deps --no-build-isolation -e .
echo "== ruff"; .venv/bin/ruff check analysis host_tools tests fw/bench scripts
echo "== mypy"; .venv/bin/mypy
echo "== fw (C library)"; bash scripts/test_fw.sh
echo "== pytest"; .venv/bin/python -m pytest -q --junitxml=build/pytest-junit.xml
echo "== wheel (built from the checkout, installed in a clean venv, run outside it)"; bash scripts/test_wheel.sh
# every skip with its reason (README: the skips to expect without root or without QEMU)
.venv/bin/python scripts/skip_summary.py build/fw/ctest-junit.xml build/fw-san/ctest-junit.xml build/pytest-junit.xml
