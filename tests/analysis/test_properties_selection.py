"""Property-based tests (hypothesis) of fault matrices and test selection: optimal is never larger than
greedy, both keep the isolability of all candidates, fault-matrix definitions hold."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as hst
from structure_strategies import structures

from fdi_analysis.fault_matrix import Candidate, Method, fault_matrix
from fdi_analysis.mso import isolability, isolability_from_signatures, iter_msos
from fdi_analysis.selection import greedy, optimal, reaches_same_matrix
from fdi_analysis.structure import Structure

FAST = settings(max_examples=100, deadline=5000)


@hst.composite
def candidate_sets(draw: hst.DrawFn) -> tuple[int, list[Candidate]]:
    nf = draw(hst.integers(min_value=1, max_value=7))
    n = draw(hst.integers(min_value=1, max_value=14))
    tests = [
        Candidate(
            equations=1 << t,
            faults=draw(hst.integers(min_value=1, max_value=(1 << nf) - 1)),
            cost=draw(hst.integers(min_value=1, max_value=20)),
            label=f"t{t}",
        )
        for t in range(n)
    ]
    return nf, tests


@FAST
@given(candidate_sets(), hst.sampled_from(["A", "B"]))
def test_fault_matrix_invariants(case: tuple[int, list[Candidate]], method: Method) -> None:
    nf, tests = case
    fs = [t.faults for t in tests]
    fm = fault_matrix(fs, nf, method)
    assert fm.shape == (nf + 1, nf + 1)
    assert fm.diagonal().all()
    assert (fault_matrix(fs, nf, "A") >= fault_matrix(fs, nf, "B")).all()  # B confuses only identical signatures
    if method == "B":
        assert (fm == fm.T).all()
    else:
        assert fm[0].all()  # "no fault" is explained by every fault
    # a fault covered by some test is never confused with "no fault"
    covered = 0
    for f in fs:
        covered |= f
    for k in range(nf):
        assert fm[k + 1, 0] == (not covered >> k & 1)
    # adding a test never makes the matrix worse (entries only clear)
    more = fault_matrix([*fs, (1 << nf) - 1], nf, method)
    assert (more <= fm).all()


@FAST
@given(candidate_sets(), hst.sampled_from(["A", "B"]))
def test_optimal_never_larger_than_greedy_and_keeps_isolability(
    case: tuple[int, list[Candidate]], method: Method
) -> None:
    nf, tests = case
    g = greedy(tests, nf, method)
    o = optimal(tests, nf, method, time_limit_s=10.0)
    assert o.proven
    assert len(o.tests) <= len(g.tests)
    if len(o.tests) == len(g.tests):
        assert o.total_cost <= g.total_cost
    all_fm = fault_matrix([t.faults for t in tests], nf, method)
    assert (g.matrix(nf) == all_fm).all() and (o.matrix(nf) == all_fm).all()
    assert reaches_same_matrix(o, tests, nf) and reaches_same_matrix(g, tests, nf)
    if method == "A":  # method A's matrix is exactly one-sided isolability (a test sees i and not j)
        full_iso = isolability_from_signatures(nf, {t.faults for t in tests})
        assert (isolability_from_signatures(nf, {t.faults for t in o.tests}) == full_iso).all()
        assert (isolability_from_signatures(nf, {t.faults for t in g.tests}) == full_iso).all()
    assert set(o.tests) <= set(tests) and set(g.tests) <= set(tests)


@settings(max_examples=60, deadline=5000)
@given(structures(max_eqs=11, max_faults=5, min_redundancy=1))
def test_selected_msos_keep_structural_isolability(st: Structure) -> None:
    feq = [sum(1 << int(e) for e in np.flatnonzero(st.F[:, f])) for f in range(st.nf)]
    tests = []
    for m in iter_msos(st):
        fs = sum(1 << f for f in range(st.nf) if m & feq[f])
        if fs:
            tests.append(Candidate(equations=m, faults=fs, cost=m.bit_count() - 1))
    structural = isolability(st)
    for method in ("A", "B"):
        sel = optimal(tests, st.nf, method, time_limit_s=10.0)
        assert len(sel.tests) <= len(greedy(tests, st.nf, method).tests)
        assert (sel.matrix(st.nf) == fault_matrix([t.faults for t in tests], st.nf, method)).all()
        sel_iso = isolability_from_signatures(st.nf, {t.faults for t in sel.tests})
        if method == "A":  # full structural isolability with the selected residuals only
            assert (sel_iso == structural.isolable).all()
        else:  # exoneration: mutually isolable pairs keep distinct signatures, detectable faults stay detected
            sig = [{t.faults for t in sel.tests if t.faults >> k & 1} for k in range(st.nf)]
            for i in range(st.nf):
                assert bool(sig[i]) == bool(structural.detectable[i])
                for j in range(st.nf):
                    if structural.isolable[i, j] or structural.isolable[j, i]:
                        assert sig[i] != sig[j]


@FAST
@given(candidate_sets(), hst.sampled_from(["A", "B"]))
def test_greedy_on_the_reduced_problem_is_the_papers_greedy(case: tuple[int, list[Candidate]], method: Method) -> None:
    from fdi_analysis.selection import _greedy_columns, cheapest_per_signature
    from fdi_analysis.selection.exact import cover_matrix, reduce_problem

    nf, tests = case
    cands = cheapest_per_signature(tests)
    problem = reduce_problem([t.faults for t in cands], [t.cost for t in cands], nf, method)
    index = {c: i for i, c in enumerate(problem.columns)}
    expected = set()
    for t in greedy(cands, nf, method).tests:
        mask = 0
        for k in range(nf):
            if t.faults >> k & 1:
                mask |= 1 << problem.item_of_fault[k]
        expected.add(index[mask])
    assert set(_greedy_columns(problem, cands, cover_matrix(problem))) == expected


@settings(max_examples=40, deadline=None)
@given(candidate_sets(), hst.sampled_from(["A", "B"]))
def test_fallback_without_sat_gives_the_same_optimum(case: tuple[int, list[Candidate]], method: Method) -> None:
    """Without python-sat the code search decides; count and cost must equal the SAT answer."""
    from unittest import mock

    from fdi_analysis.selection import sat

    nf, tests = case
    with_sat = optimal(tests, nf, method, time_limit_s=10.0)
    with mock.patch.object(sat, "HAVE_SAT", False):
        without = optimal(tests, nf, method, time_limit_s=10.0)
    assert with_sat.proven and without.proven
    assert len(with_sat.tests) == len(without.tests)
    assert with_sat.total_cost == without.total_cost
