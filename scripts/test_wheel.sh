#!/usr/bin/env bash
# The wheel outside the checkout: build it from a copy of the checkout, install it into a clean venv in a
# temporary folder (its dependencies at the versions of constraints.txt), and run the command lines there with
# their defaults (shipped models, scenarios and DBC, the compiled ECU bindings); the shipped files are compared byte
# for byte with their sources. ~1-2 min (two C extensions; the dependencies come from pip's cache after the first
# run). The newest versions the registry serves are tried by scripts/update_constraints.sh.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
py="${PYTHON:-python3}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# A copy of the sources, so that no earlier build/ of the checkout can slip into the wheel.
tar -C "$top" --exclude=./.venv --exclude=./build --exclude='./build-*' --exclude=./out --exclude=./.git \
    --exclude='*.so' --exclude='*.egg-info' --exclude=__pycache__ --exclude='.*_cache' -cf - . | \
    (mkdir -p "$work/src" && tar -C "$work/src" -xf -)
"$top/.venv/bin/python" -m pip wheel -q --no-deps --no-build-isolation -w "$work/dist" "$work/src"
wheel="$(ls "$work"/dist/romo_fdi-*.whl)"
echo "built $(basename "$wheel") ($(du -k "$wheel" | cut -f1) kB)"

"$py" -m venv "$work/venv"
"$work/venv/bin/python" -m pip install -q -c "$top/constraints.txt" "$wheel"
bin="$work/venv/bin"
mkdir "$work/run" && cd "$work/run"

# what the wheel holds: both extensions, the shipped files (byte for byte their sources), the license
"$bin/python" - "$top" <<'EOF'
import importlib.metadata as md
import sys
from pathlib import Path

from fdi_analysis import resources as ra
from fdi_host import resources as rh

top = Path(sys.argv[1])
import importlib.util

from fdi_host.vehicle import plugin_module, shipped_vehicles

# the MSO engine, and the shipped vehicles' plugins (the C ECU core with each vehicle's diagnosis)
for ext in ("fdi_analysis.mso._core", *(plugin_module(v) for v in shipped_vehicles())):
    spec = importlib.util.find_spec(ext)
    assert spec is not None and "site-packages" in str(spec.origin), f"{ext}: not in the wheel"
for d in (*ra.PACKAGE_DATA, *rh.PACKAGE_DATA):
    here = d.path()
    assert "site-packages" in str(here), f"{d.source}: read from {here}, not from the installed package"
    shipped = sorted(p.name for p in here.glob(d.pattern))
    sources = d.sources(top)
    assert shipped == [p.name for p in sources], f"{d.source}: wheel has {shipped}"
    for p in sources:
        assert (here / p.name).read_bytes() == p.read_bytes(), f"{p}: the wheel's copy differs"
meta = md.metadata("romo-fdi")
assert meta["License-Expression"] == "MIT", meta["License-Expression"]
assert any(str(f).endswith("LICENSE") for f in md.files("romo-fdi")), "no LICENSE in the wheel"
assert meta["Version"] == (top / "VERSION").read_text().strip()
print(f"wheel contents ok: version {meta['Version']}, license MIT, shipped files equal their sources")
EOF

t() { timeout 300 "$@"; }  # a hung program fails the test instead of CI
for cli in fdi-analyze fdi-sim fdi-ecu fdi-monitor fdi-replay fdi-live fdi-quality fdi-tune; do
  t "$bin/$cli" --version >/dev/null
done
t "$bin/fdi-analyze" report romo_quasistatic -o report | grep "detectable faults: 25/25"
t "$bin/fdi-analyze" mso romo_grouped --workers 1 --no-progress > mso.txt && grep "MSO sets (complete)" mso.txt
t "$bin/fdi-analyze" select three_tank --workers 1 --no-progress -o select > select.txt  # without python-sat
grep "optimal B" select.txt
t "$bin/fdi-sim" --list > list.txt 2> list_err.txt; grep -q fig6 list.txt; test ! -s list_err.txt
t "$bin/fdi-sim" --scenario fig6 --duration 12 --out logs/fig6.blf --quiet
t "$bin/fdi-sim" --scenario cornering --no-scenario-faults --fault f10@3s:-120 --duration 8 --out logs/f10.blf --quiet
t "$bin/fdi-replay" logs/fig6.blf --offline --truth logs/fig6.truth.json --out-dir replay > replay.txt
grep "^offline" replay.txt
t "$bin/fdi-replay" logs --workers 2 --out-dir fleet --quiet > fleet.txt
grep "2 of 2 logs" fleet.txt
test -s fleet/fleet.md
"$bin/python" -c "import os; open('bad.blf', 'wb').write(b'LOGG' + os.urandom(400))"
rc=0; t "$bin/fdi-replay" bad.blf --offline 2> err.txt || rc=$?
[ "$rc" -eq 1 ] && [ "$(wc -l < err.txt)" -eq 1 ] || { echo "bad log: exit $rc, stderr:"; cat err.txt; exit 1; }
rc=0; t "$bin/fdi-replay" logs --scheduler tcp://127.0.0.1:8786 2> err.txt || rc=$?  # Dask is an extra
[ "$rc" -eq 1 ] && grep -q "pip install 'romo-fdi\[fleet\]'" err.txt || { echo "no Dask: exit $rc"; cat err.txt; exit 1; }
echo "wheel smoke test passed (in $work/run, outside the checkout)"
