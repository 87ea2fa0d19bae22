"""How far the envelope of a model's uncertainty moves the residuals of the tests on board, against their gates
(`fdi-tune uncertainty`; issue 45, item 3).

For every test of the table (the thresholds file's selection, synthesised as export-c does), along each scenario's
fault-free drive (its operating points), at every step after the warm-up and inside the test's domain:

* the worst-case spread of the residual over the envelope, to first order (`residuals.uncertainty_sensitivity`):
  sum over the uncertain parameters and nuisances theta of |d r / d theta| * w_theta, against the test's gate
  gate * sigma (sigma: the thresholds file's fault-free standard deviation, calibrated on the model plant);
* which theta contributes most of it;
* per fault of its signature at its required size, the fault-to-noise ratio |s_f| size_f / sigma and the
  fault-to-uncertainty ratio |s_f| size_f / spread (medians over the steps).

A spread above the gate is a false alarm waiting for a vehicle at that corner of the envelope; a
fault-to-uncertainty ratio below 1 is a fault the test cannot tell from the envelope at a fixed gate. The drives
give the operating points only (model plant, the scenarios' own seeds); the spread is the model's, not a
measurement: the fleet suite (`fdi-quality --fleet`) measures on the truth plant."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fdi_analysis.model import Model
from fdi_analysis.names import in_order
from fdi_analysis.residuals.evaluate import FilterDesign, in_domain, sensitivity_series
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.uncertainty_sensitivity import (
    UncertaintySolver,
    spread_series,
    uncertainties,
    uncertainty_sensitivities,
)

FloatArray = NDArray[np.float64]
WARMUP_S = 3.0  # s at the start of each drive that are not operating points (the screening's)


@dataclass(frozen=True)
class ScenarioSpread:
    """One test in one scenario: medians and 95th percentiles over its evaluable steps."""

    steps: int
    spread_median: float  # in gates (spread / (gate * sigma))
    spread_p95: float
    top: str  # the theta with the largest median share
    top_share: float  # its median share, in gates
    fnr: dict[str, float] = field(default_factory=dict)  # fault -> median |s_f| size / sigma
    fur: dict[str, float] = field(default_factory=dict)  # fault -> median |s_f| size / spread


@dataclass(frozen=True)
class GeneratorSpread:
    label: str
    equations: str
    sigma: float
    gate: float
    uncertain: tuple[str, ...]  # the thetas the residual is sensitive to
    scenarios: dict[str, ScenarioSpread]

    def to_dict(self) -> dict[str, Any]:
        return {"label": self.label, "equations": self.equations, "sigma": self.sigma, "gate": self.gate,
                "uncertain": list(self.uncertain),
                "scenarios": {k: vars(v) for k, v in self.scenarios.items()}}


def _median(x: FloatArray) -> float:
    return float(f"{np.median(x):.3g}") if x.size else math.nan


def generator_spread(model: Model, g: Generator, sigma: float, gate: float, sizes: Mapping[str, float],
                drives: Mapping[str, Mapping[str, FloatArray]], design: FilterDesign,
                solver: UncertaintySolver) -> GeneratorSpread:
    """The spread of one generator (with its fault sensitivities) on the operating points of `drives`."""
    sens = uncertainty_sensitivities(model, g, solver)
    widths = {u.name: u.half_width for u in solver.quantities}
    warm = round(WARMUP_S / design.dt)
    per: dict[str, ScenarioSpread] = {}
    for sc, sig in drives.items():
        keep = in_domain(g, sig)
        keep[:warm] = False
        total, parts = spread_series(g, sens, widths, sig, design)
        faults = sensitivity_series(g, sig, design)
        unit = gate * sigma
        spread = total[keep] / unit
        shares = {k: _median(v[keep] / unit) for k, v in parts.items()}
        top = max(shares, key=lambda k: shares[k]) if shares else ""
        fnr, fur = {}, {}
        for f, s in faults.items():
            effect = np.abs(s[keep]) * sizes.get(f, 0.0)
            fnr[f] = _median(effect / sigma)
            with np.errstate(divide="ignore", invalid="ignore"):
                fur[f] = _median(np.where(total[keep] > 0.0, effect / total[keep], math.inf))
        per[sc] = ScenarioSpread(int(np.count_nonzero(keep)), _median(spread),
                                 float(f"{np.percentile(spread, 95):.3g}") if spread.size else math.nan,
                                 top, shares.get(top, 0.0), fnr, fur)
    return GeneratorSpread(g.name, " ".join(g.equations), sigma, gate, tuple(n for n, _ in sens), per)


def table_spread(model: Model, gens: Sequence[Generator], sigmas: Sequence[float], gate: float,
                 sizes: Mapping[str, float], drives: Mapping[str, Mapping[str, FloatArray]], design: FilterDesign,
                 progress: Callable[[int, int, str], None] | None = None) -> list[GeneratorSpread]:
    """`generator_spread` of every generator of the table (one uncertainty solver shared)."""
    solver = UncertaintySolver(model)
    out = []
    for i, (g, sigma) in enumerate(zip(gens, sigmas, strict=True)):
        out.append(generator_spread(model, g, sigma, gate, sizes, drives, design, solver))
        if progress is not None:
            progress(i + 1, len(gens), g.name)
    return out


def markdown(model: Model, rows: Sequence[GeneratorSpread], provenance: str) -> str:
    """The report as Markdown: the envelope, then per test and scenario the spread in gates and its main
    contributor, then per fault the worst test's fault-to-noise and fault-to-uncertainty ratios."""
    qs = uncertainties(model)
    lines = [f"## Residual spread over the uncertainty envelope, model `{model.name}`", "", provenance, "",
             "Envelope (first-order worst case over the box; w = largest deviation from the nominal value):", "",
             "| quantity | kind | nominal | range | w |", "|---|---|---|---|---|"]
    lines += [f"| `{u.name}` | {u.kind} | {u.nominal:g} {u.unit} | [{u.range[0]:g}, {u.range[1]:g}] | "
              f"{u.half_width:.4g} |" for u in qs]
    scenarios = list(dict.fromkeys(s for r in rows for s in r.scenarios))
    lines += ["", "Spread of each test in gates (spread / (gate x sigma); median, 95th percentile over the evaluable "
              "steps) and the quantity that contributes most (its median share, in gates). Above 1: the test "
              "alarms on a vehicle at that corner of the envelope.", "",
              "| test | " + " | ".join(scenarios) + " | main contributor |",
              "|---|" + "---|" * (len(scenarios) + 1)]
    for r in rows:
        cells = []
        for sc in scenarios:
            s = r.scenarios.get(sc)
            cells.append("not evaluable" if s is None or not s.steps else f"{s.spread_median:.3g} / {s.spread_p95:.3g}")
        tops: dict[str, float] = {}
        for s in r.scenarios.values():
            if s.top:
                tops[s.top] = max(tops.get(s.top, 0.0), s.top_share)
        main = max(tops, key=lambda k: tops[k]) if tops else ""
        lines.append(f"| {r.label} | " + " | ".join(cells) + f" | `{main}` ({tops.get(main, 0.0):.3g}) |"
                     if main else f"| {r.label} | " + " | ".join(cells) + " | none |")
    faults = in_order({f for r in rows for s in r.scenarios.values() for f in s.fnr}, [f.name for f in model.faults])
    lines += ["", "Per fault at its required size, the best test of the table (largest median fault-to-uncertainty "
              "ratio over the scenarios): fault-to-noise ratio |s| size / sigma and fault-to-uncertainty ratio "
              "|s| size / spread. A ratio below 1 means the envelope alone moves that test's residual further "
              "than the fault does.", "", "| fault | best test | scenario | fault-to-noise | fault-to-uncertainty |",
              "|---|---|---|---|---|"]
    for f in faults:
        best = max(((r.label, sc, s.fnr[f], s.fur[f]) for r in rows for sc, s in r.scenarios.items()
                    if f in s.fur and math.isfinite(s.fnr[f]) and not math.isnan(s.fur[f])),
                   key=lambda x: x[3], default=None)
        if best is None:
            lines.append(f"| {f} | none | | | |")
            continue
        lines.append(f"| {f} | {best[0]} | {best[1]} | {best[2]:.3g} | {best[3]:.3g} |")
    return "\n".join(lines) + "\n"
