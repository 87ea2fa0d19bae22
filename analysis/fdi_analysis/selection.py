"""Selection of a minimal set of tests (MSO sets) with maximal isolability.

- `greedy`: the paper's method. Tests sorted by cost (number of unknowns, then equations for a stable
  order); a test is kept when adding it clears at least one element of the fault matrix.
- `optimal`: the fewest tests that reach the same fault matrix as all candidates together, ties broken by
  the smallest total cost, solved exactly in two stages (minimum count, then minimum cost at that count)
  by bounds, local-search incumbents and an exact code-assignment search (`selection_exact`).

Both only need one candidate per distinct fault set: tests with the same fault set clear the same fault
matrix elements, so the cheapest represents them all (`cheapest_per_signature`).
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from fdi_analysis.fault_matrix import Candidate, Method, distinguished_pairs, fault_matrix
from fdi_analysis.selection_exact import (
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
    `selection_exact` for the algorithm and why it is exact. If `time_limit_s` runs out the best
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
    best = min(_greedy_columns(problem, cands, nf, method), cover_greedy(cover), key=len)
    lb = root_lower_bound(problem)
    best, lb = _count_stage(problem, cover, best, lb, deadline)
    count_proven = lb == len(best)
    best, cost_proven = _cost_stage(problem, cover, costs, best, count_proven, deadline)
    chosen = sorted((by_mask[problem.columns[c]] for c in best), key=_order_key)
    return Selection(method=method, kind="optimal", tests=tuple(chosen), proven=count_proven and cost_proven,
                     lower_bound=lb)


def _candidate_by_mask(cands: Sequence[Candidate], problem: Problem) -> dict[int, Candidate]:
    """The cheapest candidate behind each reduced column (same tie order as `cheapest_per_signature`)."""
    out: dict[int, Candidate] = {}
    for t in cands:  # sorted cheapest first
        mask = 0
        for k, item in enumerate(problem.item_of_fault):
            if t.faults >> k & 1:
                mask |= 1 << item
        out.setdefault(mask, t)
    return out


def _greedy_columns(problem: Problem, cands: Sequence[Candidate], nf: int, method: Method) -> list[int]:
    index = {c: i for i, c in enumerate(problem.columns)}
    cols = []
    for t in greedy(cands, nf, method).tests:
        mask = 0
        for k, item in enumerate(problem.item_of_fault):
            if t.faults >> k & 1:
                mask |= 1 << item
        cols.append(index[mask])
    return sorted(set(cols))


def _count_stage(problem: Problem, cover: BoolMatrix, best: list[int], lb: int,
                 deadline: float) -> tuple[list[int], int]:
    """First shrink the incumbent from above by local search (k = |best| - 1, ...). Then for k = lb, lb+1,
    ...: a short local search may find a selection with k columns (then k is optimal, all smaller k being
    refuted); otherwise the exact search finds one or proves none exists (lb = k+1)."""
    search: CodeSearch | None = None
    iterations = min(COUNT_SEARCH_ITERATIONS, 20 * len(problem.columns))
    while lb < len(best) - 1 and time.monotonic() < deadline:  # shrink the incumbent from above first
        found = local_search(cover, len(best) - 1, iterations=iterations, seed=len(best), deadline=deadline)
        if found is None:
            break
        best = sorted(found)
    while lb < len(best):
        found = local_search(cover, lb, iterations=iterations, seed=lb, deadline=deadline)
        try:
            if found is None:
                search = search or CodeSearch(problem, deadline)
                found = search.feasible(lb)
        except SearchTimeoutError:
            break
        if found is None:
            lb += 1
        else:
            best = sorted(found)
    return best, lb


def _cost_stage(problem: Problem, cover: BoolMatrix, costs: IntArray, best: list[int], count_proven: bool,
                deadline: float) -> tuple[list[int], bool]:
    """Cheapest selection with len(best) columns: local-search incumbents, then branch and bound."""
    k = len(best)
    iterations = min(LOCAL_SEARCH_ITERATIONS, 20 * len(problem.columns))
    best = cheaper_swaps(cover, costs, best, deadline)
    for seed in range(COST_SEEDS):
        if time.monotonic() > deadline:
            break
        found = local_search(cover, k, iterations=iterations, seed=100 + seed, deadline=deadline)
        if found is not None:
            found = cheaper_swaps(cover, costs, found, deadline)
            if costs[found].sum() < costs[best].sum():
                best = found
    if not count_proven:
        return sorted(best), False
    try:
        better = CodeSearch(problem, deadline, with_costs=True).cheapest(k, int(costs[best].sum()))
    except SearchTimeoutError:
        return sorted(best), False
    return sorted(better if better is not None else best), True


def reaches_same_matrix(selection: Selection, tests: Sequence[Candidate], nf: int) -> bool:
    full = fault_matrix([t.faults for t in tests], nf, selection.method)
    return bool(np.array_equal(selection.matrix(nf), full))
