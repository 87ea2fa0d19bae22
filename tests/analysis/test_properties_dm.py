"""Property-based tests (hypothesis) of the Dulmage-Mendelsohn decomposition on random structures."""

from __future__ import annotations

import itertools

import numpy as np
from hypothesis import given, settings
from structure_strategies import structures

from fdi_analysis.dm import dulmage_mendelsohn, equivalence_classes, overdetermined_part, redundancy
from fdi_analysis.mso import reference
from fdi_analysis.structure import Structure

FAST = settings(max_examples=150, deadline=2000)


def _vars_of(st: Structure, eqs: list[int] | tuple[int, ...]) -> set[int]:
    return {int(v) for e in eqs for v in np.flatnonzero(st.incidence[e])}


def _brute_max_matching_size(A: np.ndarray) -> int:
    """Structural rank by brute force: the largest k with k equations matchable to k distinct unknowns."""
    ne, nx = A.shape
    for k in range(min(ne, nx), 0, -1):
        for rows in itertools.combinations(range(ne), k):
            for cols in itertools.permutations(range(nx), k):
                if all(A[r, c] for r, c in zip(rows, cols, strict=True)):
                    return k
    return 0


@FAST
@given(structures(max_eqs=9))
def test_dm_partition_and_matching(st: Structure) -> None:
    dm = dulmage_mendelsohn(st.X)
    A = st.incidence
    plus, minus, zero = set(dm.plus_eqs), set(dm.minus_eqs), set(dm.zero_eqs)
    # the three parts partition the equations and the unknowns
    assert plus | minus | zero == set(range(st.ne))
    assert not (plus & minus) and not (plus & zero) and not (minus & zero)
    pv, mv, zv = set(dm.plus_vars), set(dm.minus_vars), set(dm.zero_vars)
    assert pv | mv | zv == set(range(st.nx))
    assert not (pv & mv) and not (pv & zv) and not (mv & zv)
    # the matching is a matching along incidences, and maximum
    matched = [(e, v) for e, v in enumerate(dm.matching) if v >= 0]
    assert all(A[e, v] for e, v in matched)
    assert len({v for _, v in matched}) == len(matched)
    if st.ne <= 7 and st.nx <= 6:
        assert dm.structural_rank == _brute_max_matching_size(A)
    # M+ holds only its own unknowns and is structurally overdetermined; its redundancy is the model's
    assert _vars_of(st, dm.plus_eqs) <= pv
    assert dm.redundancy == st.ne - dm.structural_rank
    if plus:
        assert dm.redundancy >= 1
        assert set(overdetermined_part(st.X, list(dm.plus_eqs))) == plus
        sub = dulmage_mendelsohn(st.X[list(dm.plus_eqs)][:, list(dm.plus_vars)])
        assert not sub.minus_eqs and not sub.zero_blocks
    # M0 blocks are square and solvable in order (a block only uses unknowns of itself or earlier blocks)
    known: set[int] = set()
    for eqs, vs in dm.zero_blocks:
        assert len(eqs) == len(vs)
        assert _vars_of(st, eqs) - pv - mv <= known | set(vs)
        known |= set(vs)
    # M- is underdetermined
    if minus or mv:
        assert len(mv) > len(minus)
    # the reference implementation finds the same overdetermined part
    assert reference.mplus([frozenset(np.flatnonzero(r)) for r in A], frozenset(range(st.ne))) == frozenset(plus)


@FAST
@given(structures(max_eqs=9, min_redundancy=1))
def test_equivalence_classes_partition_mplus(st: Structure) -> None:
    plus = set(int(e) for e in overdetermined_part(st.X))
    classes = equivalence_classes(st.X)
    assert sorted(e for c in classes for e in c) == sorted(plus)
    for c in classes:  # removing any member of a class removes the whole class from M+, and nothing else
        for e in c:
            kept = set(int(x) for x in overdetermined_part(st.X, sorted(plus - {e})))
            assert not (kept & set(c))
    assert redundancy(st.X) == (len(plus) - len(_vars_of(st, sorted(plus))) if plus else 0)
