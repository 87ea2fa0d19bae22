"""Fault matrices (methods A and B) and test selection: greedy as in the paper, exact optimal selection."""

from __future__ import annotations

import itertools
import pathlib
import time

import numpy as np
import pytest
from msos_bruteforce import all_msos

from fdi_analysis.fault_matrix import Candidate, fault_matrix
from fdi_analysis.isolability import isolability
from fdi_analysis.model_loader import load_model
from fdi_analysis.random_structures import random_structure
from fdi_analysis.selection import cheapest_per_signature, greedy, optimal, reaches_same_matrix
from fdi_analysis.selection.candidates import mso_candidates
from fdi_analysis.selection.exact import (
    CodeSearch,
    Problem,
    automorphisms,
    reduce_problem,
    required_pairs,
    root_lower_bound,
    search_order,
)


def random_tests(seed: int, n: int, nf: int) -> list[Candidate]:
    rng = np.random.default_rng(seed)
    out = []
    for t in range(n):
        faults = int(rng.integers(1, 1 << nf))
        out.append(Candidate(equations=1 << t, faults=faults, cost=int(rng.integers(2, 30)), label=f"t{t}"))
    return out


def test_fault_matrix_definitions() -> None:
    # two tests over 3 faults: t0 = {f1, f2}, t1 = {f2, f3}
    fm_a = fault_matrix([0b011, 0b110], 3, "A")
    fm_b = fault_matrix([0b011, 0b110], 3, "B")
    # signatures: f1 -> {t0}, f2 -> {t0, t1}, f3 -> {t1}; fault 0 -> {}
    assert fm_a[0].all()  # no fault is explained by every fault
    assert fm_a[1, 2] and not fm_a[2, 1]  # f2 explains f1 (sig f1 within sig f2), not the reverse
    assert not fm_a[1, 3] and not fm_a[3, 1]
    assert not fm_a[1, 0]  # f1 is detected
    assert (fm_b == fm_b.T).all() and fm_b.sum() == 4  # only the diagonal
    assert (fm_a >= fm_b).all()


def test_method_a_on_all_msos_equals_structural_isolability() -> None:
    for seed in range(6):
        st = random_structure(seed, ne=18, redundancy=3, nf=6)
        msos = all_msos(st)
        fsets = [sum(1 << k for k in np.flatnonzero(st.equation_faults(sorted(m)))) for m in msos]
        fm = fault_matrix(fsets, st.nf, "A")
        iso = isolability(st)
        for j in range(st.nf):
            assert fm[j + 1, 0] == (not iso.detectable[j])
            for i in range(st.nf):
                if i != j and iso.detectable[j]:
                    assert fm[j + 1, i + 1] == (not iso.isolable[j, i])


@pytest.mark.parametrize("method", ["A", "B"])
@pytest.mark.parametrize("seed", range(12))
def test_optimal_is_minimal_by_brute_force_and_never_larger_than_greedy(method: str, seed: int) -> None:
    nf = 5
    tests = random_tests(seed, n=10, nf=nf)
    g = greedy(tests, nf, method)  # type: ignore[arg-type]
    o = optimal(tests, nf, method)  # type: ignore[arg-type]
    assert reaches_same_matrix(g, tests, nf) and reaches_same_matrix(o, tests, nf)
    assert len(o.tests) <= len(g.tests)
    target = fault_matrix([t.faults for t in tests], nf, method)  # type: ignore[arg-type]
    best: tuple[int, int] | None = None
    for k in range(len(tests) + 1):
        for combo in itertools.combinations(tests, k):
            if np.array_equal(fault_matrix([t.faults for t in combo], nf, method), target):  # type: ignore[arg-type]
                cost = sum(t.cost for t in combo)
                best = (k, cost) if best is None or (k, cost) < best else best
        if best is not None:
            break
    assert best == (len(o.tests), o.total_cost)
    assert o.proven and o.lower_bound == len(o.tests)


