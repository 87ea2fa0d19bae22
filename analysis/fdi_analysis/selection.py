"""Selection of a minimal set of tests (MSO sets) with maximal isolability.

- `greedy`: the paper's method. Tests sorted by cost (number of unknowns, then equations for a stable
  order); a test is kept when adding it clears at least one element of the fault matrix.
- `optimal`: the fewest tests that reach the same fault matrix as all candidates together, ties broken by
  the smallest total cost; a set-cover problem solved exactly as a MILP (scipy/HiGHS) in two stages
  (minimum count, then minimum cost at that count).

Both only need one candidate per distinct fault set: tests with the same fault set clear the same fault
matrix elements, so the cheapest represents them all (`cheapest_per_signature`).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import Bounds, LinearConstraint, milp
from scipy.sparse import csc_matrix

from fdi_analysis.fault_matrix import Candidate, Method, distinguished_pairs, fault_matrix


@dataclass(frozen=True)
class Selection:
    method: Method
    kind: str  # "greedy" or "optimal"
    tests: tuple[Candidate, ...]

    @property
    def total_cost(self) -> int:
        return sum(t.cost for t in self.tests)

    def matrix(self, nf: int) -> np.ndarray:
        return fault_matrix([t.faults for t in self.tests], nf, self.method)


def _order_key(t: Candidate) -> tuple[int, int, int]:
    return (t.cost, t.equations.bit_count(), t.equations)


def cheapest_per_signature(tests: Iterable[Candidate]) -> list[Candidate]:
    """One test per distinct fault set: the cheapest (ties: fewer equations, then lowest equation bits)."""
    best: dict[int, Candidate] = {}
    for t in tests:
        cur = best.get(t.faults)
        if cur is None or _order_key(t) < _order_key(cur):
            best[t.faults] = t
    return sorted(best.values(), key=_order_key)


def _pair_mask(fault_set: int, nf: int, method: Method) -> int:
    n = nf + 1
    m = 0
    for j, i in distinguished_pairs(fault_set, nf, method):
        m |= 1 << (j * n + i)
    return m


def greedy(tests: Sequence[Candidate], nf: int, method: Method) -> Selection:
    cleared = 0
    kept = []
    for t in sorted(tests, key=_order_key):
        m = _pair_mask(t.faults, nf, method)
        if m & ~cleared:
            cleared |= m
            kept.append(t)
    return Selection(method=method, kind="greedy", tests=tuple(kept))


def optimal(tests: Sequence[Candidate], nf: int, method: Method, time_limit_s: float = 120.0) -> Selection:
    """Exact minimum-cardinality (then minimum-cost) test set reaching the fault matrix of all `tests`."""
    cands = cheapest_per_signature(tests)
    masks = [_pair_mask(t.faults, nf, method) for t in cands]
    universe = 0
    for m in masks:
        universe |= m
    if not cands or universe == 0:
        return Selection(method=method, kind="optimal", tests=())
    n = nf + 1
    elements = [k for k in range(n * n) if universe >> k & 1]
    row_of = {k: r for r, k in enumerate(elements)}
    rows, cols = [], []
    for c, m in enumerate(masks):
        while m:
            low = m & -m
            rows.append(row_of[low.bit_length() - 1])
            cols.append(c)
            m ^= low
    A = csc_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(elements), len(cands)))
    cover = LinearConstraint(A, lb=np.ones(len(elements)), ub=np.inf)
    integrality = np.ones(len(cands))
    bounds = Bounds(0, 1)
    opts = {"time_limit": time_limit_s, "disp": False}
    first = milp(np.ones(len(cands)), constraints=[cover], integrality=integrality, bounds=bounds, options=opts)
    if first.x is None or first.status != 0:
        raise RuntimeError(f"test selection MILP did not solve to optimality: {first.message}")
    k = round(float(first.fun))
    count = LinearConstraint(np.ones((1, len(cands))), lb=k, ub=k)
    costs = np.array([t.cost for t in cands], dtype=float)
    second = milp(costs, constraints=[cover, count], integrality=integrality, bounds=bounds, options=opts)
    if second.x is None or second.status != 0:
        raise RuntimeError(f"test selection MILP (cost stage) did not solve to optimality: {second.message}")
    chosen = [cands[c] for c in range(len(cands)) if second.x[c] > 0.5]
    return Selection(method=method, kind="optimal", tests=tuple(sorted(chosen, key=_order_key)))


def reaches_same_matrix(selection: Selection, tests: Sequence[Candidate], nf: int) -> bool:
    full = fault_matrix([t.faults for t in tests], nf, selection.method)
    return bool(np.array_equal(selection.matrix(nf), full))
