"""The SAT selection (`selection.sat`: count and cost) against brute force on random small problems, including
families closed under item permutations (interchangeable classes as count rows, lex-leader constraints):
every "no selection with k tests" and every minimum cost must equal exhaustive enumeration."""

from __future__ import annotations

import itertools

import pytest
from hypothesis import event, given, settings
from hypothesis import strategies as hst

from fdi_analysis.fault_matrix import Method
from fdi_analysis.selection.exact import Problem, cover_matrix, reduce_problem

pytest.importorskip("pysat")
from fdi_analysis.selection.sat import SatSelector, interchangeable_classes, sat_problem, separates

DEADLINE_S = 30.0
MAX_COLUMNS = 22  # brute force stays below ~30k combinations per k


def _closure(columns: set[int], gens: list[list[int]], limit: int) -> set[int]:
    """Smallest superset of `columns` mapped onto itself by every generator (None-safe cap: `limit`)."""
    out = set(columns)
    todo = list(columns)
    while todo and len(out) <= limit:
        c = todo.pop()
        for g in gens:
            img = sum(1 << g[i] for i in range(len(g)) if c >> i & 1)
            if img not in out:
                out.add(img)
                todo.append(img)
    return out


@hst.composite
def problems(draw: hst.DrawFn) -> tuple[Problem, list[int]]:
    """A reduced problem (method A or B) whose family is often closed under a symmetric group on a random
    block of faults (and sometimes under a swap of two blocks)."""
    nf = draw(hst.integers(min_value=2, max_value=7))
    method: Method = draw(hst.sampled_from(["A", "B"]))
    base = set(draw(hst.lists(hst.integers(min_value=1, max_value=(1 << nf) - 1), min_size=1, max_size=6)))
    gens: list[list[int]] = []
    if draw(hst.booleans()):
        size = draw(hst.integers(min_value=2, max_value=nf))
        block = draw(hst.permutations(list(range(nf))))[:size]
        for a, b in itertools.pairwise(block):
            g = list(range(nf))
            g[a], g[b] = b, a
            gens.append(g)
    if nf >= 4 and draw(hst.booleans()):
        g = list(range(nf))
        g[0], g[1], g[2], g[3] = 2, 3, 0, 1
        gens.append(g)
    family = sorted(_closure(base, gens, 4 * MAX_COLUMNS))
    family = family[:MAX_COLUMNS] if len(family) > MAX_COLUMNS else family
    if draw(hst.booleans()):  # costs invariant under the group (size + a per-size offset)
        offset = draw(hst.lists(hst.integers(min_value=0, max_value=5), min_size=nf + 1, max_size=nf + 1))
        costs = [c.bit_count() * 3 + offset[c.bit_count()] for c in family]
    else:
        costs = [draw(hst.integers(min_value=1, max_value=20)) for _ in family]
    return reduce_problem(family, costs, nf, method), costs


def _brute_force(problem: Problem) -> tuple[int, int]:
    """(minimum count, minimum cost at that count) by enumerating column subsets."""
    cover = cover_matrix(problem)
    masks = [int("".join("1" if x else "0" for x in row) or "0", 2) for row in cover]
    full = 0
    for m in masks:
        full |= m
    for k in range(1, len(masks) + 1):
        best = None
        for combo in itertools.combinations(range(len(masks)), k):
            acc = 0
            for c in combo:
                acc |= masks[c]
            if acc == full:
                cost = sum(problem.costs[c] for c in combo)
                best = cost if best is None else min(best, cost)
        if best is not None:
            return k, best
    raise AssertionError("the whole family must separate what it separates")


def _feasible_any_class_size(problem: Problem, k: int, min_class: int) -> list[int] | None:
    import time

    return SatSelector(problem, min_class=min_class).feasible(k, time.monotonic() + DEADLINE_S)


@settings(max_examples=120, deadline=None)
@given(problems(), hst.sampled_from([2, 4, 99]))
def test_sat_count_and_cost_equal_brute_force(case: tuple[Problem, list[int]], min_class: int) -> None:
    import time

    problem, _ = case
    if not problem.has_requirements:
        return
    sp = sat_problem(problem, with_costs=False, min_class=min_class)
    event(f"count rows: {len(sp.rows.classes)}, symmetry row permutations: {min(len(sp.row_perms), 2)}")
    k_min, cost_min = _brute_force(problem)
    if k_min > 1:  # "no selection with k_min - 1 tests" is a claim: it must be true
        assert _feasible_any_class_size(problem, k_min - 1, min_class) is None
    found = _feasible_any_class_size(problem, k_min, min_class)
    assert found is not None and len(found) <= k_min
    assert separates(problem, [problem.columns[c] for c in found])
    sel = SatSelector(problem, min_class=min_class)
    upper = sum(problem.costs[c] for c in found) + 1 if len(found) == k_min else sum(problem.costs) + 1
    cheapest, proven = sel.cheapest(k_min, upper, time.monotonic() + DEADLINE_S)
    assert proven and cheapest is not None and len(cheapest) == k_min
    assert separates(problem, [problem.columns[c] for c in cheapest])
    assert sum(problem.costs[c] for c in cheapest) == cost_min
    # from the optimum as upper bound: proven that nothing is cheaper
    again, proven = sel.cheapest(k_min, cost_min, time.monotonic() + DEADLINE_S)
    assert again is None and proven


def test_interchangeable_classes_of_a_symmetric_family() -> None:
    # faults 0..3 fully interchangeable (every 2-subset), fault 4 alone in its own column
    family = [(1 << a) | (1 << b) for a, b in itertools.combinations(range(4), 2)] + [1 << 4]
    problem = reduce_problem(family, [1] * len(family), 5, "A")
    classes = interchangeable_classes(problem, with_costs=False)
    items = [problem.item_of_fault[f] for f in range(4)]
    assert sorted(items) in classes
    assert [problem.item_of_fault[4]] in classes
    # costs that differ inside the orbit split the class
    costly = reduce_problem(family, [1, 1, 1, 1, 1, 9, 1], 5, "A")
    assert sorted(items) not in interchangeable_classes(costly, with_costs=True)


def test_bad_k_is_a_clear_error() -> None:
    import time

    problem = reduce_problem([0b01, 0b10], [1, 1], 2, "A")
    with pytest.raises(ValueError, match="k must be at least 1"):
        SatSelector(problem).feasible(0, time.monotonic() + 5)