def test_greedy_keeps_cheapest_first() -> None:
    tests = [Candidate(equations=0b1, faults=0b11, cost=9), Candidate(equations=0b10, faults=0b11, cost=3),
             Candidate(equations=0b100, faults=0b01, cost=5)]
    g = greedy(tests, 2, "B")
    assert [t.cost for t in g.tests] == [3, 5]
    assert [t.cost for t in cheapest_per_signature(tests)] == [3, 5]


# ----------------------------------------------------------------------------------------------------
# Exact machinery (selection.exact): the search itself against brute force, bounds, reduction, symmetry


def brute_force(tests: list[Candidate], nf: int, method: str) -> tuple[int, int]:
    """(fewest tests, cheapest cost at that count) reaching the full fault matrix."""
    target = fault_matrix([t.faults for t in tests], nf, method)  # type: ignore[arg-type]
    for k in range(len(tests) + 1):
        costs = [sum(t.cost for t in combo) for combo in itertools.combinations(tests, k)
                 if np.array_equal(fault_matrix([t.faults for t in combo], nf, method), target)]  # type: ignore[arg-type]
        if costs:
            return k, min(costs)
    raise AssertionError("unreachable")


def symmetric_tests(seed: int) -> tuple[list[Candidate], int]:
    """Candidates closed under swapping faults f1<->f2 and f3<->f4 (so the automorphism search finds
    symmetries), costs invariant, plus faults f5 = f6 never separated (merged into one item)."""
    rng = np.random.default_rng(seed)
    nf = 6
    swap = [1, 0, 3, 2, 4, 5]
    out: dict[int, int] = {}
    for _ in range(6):
        fs = int(rng.integers(1, 1 << 4)) | (0b110000 if rng.random() < 0.5 else 0)
        image = sum(1 << swap[k] for k in range(nf) if fs >> k & 1)
        cost = int(rng.integers(2, 20))
        out.setdefault(fs, cost)
        out.setdefault(image, out[fs])
    tests = [Candidate(equations=1 << t, faults=fs, cost=c) for t, (fs, c) in enumerate(sorted(out.items()))]
    return tests, nf


@pytest.mark.parametrize("method", ["A", "B"])
@pytest.mark.parametrize("seed", range(8))
def test_code_search_decides_every_k_like_brute_force(method: str, seed: int) -> None:
    # the exact search alone (no local search in front of it), for every k around the optimum
    tests = random_tests(100 + seed, n=9, nf=5)
    k_opt, cost_opt = brute_force(tests, 5, method)
    problem = reduce_problem([t.faults for t in tests], [t.cost for t in tests], 5, method)  # type: ignore[arg-type]
    assert root_lower_bound(problem) <= k_opt
    for k in range(k_opt + 2):
        found = CodeSearch(problem, time.monotonic() + 30).feasible(k)
        assert (found is not None) == (k >= k_opt)
        if found is not None:
            faults = [problem.columns[c] for c in found]
            assert len(found) <= k and covers_all(problem, faults)
    cheapest = CodeSearch(problem, time.monotonic() + 30, with_costs=True).cheapest(k_opt, 1 << 30)
    assert cheapest is not None and sum(problem.costs[c] for c in cheapest) == cost_opt


def covers_all(problem: Problem, columns: list[int]) -> bool:
    for j, i in required_pairs(problem):
        if problem.method == "A" and not any(c >> j & 1 and not c >> i & 1 for c in columns):
            return False
        if problem.method == "B" and not any((c >> j ^ c >> i) & 1 for c in columns):
            return False
    return True


@pytest.mark.parametrize("method", ["A", "B"])
@pytest.mark.parametrize("seed", range(6))
def test_symmetry_breaking_and_merged_faults_keep_optimality(method: str, seed: int) -> None:
    tests, nf = symmetric_tests(seed)
    problem = reduce_problem([t.faults for t in tests], [t.cost for t in tests], nf, method)  # type: ignore[arg-type]
    assert problem.item_of_fault[4] == problem.item_of_fault[5]
    order = search_order(problem)
    assert automorphisms(problem, order, with_costs=True)  # the f1<->f2, f3<->f4 swap is found
    o = optimal(tests, nf, method)  # type: ignore[arg-type]
    assert o.proven and reaches_same_matrix(o, tests, nf)
    assert (len(o.tests), o.total_cost) == brute_force(tests, nf, method)


