#!/usr/bin/env bash
# Moves constraints.txt to the newest versions the package registry serves: installs the project with its dev
# dependencies, unconstrained, into a fresh temporary venv and writes what it got (pip freeze --all) below the
# file's own comment. Then run `bash scripts/bootstrap.sh` (reinstalls .venv at the new versions),
# `bash scripts/generate.sh` (the generated files, in case the new sympy writes them otherwise) and
# `bash scripts/test.sh`, and commit what changed together. Prints the versions that moved.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
py="${PYTHON:-python3}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$py" -m venv "$work/venv"
"$work/venv/bin/python" -m pip install -q --upgrade pip setuptools wheel
"$work/venv/bin/python" -m pip install -q "$top[dev]"
{ grep '^#' constraints.txt
  "$work/venv/bin/python" -m pip freeze --all --exclude-editable | grep -v -i '^romo-fdi[= @]'
} > "$work/constraints.txt"
echo "versions that moved (< pinned before, > now):"
diff <(grep -v '^#' constraints.txt) <(grep -v '^#' "$work/constraints.txt") | grep '^[<>]' || echo "  none"
cp "$work/constraints.txt" constraints.txt
echo "constraints.txt: $(grep -vc '^#' constraints.txt) pinned distributions"
