"""What decoupling the residuals from a model's nuisances costs (`fdi-analyze robustness`).

For the nominal model, for each nuisance decoupled alone (`fdi_analysis.uncertainty.decoupled`), for every
nuisance at once, and for a chosen set: the structural redundancy, the detectable faults, the isolability, and
(optionally) the MSO sets; each against the nominal model, as the faults that lose detectability and the ordered
pairs (fi, fj) that lose "fi isolable from fj". A constant or slowly varying parameter is costed twice: with its
zero derivative (a residual may test that it does not change, so an abrupt fault stays visible at its onset) and
strictly as an unknown input (what stays visible whatever its time course).

The chosen set is the largest one found greedily, cheapest nuisance first, that costs nothing: no fault loses
detectability and no pair loses isolability against the nominal model. The residuals are decoupled from it; the
others stay bounded by their ranges (the thresholds carry them, with the uncertain parameters)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fdi_analysis.dm import redundancy
from fdi_analysis.isolability import IsolabilityResult, isolability
from fdi_analysis.model import Model
from fdi_analysis.mso import find_msos
from fdi_analysis.mso.results import bits
from fdi_analysis.uncertainty import decoupled


@dataclass(frozen=True)
class Cost:
    """One decoupled set of nuisances against the nominal model."""

    nuisances: tuple[str, ...]
    strict: bool
    redundancy: int
    detectable: tuple[str, ...]
    lost_detectability: tuple[str, ...]
    lost_isolability: tuple[tuple[str, str], ...]  # (fi, fj): fi was isolable from fj, is not any more
    classes: tuple[tuple[str, ...], ...]  # isolability classes with more than one fault
    msos: int | None = None  # MSO sets (None: not counted)
    msos_per_fault: dict[str, int] | None = None

    @property
    def free(self) -> bool:
        """Costs nothing structurally."""
        return not self.lost_detectability and not self.lost_isolability

    def to_dict(self) -> dict[str, Any]:
        return {
            "nuisances": list(self.nuisances), "strict": self.strict, "redundancy": self.redundancy,
            "detectable": list(self.detectable), "lost_detectability": list(self.lost_detectability),
            "lost_isolability": [list(p) for p in self.lost_isolability], "classes": [list(c) for c in self.classes],
            "msos": self.msos, "msos_per_fault": self.msos_per_fault,
        }


@dataclass(frozen=True)
class RobustnessReport:
    model: str
    nuisances: tuple[dict[str, Any], ...]  # name, kind, range, unit
    uncertain_parameters: tuple[dict[str, Any], ...]  # name, value, range, unit
    nominal: Cost
    each: tuple[Cost, ...]  # each nuisance alone (constants with their zero derivative)
    each_strict: tuple[Cost, ...]  # each constant or slow parameter alone, strictly as an unknown input
    everything: Cost
    everything_strict: Cost
    chosen: Cost
    bounded: tuple[str, ...]  # the nuisances the residuals stay coupled to
    beyond: tuple[Cost, ...] = ()  # the chosen set plus each bounded nuisance: why it stays bounded

    def to_dict(self) -> dict[str, Any]:
        return {
            "model": self.model, "nuisances": list(self.nuisances),
            "uncertain_parameters": list(self.uncertain_parameters), "nominal": self.nominal.to_dict(),
            "each": [c.to_dict() for c in self.each], "each_strict": [c.to_dict() for c in self.each_strict],
            "everything": self.everything.to_dict(), "everything_strict": self.everything_strict.to_dict(),
            "chosen": self.chosen.to_dict(), "bounded": list(self.bounded),
            "beyond": [c.to_dict() for c in self.beyond],
        }


def _msos(model: Model, workers: int) -> tuple[int, dict[str, int]]:
    st = model.structure()
    if redundancy(st.X) <= 0:
        return 0, {f: 0 for f in st.faults}
    s = find_msos(st, workers=workers, progress=False)
    per = dict.fromkeys(st.faults, 0)
    for e in s.signatures:
        for i in bits(e.faults):
            per[st.faults[i]] += e.count
    return s.count, per


def cost(model: Model, names: tuple[str, ...], nominal: IsolabilityResult | None = None, *, strict: bool = False,
         mso_workers: int = 0) -> Cost:
    """The cost of decoupling `names` from `model` (against `nominal`, default: the model's own isolability).
    `mso_workers` > 0 also counts the MSO sets with that many processes."""
    m = decoupled(model, names, strict=strict) if names else model
    st = m.structure()
    iso = isolability(st)
    base = nominal if nominal is not None else isolability(model.structure())
    faults = st.faults
    lost_det = tuple(f for f, a, b in zip(faults, base.detectable, iso.detectable, strict=True) if a and not b)
    lost_iso = tuple((faults[i], faults[j]) for i, j in zip(*np.nonzero(base.isolable & ~iso.isolable), strict=True)
                     if iso.detectable[i])  # a fault that lost detectability is counted once, above
    count, per = _msos(m, mso_workers) if mso_workers > 0 else (None, None)
    return Cost(
        nuisances=names, strict=strict, redundancy=int(redundancy(st.X)),
        detectable=tuple(f for f, d in zip(faults, iso.detectable, strict=True) if d),
        lost_detectability=lost_det, lost_isolability=lost_iso,
        classes=tuple(tuple(faults[i] for i in c) for c in iso.classes if len(c) > 1),
        msos=count, msos_per_fault=per,
    )


def _badness(c: Cost, nominal_redundancy: int) -> tuple[int, int, int]:
    return len(c.lost_detectability), len(c.lost_isolability), nominal_redundancy - c.redundancy


def analyse(model: Model, *, mso_workers: int = 0) -> RobustnessReport:
    """The robustness report of `model` (MSO sets counted for the nominal, chosen and all-decoupled models when
    `mso_workers` > 0)."""
    base = isolability(model.structure())
    nominal = cost(model, (), base, mso_workers=mso_workers)
    names = tuple(n.name for n in model.nuisances)
    each = tuple(cost(model, (n,), base) for n in names)
    each_strict = tuple(cost(model, (n.name,), base, strict=True) for n in model.nuisances if n.kind != "input")
    chosen: tuple[str, ...] = ()
    for c in sorted(each, key=lambda c: (_badness(c, nominal.redundancy), names.index(c.nuisances[0]))):
        trial = (*chosen, c.nuisances[0])
        if cost(model, trial, base).free:
            chosen = trial
    chosen = tuple(n for n in names if n in chosen)  # declared order
    bounded = tuple(n for n in names if n not in chosen)
    return RobustnessReport(
        model=model.name,
        nuisances=tuple({"name": n.name, "kind": n.kind, "range": list(n.range), "unit": n.unit, "drift": n.drift}
                        for n in model.nuisances),
        uncertain_parameters=tuple({"name": p.name, "value": p.value, "range": list(p.range), "unit": p.unit}
                                   for p in model.uncertain_parameters().values() if p.range is not None),
        nominal=nominal, each=each, each_strict=each_strict,
        everything=cost(model, names, base, mso_workers=mso_workers),
        everything_strict=cost(model, names, base, strict=True),
        chosen=cost(model, chosen, base, mso_workers=mso_workers) if chosen else nominal,
        bounded=bounded,
        beyond=tuple(cost(model, (*chosen, n), base) for n in bounded),
    )


def _pairs(pairs: tuple[tuple[str, str], ...], limit: int = 8) -> str:
    if not pairs:
        return "none"
    text = ", ".join(f"{a} from {b}" for a, b in pairs[:limit])
    return text + (f" (+{len(pairs) - limit} more)" if len(pairs) > limit else "")


def _row(label: str, c: Cost, nominal: Cost) -> str:
    msos = "-" if c.msos is None else f"{c.msos:,}"
    lost = ", ".join(c.lost_detectability) or "none"
    return (f"| {label} | {c.redundancy} ({c.redundancy - nominal.redundancy:+d}) | {len(c.detectable)} | {lost} | "
            f"{len(c.lost_isolability)}: {_pairs(c.lost_isolability)} | {msos} |")


def markdown(r: RobustnessReport) -> str:
    kinds = {n["name"]: n["kind"] for n in r.nuisances}
    lines = [
        f"## Decoupling the residuals of `{r.model}` from what the model does not know",
        "",
        "Nuisances declared: " + (", ".join(f"`{n['name']}` ({n['kind']}, [{n['range'][0]:g}, {n['range'][1]:g}] "
                                            f"{n['unit']})" for n in r.nuisances) or "none") + ".",
        "Uncertain parameters (bounded, not decoupled): " + (", ".join(
            f"`{p['name']}` [{p['range'][0]:g}, {p['range'][1]:g}] {p['unit']}" for p in r.uncertain_parameters)
            or "none") + ".",
        "",
        "Each row decouples the named nuisances (constant and slow parameters with their zero derivative, unless "
        "'strict': then as unknown inputs) and compares with the nominal model: redundancy (change), detectable "
        "faults, faults that lose detectability, ordered pairs that lose isolability (fi from fj), MSO sets.",
        "",
        "| decoupled | redundancy | detectable | lost detectability | lost isolability | MSO sets |",
        "|---|---|---|---|---|---|",
        _row("nothing (nominal model)", r.nominal, r.nominal),
    ]
    for c in r.each:
        lines.append(_row(f"`{c.nuisances[0]}` ({kinds[c.nuisances[0]]})", c, r.nominal))
    for c in r.each_strict:
        lines.append(_row(f"`{c.nuisances[0]}` strict", c, r.nominal))
    lines.append(_row("every nuisance", r.everything, r.nominal))
    lines.append(_row("every nuisance, strict", r.everything_strict, r.nominal))
    lines.append(_row("chosen: " + (", ".join(f"`{n}`" for n in r.chosen.nuisances) or "none"), r.chosen,
                      r.nominal))
    for c in r.beyond:
        lines.append(_row(f"chosen and `{c.nuisances[-1]}`", c, r.nominal))
    lines += [
        "",
        f"Chosen (greedily, cheapest first, at no structural cost): "
        f"{', '.join(r.chosen.nuisances) or 'none'}. Left bounded by their ranges (the thresholds carry them): "
        f"{', '.join(r.bounded) or 'none'}.",
    ]
    if r.everything.classes:
        lines.append("With every nuisance decoupled, not isolable from each other: "
                     + "; ".join(", ".join(c) for c in r.everything.classes) + ".")
    if r.nominal.msos_per_fault and r.chosen.msos_per_fault and r.chosen.nuisances:
        lines += ["", "| fault | MSO sets, nominal | MSO sets, chosen decoupled |", "|---|---|---|"]
        for f, n in r.nominal.msos_per_fault.items():
            lines.append(f"| {f} | {n:,} | {r.chosen.msos_per_fault.get(f, 0):,} |")
    return "\n".join(lines) + "\n"