def test_merged_non_isolable_faults() -> None:
    # f2 and f3 appear in exactly the same candidates: one item; f4 is in none: merged with "no fault"
    tests = [Candidate(equations=1, faults=0b0111, cost=3), Candidate(equations=2, faults=0b0001, cost=2),
             Candidate(equations=4, faults=0b0110, cost=4)]
    problem = reduce_problem([t.faults for t in tests], [t.cost for t in tests], 4, "B")
    assert problem.n_items == 3 and problem.item_of_fault == (1, 2, 2, 0)
    for method in ("A", "B"):
        o = optimal(tests, 4, method)  # type: ignore[arg-type]
        assert o.proven and reaches_same_matrix(o, tests, 4)
        assert (len(o.tests), o.total_cost) == brute_force(tests, 4, method)


def test_lower_bounds_information_and_sperner() -> None:
    # every singleton fault set: B needs 2^k >= 8 items (7 faults + no fault) -> 3, but singletons can only
    # give 7 tests; A needs 7 pairwise incomparable codes -> C(4, 2) = 6 < 7 <= C(5, 2) -> 5
    nf = 7
    singles = [Candidate(equations=1 << k, faults=1 << k, cost=1) for k in range(nf)]
    pairs = [Candidate(equations=1 << (nf + t), faults=fs, cost=1)
             for t, fs in enumerate(a | b for a, b in itertools.combinations([1 << k for k in range(nf)], 2))]
    big = [Candidate(equations=1 << 40, faults=0b1111111 ^ (1 << k), cost=1) for k in range(nf)]
    everything = singles + pairs + big
    assert root_lower_bound(reduce_problem([t.faults for t in everything], [1] * len(everything), nf, "B")) == 3
    assert root_lower_bound(reduce_problem([t.faults for t in everything], [1] * len(everything), nf, "A")) == 5
    # with only singletons the bound is not reached; the search proves the true optimum (nf tests)
    for method in ("A", "B"):
        o = optimal(singles, nf, method)  # type: ignore[arg-type]
        assert o.proven and len(o.tests) == nf and o.lower_bound == nf


def test_time_limit_returns_unproven_but_valid_selection() -> None:
    tests = random_tests(7, n=40, nf=9)
    o = optimal(tests, 9, "A", time_limit_s=0.0)
    assert reaches_same_matrix(o, tests, 9) and o.lower_bound <= len(o.tests)


def test_grouped_romo_optimal_not_worse_than_greedy(models_dir: pathlib.Path) -> None:
    st = load_model(models_dir / "romo_grouped.toml").structure()
    _, cands = mso_candidates(st, workers=1, progress=False)
    nf = st.nf
    o = optimal(cands, nf, "A", time_limit_s=15.0)
    g = greedy(cands, nf, "A")
    assert len(o.tests) <= len(g.tests) and 6 <= o.lower_bound <= len(o.tests)
    assert reaches_same_matrix(o, cands, nf)


@pytest.mark.parametrize("method", ["A", "B"])
@pytest.mark.parametrize("seed", range(4))
def test_cover_greedy_covers_every_required_pair(method: str, seed: int) -> None:
    from fdi_analysis.selection.exact import cover_greedy, cover_matrix

    tests = random_tests(seed, n=60, nf=8)
    problem = reduce_problem([t.faults for t in tests], [t.cost for t in tests], 8, method)
    cover = cover_matrix(problem)
    sel = cover_greedy(cover)
    assert np.array_equal(cover[sel].any(axis=0), cover.any(axis=0))
    assert len(sel) == len(set(sel))
