"""Structural detectability and single-fault isolability (mixed causality, as in the paper).

- Fault f is structurally detectable when one of its equations lies in the overdetermined part M+.
- Fault fi is structurally isolable from fault fj when fi is detectable in the model with fj's equations
  removed (Krysander & Frisk): some residual can react to fi while being insensitive to fj.
- Faults that are mutually not isolable form isolability classes; the firmware can at best name a class.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fdi_analysis.dm import overdetermined_part
from fdi_analysis.structure import Structure


@dataclass(frozen=True)
class IsolabilityResult:
    faults: tuple[str, ...]
    detectable: npt.NDArray[np.bool_]  # detectable[i]
    isolable: npt.NDArray[np.bool_]  # isolable[i, j]: fault i can be isolated from fault j
    classes: tuple[tuple[int, ...], ...]  # mutually non-isolable detectable faults

    def non_isolable_pairs(self) -> list[tuple[int, int]]:
        """Unordered pairs (i < j) of detectable faults that cannot be isolated from each other."""
        n = len(self.faults)
        return [
            (i, j)
            for i in range(n)
            for j in range(i + 1, n)
            if self.detectable[i] and self.detectable[j] and not self.isolable[i, j] and not self.isolable[j, i]
        ]

    def one_way_pairs(self) -> list[tuple[int, int]]:
        """Ordered pairs (i, j) of detectable faults isolable in one direction only: fault i cannot be isolated from
        fault j, but j can be isolated from i (every residual that can react to i can also react to j, and some
        residual can react to j and not to i). When i occurs, j stays a candidate; when j occurs, i is ruled out."""
        n = len(self.faults)
        return [
            (i, j)
            for i in range(n)
            for j in range(n)
            if i != j and self.detectable[i] and self.detectable[j] and not self.isolable[i, j] and self.isolable[j, i]
        ]

    def class_of(self, fault: int) -> tuple[int, ...]:
        for c in self.classes:
            if fault in c:
                return c
        return (fault,)


def detectable_faults(st: Structure, eqs: npt.ArrayLike | None = None) -> npt.NDArray[np.bool_]:
    """Boolean vector over st.faults: detectable in the subsystem `eqs` (default: the whole model)."""
    plus = overdetermined_part(st.X, eqs)
    return st.equation_faults(plus)


def isolability(st: Structure) -> IsolabilityResult:
    nf = st.nf
    det = detectable_faults(st)
    iso = np.zeros((nf, nf), dtype=bool)
    all_eqs = np.arange(st.ne)
    for j in range(nf):
        keep = all_eqs[st.F[:, j] == 0]
        iso[:, j] = detectable_faults(st, keep)
    iso[np.arange(nf), np.arange(nf)] = False
    classes = _classes(det, iso)
    return IsolabilityResult(faults=st.faults, detectable=det, isolable=iso, classes=classes)


def _classes(det: npt.NDArray[np.bool_], iso: npt.NDArray[np.bool_]) -> tuple[tuple[int, ...], ...]:
    """Connected components of 'mutually not isolable' among the detectable faults."""
    n = len(det)
    label = list(range(n))

    def find(a: int) -> int:
        while label[a] != a:
            label[a] = label[label[a]]
            a = label[a]
        return a

    for i in range(n):
        for j in range(i + 1, n):
            if det[i] and det[j] and not iso[i, j] and not iso[j, i]:
                label[find(i)] = find(j)
    groups: dict[int, list[int]] = {}
    for i in range(n):
        if det[i]:
            groups.setdefault(find(i), []).append(i)
    return tuple(tuple(g) for g in sorted(groups.values()))
