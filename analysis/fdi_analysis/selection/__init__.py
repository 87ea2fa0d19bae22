"""Selection of a minimal set of tests (MSO sets) with maximal isolability.

- `greedy`: the paper's method. Tests sorted by cost (number of unknowns, then equations for a stable
  order); a test is kept when adding it clears at least one element of the fault matrix.
- `optimal`: the fewest tests that reach the same fault matrix as all candidates together, ties broken by
  the smallest total cost, solved exactly in two stages (minimum count, then minimum cost at that count)
  by bounds, local-search incumbents and an exact decision: SAT (count) and incremental SAT (cost) on a
  symmetry-reduced code model (`selection.sat`, needs python-sat), or without python-sat the
  code-assignment search of `selection.exact` (slower; more often "not proven" at the time limit).

Both only need one candidate per distinct fault set: tests with the same fault set clear the same fault
matrix elements, so the cheapest represents them all (`cheapest_per_signature`).
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fdi_analysis.fault_matrix import Candidate, Method, distinguished_pairs, fault_matrix
from fdi_analysis.selection import sat
from fdi_analysis.selection.exact import (
    BoolMatrix,
    CodeSearch,
    IntArray,
    Problem,
    SearchTimeoutError,
    cheaper_swaps,
    cover_greedy,
    cover_matrix,
    local_search,
    reduce_problem,
    root_lower_bound,
)

LOCAL_SEARCH_ITERATIONS = 1000  # per local-search run in the cost stage
COUNT_SEARCH_ITERATIONS = 300  # per k in the count stage; a failure there is settled by the exact search
COST_SEEDS = 6
SPECULATE = True  # start the cost search beside the last count refutation (second core)


@dataclass(frozen=True)
class Selection:
    """Selected tests. For "optimal", `proven` says the count and then the cost are proven minimal and
    `lower_bound` is the proven lower bound on the count (equal to len(tests) when the count is proven)."""

    method: Method
    kind: str  # "greedy" or "optimal"
    tests: tuple[Candidate, ...]
    proven: bool = False
    lower_bound: int = 0

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


def optimal(tests: Sequence[Candidate], nf: int, method: Method, time_limit_s: float = 60.0) -> Selection:
    """Fewest tests reaching the fault matrix of all `tests`, then the cheapest such set (exact).

    Stage 1 (count): lower bound from `root_lower_bound`, incumbents from greedy and a weighted local
    search, then the exact code search decides k = LB, LB+1, ... until one is feasible; each infeasible k
    raises the proven bound. Stage 2 (cost): branch and bound at the optimal count. See
    `selection.exact` for the algorithm and why it is exact. If `time_limit_s` runs out the best
    selection found is returned with `proven=False` and the proven `lower_bound` on the count.
    """
    deadline = time.monotonic() + time_limit_s
    cands = cheapest_per_signature(tests)
    problem = reduce_problem([t.faults for t in cands], [t.cost for t in cands], nf, method)
    if not problem.has_requirements:
        return Selection(method=method, kind="optimal", tests=(), proven=True, lower_bound=0)
    by_mask = _candidate_by_mask(cands, problem)
    cover = cover_matrix(problem)
    costs = np.array(problem.costs, dtype=np.int64)
    best = min(_greedy_columns(problem, cands, cover), cover_greedy(cover), key=len)
    lb = root_lower_bound(problem)
    exact = _ExactSolver(problem)
    try:
        best, lb = _count_stage(problem, cover, costs, best, lb, deadline, exact)
        count_proven = lb == len(best)
        best, cost_proven = _cost_stage(problem, cover, costs, best, count_proven, deadline, exact)
    finally:
        exact.cancel_pending()
    chosen = sorted((by_mask[problem.columns[c]] for c in best), key=_order_key)
    return Selection(method=method, kind="optimal", tests=tuple(chosen), proven=count_proven and cost_proven,
                     lower_bound=lb)


def _column_masks(cands: Sequence[Candidate], problem: Problem) -> npt.NDArray[np.uint64]:
    """Each candidate's fault set as a bitmask over the problem's items."""
    faults = np.array([t.faults for t in cands], dtype=np.uint64)
    masks = np.zeros(len(cands), dtype=np.uint64)
    one = np.uint64(1)
    for k, item in enumerate(problem.item_of_fault):
        masks |= ((faults >> np.uint64(k)) & one) << np.uint64(item)
    return masks


def _candidate_by_mask(cands: Sequence[Candidate], problem: Problem) -> dict[int, Candidate]:
    """The cheapest candidate behind each reduced column (same tie order as `cheapest_per_signature`)."""
    out: dict[int, Candidate] = {}
    for t, mask in zip(cands, _column_masks(cands, problem).tolist(), strict=True):  # sorted cheapest first
        out.setdefault(int(mask), t)
    return out


def _greedy_columns(problem: Problem, cands: Sequence[Candidate], cover: BoolMatrix) -> list[int]:
    """The paper's greedy (`greedy`) on the reduced problem, as column indices: candidates in cost order,
    kept when they separate a required item pair not separated yet (a fault pair is separated exactly when
    its item pair is, and every separable item pair is required)."""
    index = {c: i for i, c in enumerate(problem.columns)}
    rows = np.packbits(cover, axis=1)
    covered = 0
    cols = []
    for mask in _column_masks(cands, problem).tolist():  # cands are in greedy's order (cheapest first)
        c = index.get(int(mask))
        if c is None:  # no faults of any item: separates nothing
            continue
        row = int.from_bytes(rows[c].tobytes(), "big")
        if row & ~covered:
            covered |= row
            cols.append(c)
    return sorted(set(cols))


def _count_stage(problem: Problem, cover: BoolMatrix, costs: IntArray, best: list[int], lb: int,
                 deadline: float, exact: _ExactSolver) -> tuple[list[int], int]:
    """First shrink the incumbent from above by local search (k = |best| - 1, ...). Then for k = lb, lb+1,
    ...: a short local search (only without SAT, which finds selections fast) may find a selection with k
    columns (then k is optimal, all smaller k being refuted); otherwise the exact search finds one or
    proves none exists (lb = k+1). When one refutation would prove the incumbent's count (lb = |best| - 1),
    the cost search at |best| starts beside it on the second core (`_ExactSolver.speculate`)."""
    iterations = min(COUNT_SEARCH_ITERATIONS, 20 * len(problem.columns))
    while lb < len(best) - 1 and time.monotonic() < deadline:  # shrink the incumbent from above first
        found = local_search(cover, len(best) - 1, iterations=iterations, seed=len(best), deadline=deadline)
        if found is None:
            break
        best = sorted(found)
    while lb < len(best):
        found = None
        if exact.sat is None:
            found = local_search(cover, lb, iterations=iterations, seed=lb, deadline=deadline)
        elif lb == len(best) - 1:
            best = sorted(cheaper_swaps(cover, costs, best, deadline))
            exact.speculate(len(best), int(costs[best].sum()))
        try:
            if found is None:
                found = exact.feasible(lb, deadline)
        except (SearchTimeoutError, sat.SatTimeoutError):
            break
        if found is None:
            lb += 1
        else:
            best = sorted(found)
            exact.cancel_pending()
    return best, lb


def _cost_stage(problem: Problem, cover: BoolMatrix, costs: IntArray, best: list[int], count_proven: bool,
                deadline: float, exact: _ExactSolver) -> tuple[list[int], bool]:
    """Cheapest selection with len(best) columns: cheaper swaps, local-search incumbents (skipped when the
    exact SAT search follows: it improves faster), then the exact search from that upper bound."""
    k = len(best)
    if count_proven and exact.pending_k() == k:  # started during the count stage
        better, proven = exact.cheapest(k, int(costs[best].sum()), deadline)
        if better is not None and costs[better].sum() < costs[best].sum():
            best = better
        return sorted(best), proven
    exact.cancel_pending()
    iterations = min(LOCAL_SEARCH_ITERATIONS, 20 * len(problem.columns))
    best = cheaper_swaps(cover, costs, best, deadline)
    exact_follows = count_proven and exact.sat is not None
    for seed in range(0 if exact_follows else COST_SEEDS):
        if time.monotonic() > deadline:
            break
        found = local_search(cover, k, iterations=iterations, seed=100 + seed, deadline=deadline)
        if found is not None:
            found = cheaper_swaps(cover, costs, found, deadline)
            if costs[found].sum() < costs[best].sum():
                best = found
    if not count_proven:
        return sorted(best), False
    better, proven = exact.cheapest(k, int(costs[best].sum()), deadline)
    if better is not None and costs[better].sum() < costs[best].sum():
        best = better
    return sorted(best), proven


class _ExactSolver:
    """The exact decisions: SAT (`selection.sat`) when python-sat is installed, else the code search."""

    def __init__(self, problem: Problem) -> None:
        self.problem = problem
        self.sat = sat.SatSelector(problem) if sat.HAVE_SAT else None
        self.search: CodeSearch | None = None
        self.pending: sat.PendingCost | None = None

    def feasible(self, k: int, deadline: float) -> list[int] | None:
        """A selection with at most k columns, or None when none exists (time-outs raise)."""
        if self.sat is not None:
            return self.sat.feasible(k, deadline)
        self.search = self.search or CodeSearch(self.problem, deadline)
        return self.search.feasible(k)

    def speculate(self, k: int, upper: int) -> None:
        """Start the cost search at k in the background (SAT only; one at a time)."""
        if SPECULATE and self.sat is not None and self.pending is None:
            self.pending = self.sat.cheapest_start(k, upper)

    def pending_k(self) -> int | None:
        return None if self.pending is None else self.pending.k

    def cancel_pending(self) -> None:
        if self.pending is not None:
            self.pending.cancel()
            self.pending = None

    def cheapest(self, k: int, upper: int, deadline: float) -> tuple[list[int] | None, bool]:
        """(a selection with k columns cheaper than `upper`, or None; whether it is proven cheapest, or
        for None, whether none cheaper exists). Best effort at the deadline, then unproven. Collects the
        background search if it was started for this k (it started from an upper bound at least as
        large as `upper`, so its answer is only used when cheaper than `upper`)."""
        if self.pending is not None and self.pending.k == k:
            pending, self.pending = self.pending, None
            return pending.collect(deadline)
        if self.sat is not None:
            return self.sat.cheapest(k, upper, deadline)
        try:
            return CodeSearch(self.problem, deadline, with_costs=True).cheapest(k, upper), True
        except SearchTimeoutError:
            return None, False


def reaches_same_matrix(selection: Selection, tests: Sequence[Candidate], nf: int) -> bool:
    full = fault_matrix([t.faults for t in tests], nf, selection.method)
    return bool(np.array_equal(selection.matrix(nf), full))
