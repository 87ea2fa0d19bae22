"""The generator report of an exported table: per test its MSO set, residual equation, causality, inputs,
operating domain, gate, and the measured fault responses (the stated sizes of the fault-size file), as
Markdown, JSON and a plot, for the diagnosis engineer who reviews what goes on board."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from fdi_analysis.export.fault_sizes import FaultSizes
from fdi_analysis.residuals.generator import Generator


@dataclass(frozen=True)
class Response:
    """How a test responds to one fault of its signature."""

    fault: str
    size: float | None  # stated size (None: not detectable in practice, or not swept)
    scenario: str  # "" = the fault-size sweep's own scenario (3 s steps); else the manoeuvre it is stated in
    limit: float | None  # the fault's physical limit
    note: str = ""  # why there is no size

    def text(self) -> str:
        if self.size is None:
            return "n.d."
        return f"{self.size:g}" + (f" ({self.scenario})" if self.scenario else "")


@dataclass(frozen=True)
class TestRow:
    name: str
    equations: tuple[str, ...]
    residual_equation: str
    causality: str
    inputs: tuple[str, ...]
    domain: str
    sigma: float
    gate: float
    responses: tuple[Response, ...]
    note: str = ""  # a causality considered and not taken, and why


def rows(gens: Sequence[Generator], sigmas: Sequence[float], gate: float, sizes: FaultSizes | None,
         limits: Mapping[str, float]) -> list[TestRow]:
    out = []
    for g, s in zip(gens, sigmas, strict=True):
        resp = []
        for f in g.faults:
            v = sizes.per_test.get(f, {}).get(g.name) if sizes is not None else None
            other = sizes.elsewhere.get(f, {}).get(g.name) if sizes is not None else None
            if isinstance(v, int | float):
                resp.append(Response(f, float(v), "", limits.get(f)))
            elif other is not None:
                resp.append(Response(f, other[1], other[0], limits.get(f)))
            else:
                resp.append(Response(f, None, "", limits.get(f), v if isinstance(v, str) else "not swept"))
        causality = g.causality().split("; domain ", 1)[0]  # the domain has a field of its own
        out.append(TestRow(g.name, g.equations, g.residual_equation, causality, g.knowns, g.domain(), s, gate,
                           tuple(resp), g.note))
    return out


def markdown(table: str, test_rows: Sequence[TestRow], sizes_source: str) -> str:
    lines = [f"# Residual generators of {table}", "",
             "Fault responses: the stated size of each fault of the test's signature (its unit as in Table I), from "
             f"`{sizes_source}` (`fdi-tune fault-sizes`): a 3 s step in the sweep's scenario (steady cornering), "
             "or, in parentheses, the manoeuvre that excites a pair steady cornering leaves silent (a step from "
             "4 s to the end of that drive); n.d. = not detectable within the fault's physical limit. Each stated "
             "size alarmed with 8 noise seeds in the sweep; tests/analysis/test_residual_faults.py checks it with "
             "another.", ""]
    lines += ["| test | residual equation | inputs | sigma | gate | fault responses |", "|---|---|---|---|---|---|"]
    for r in test_rows:
        resp = ", ".join(f"{x.fault} {x.text()}" for x in r.responses)
        lines.append(f"| {r.name} | {r.residual_equation} | {len(r.inputs)} | {r.sigma:.3g} | {r.gate:g} sigma | "
                     f"{resp} |")
    for r in test_rows:
        lines += ["", f"## {r.name}", "", f"- MSO set: {' '.join(r.equations)}", f"- causality: {r.causality}",
                  *([f"- not taken: {r.note}"] if r.note else []),
                  f"- inputs: {', '.join(r.inputs)}", f"- operating domain: {r.domain}",
                  f"- sigma {r.sigma:.4g}, alarm at {r.gate:g} sigma or CUSUM", "",
                  "| fault | stated size | limit | scenario | note |", "|---|---|---|---|---|"]
        for x in r.responses:
            lim = "-" if x.limit is None else f"{x.limit:g}"
            size = "n.d." if x.size is None else f"{x.size:g}"
            where = x.scenario or ("sweep (cornering)" if x.size is not None else "-")
            lines.append(f"| {x.fault} | {size} | {lim} | {where} | {x.note} |")
    return "\n".join(lines) + "\n"


def to_json(table: str, test_rows: Sequence[TestRow]) -> str:
    doc: dict[str, Any] = {"table": table, "tests": [asdict(r) for r in test_rows]}
    return json.dumps(doc, indent=1) + "\n"


def plot(test_rows: Sequence[TestRow], faults: Sequence[str], path: Path) -> None:
    """Stated size / physical limit per (test, fault): log colour scale, hatched where stated in another
    manoeuvre, x where not detectable, white off the signature."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from matplotlib.patches import Rectangle

    grid = np.full((len(test_rows), len(faults)), np.nan)
    fig, ax = plt.subplots(figsize=(1.2 + 0.42 * len(faults), 1.2 + 0.45 * len(test_rows)))
    for i, r in enumerate(test_rows):
        for x in r.responses:
            j = faults.index(x.fault)
            if x.size is not None and x.limit:
                grid[i, j] = math.log10(x.size / x.limit)
            if x.size is None:
                ax.text(j, i, "x", ha="center", va="center", color="k")
            elif x.scenario:
                ax.add_patch(Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False, hatch="//", lw=0))
    im = ax.imshow(grid, cmap="viridis", vmin=-4.0, vmax=0.0, aspect="auto")
    ax.set_xticks(range(len(faults)), faults, rotation=90)
    ax.set_yticks(range(len(test_rows)), [r.name for r in test_rows])
    ax.set_title("stated fault size / physical limit per test\n(hatched: stated in another manoeuvre; "
                 "x: not detectable; white: not in the signature)", fontsize=10)
    fig.colorbar(im, ax=ax, label="log10(size / limit)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write(out: Path, table: str, test_rows: Sequence[TestRow], faults: Sequence[str], sizes_source: str) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    md, js, png = out / "generators.md", out / "generators.json", out / "generators.png"
    md.write_text(markdown(table, test_rows, sizes_source), encoding="utf-8")
    js.write_text(to_json(table, test_rows), encoding="utf-8")
    plot(test_rows, faults, png)
    return [md, js, png]
