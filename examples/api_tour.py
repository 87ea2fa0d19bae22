"""The structural analysis from Python, as in a notebook: load a model, ask it, draw into your own axes.

    python examples/api_tour.py [OUT_DIR]        (default out/examples; CI runs it: tests/analysis/test_api.py)

In a notebook, leave out the `matplotlib.use` line: the figures then show inline.
"""

from __future__ import annotations

import itertools
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # a script writes files
import matplotlib.pyplot as plt

import fdi_analysis as fa

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out/examples")
out.mkdir(parents=True, exist_ok=True)

# A shipped model by name (or any .toml model file, or an FDT structure .json).
m = fa.DiagnosisModel.load("romo_grouped")
print(m)

dm = m.dm()
print(f"structural redundancy {dm.redundancy}; M+ holds {len(dm.overdetermined)} of {len(m.equations)} equations")

summary = m.mso_summary(workers=1)  # counted in C, without keeping the sets
print(f"{summary.count:,} MSO sets, {len(summary.signatures):,} distinct fault signatures")
for t in itertools.islice(m.msos(), 3):  # streamed one by one
    print(f"  MSO with {len(t.equations)} equations, faults {', '.join(t.faults) or '-'}")

iso = m.isolability()
print("not isolable from each other:", ", ".join(f"{a}/{b}" for a, b in iso.non_isolable_pairs()))

sel = m.select(method="B", time_limit_s=30)
print(f"optimal selection (method B): {len(sel.tests)} tests, {sel.cost} unknowns, proven {sel.proven}")
for t in sel.tests:
    print(f"  {t.label:8s} {t.cost:3d} unknowns  faults {' '.join(t.faults)}")

fig, (left, right) = plt.subplots(1, 2, figsize=(14, 6))
iso.plot(ax=left)  # every plot draws into the axes it is given and returns the figure
sel.plot(ax=right)
fig.savefig(out / "api_tour.png", dpi=90)
print(f"wrote {out / 'api_tour.png'}")

# Fault Diagnosis Toolbox users hold incidence matrices: the same object from X, F (and Z).
tank = fa.DiagnosisModel.from_matrices(
    X=[[1, 1, 0], [0, 1, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
    F=[[1, 0, 0], [0, 1, 0], [0, 0, 0], [0, 0, 0], [0, 0, 1]],
    equations=["e1", "e2", "m1", "m2", "m3"],
    faults=["fa", "fb", "fc"],
    name="chain",
)
print(f"{tank}: {sum(1 for _ in tank.msos())} MSO sets, isolability classes {tank.isolability().classes}")
