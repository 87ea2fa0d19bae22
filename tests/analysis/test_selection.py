"""Fault matrices (methods A and B) and test selection: greedy as in the paper, optimal by MILP."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from msos_bruteforce import all_msos

from fdi_analysis.fault_matrix import Candidate, fault_matrix
from fdi_analysis.isolability import isolability
from fdi_analysis.random_structures import random_structure
from fdi_analysis.selection import cheapest_per_signature, greedy, optimal, reaches_same_matrix


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


def test_greedy_keeps_cheapest_first() -> None:
    tests = [Candidate(equations=0b1, faults=0b11, cost=9), Candidate(equations=0b10, faults=0b11, cost=3),
             Candidate(equations=0b100, faults=0b01, cost=5)]
    g = greedy(tests, 2, "B")
    assert [t.cost for t in g.tests] == [3, 5]
    assert [t.cost for t in cheapest_per_signature(tests)] == [3, 5]
