"""Converter from the reference reconstruction JSON (shared/reference/romo_model/*.json) to a Structure.

Each equation there lists its `unknowns`, `knowns`, `faults` and, for a differential constraint, a
`diff_pair` {"derivative": dx, "of": x}; X then marks dx with 3 and x with 2 (Fault Diagnosis Toolbox
convention).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from ..structure import DIFF_DERIVATIVE, DIFF_INTEGRATED, INCIDENCE, Structure, StructureError


def _names(items: list[Any]) -> list[str]:
    return [str(i["name"]) if isinstance(i, dict) else str(i) for i in items]


def structure_from_reference(d: dict[str, Any], source: str = "<dict>") -> Structure:
    eqs = d["equations"]
    xs, zs, fs = _names(d["unknowns"]), _names(d["knowns"]), _names(d["faults"])
    xi = {n: i for i, n in enumerate(xs)}
    zi = {n: i for i, n in enumerate(zs)}
    fi = {n: i for i, n in enumerate(fs)}
    X = np.zeros((len(eqs), len(xs)), dtype=np.int8)
    Z = np.zeros((len(eqs), len(zs)), dtype=np.int8)
    F = np.zeros((len(eqs), len(fs)), dtype=np.int8)
    try:
        for e, eq in enumerate(eqs):
            for n in eq["unknowns"]:
                X[e, xi[n]] = INCIDENCE
            for n in eq.get("knowns", []):
                Z[e, zi[n]] = 1
            for n in eq.get("faults", []):
                F[e, fi[n]] = 1
            dp = eq.get("diff_pair")
            if dp:
                X[e, xi[dp["derivative"]]] = DIFF_DERIVATIVE
                X[e, xi[dp["of"]]] = DIFF_INTEGRATED
    except KeyError as exc:
        raise StructureError(f"{source}: equation {eq.get('id')!r} names an undeclared variable {exc}") from exc
    return Structure(
        equations=tuple(str(eq["id"]) for eq in eqs),
        unknowns=tuple(xs),
        knowns=tuple(zs),
        faults=tuple(fs),
        X=X,
        F=F,
        Z=Z,
        name=str(d.get("name", "")),
        equation_kinds=tuple(str(eq.get("kind", "")) for eq in eqs),
    )


def load_reference(path: Path | str) -> Structure:
    p = Path(path)
    return structure_from_reference(json.loads(p.read_text(encoding="utf-8")), source=str(p))
