"""Fault-signature-driven analysis for models too large to enumerate MSO sets.

* `mtes`: minimal test equation supports (Krysander, Aslund, Frisk, DX-10 2010; Frisk, Krysander, Aslund
  2017). Same search as for MSO sets, but only classes holding a faulty equation are removed, and a node
  with a single faulty class is an MTES. The number of nodes grows with the number of distinct fault
  supports, not with the number of MSO sets.
* `isolability`: structural single-fault detectability and isolability. Fault i is isolable from fault j
  iff an equation of fault i lies in (M without the equations of fault j)+. This equals the isolability of
  the full MSO collection (every equation of a PSO set lies in one of its MSO sets), at the cost of
  nf + 1 DM decompositions instead of an enumeration.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ..structure import Structure
from . import _core
from .engine import Prepared, prepare
from .results import MtesResult, TestSupport


def mtes(structure: Structure | Prepared, *, all_tes: bool = False, batch: int = 4096) -> MtesResult:
    """Minimal test equation supports; with ``all_tes`` also every test support visited by the search."""
    t0 = time.perf_counter()
    p = structure if isinstance(structure, Prepared) else prepare(structure)
    minimal = _search(p, all_tes=False, batch=batch)
    found = _search(p, all_tes=True, batch=batch) if all_tes else []
    key = lambda t: (t.equations.bit_count(), t.equations)  # noqa: E731
    return MtesResult(
        mtes=tuple(sorted(minimal, key=key)),
        tes=tuple(sorted(found, key=key)) if all_tes else (),
        elapsed_s=time.perf_counter() - t0,
    )


def _search(p: Prepared, *, all_tes: bool, batch: int) -> list[TestSupport]:
    found: list[TestSupport] = []
    if p.root and p.faults_of(p.root):
        it = _core.iter_new(p.model, p.root, p.root, 1, 1 if all_tes else 0)
        while True:
            chunk = _core.iter_next(it, batch, 1)
            if not chunk:
                break
            found.extend(
                TestSupport(equations=s, faults=p.signature(f) if p.keyed else p.faults_of(s)) for s, f in chunk
            )
    return found


def minimal_signatures(signatures: frozenset[int] | set[int]) -> frozenset[int]:
    """The inclusion-minimal fault sets of a collection (no other member is a proper subset)."""
    arr = np.array(sorted(signatures, key=lambda s: (s.bit_count(), s)), dtype=np.uint64)
    keep: list[int] = []
    kept = np.zeros(0, dtype=np.uint64)
    for s in arr:
        if kept.size == 0 or not bool(np.any((kept & ~s) == 0)):
            keep.append(int(s))
            kept = np.append(kept, s)
    return frozenset(keep)


@dataclass(frozen=True)
class Isolability:
    """``isolable[i, j]``: fault i can be told apart from fault j (a test sees i and not j)."""

    faults: tuple[str, ...]
    detectable: npt.NDArray[np.bool_]
    isolable: npt.NDArray[np.bool_]
    elapsed_s: float

    def non_isolable_pairs(self) -> list[tuple[str, str]]:
        """Unordered pairs of distinct faults that cannot be isolated from each other in either direction."""
        n = len(self.faults)
        return [
            (self.faults[i], self.faults[j])
            for i in range(n)
            for j in range(i + 1, n)
            if not self.isolable[i, j] and not self.isolable[j, i]
        ]


def isolability(structure: Structure) -> Isolability:
    t0 = time.perf_counter()
    p = prepare(structure)
    nf = structure.nf
    feq = [sum(1 << int(e) for e in structure.F[:, f].nonzero()[0]) for f in range(nf)]
    full = (1 << structure.ne) - 1
    det = np.array([bool(feq[i] & p.root) for i in range(nf)], dtype=bool)
    iso = np.zeros((nf, nf), dtype=bool)
    for j in range(nf):
        mj = _core.mplus(p.model, full & ~feq[j])
        for i in range(nf):
            iso[i, j] = i != j and bool(feq[i] & mj)
    return Isolability(faults=structure.faults, detectable=det, isolable=iso, elapsed_s=time.perf_counter() - t0)


def isolability_from_signatures(nf: int, signatures: frozenset[int] | set[int]) -> npt.NDArray[np.bool_]:
    """Isolability given by a collection of test fault signatures: i isolable from j iff some signature
    holds i and not j."""
    iso = np.zeros((nf, nf), dtype=bool)
    for s in signatures:
        row = np.array([(s >> i) & 1 for i in range(nf)], dtype=bool)
        iso |= np.outer(row, ~row)
    return iso
