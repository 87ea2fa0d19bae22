"""Property-based tests (hypothesis): native MSO engine vs the pure-Python reference, MSO minimality,
isolability against its definition."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from structure_strategies import structures

from fdi_analysis import isolability as iso_dm
from fdi_analysis.dm import overdetermined_part, redundancy
from fdi_analysis.mso import bits, isolability, iter_msos, reference
from fdi_analysis.structure import Structure

FAST = settings(max_examples=150, deadline=3000)


@settings(max_examples=80, deadline=3000)
@given(structures(max_eqs=10, min_redundancy=1))
def test_engine_equals_reference_and_msos_are_minimal(st: Structure) -> None:
    ours = list(iter_msos(st))
    assert len(ours) == len(set(ours))  # each MSO once
    assert set(ours) == reference.msos(st)
    plus = set(int(e) for e in overdetermined_part(st.X))
    for m in ours:
        eqs = bits(m)
        assert set(eqs) <= plus
        assert redundancy(st.X, eqs) == 1
        assert set(int(e) for e in overdetermined_part(st.X, eqs)) == set(eqs)  # proper SO
        for e in eqs:  # minimal: no proper subset is overdetermined
            assert overdetermined_part(st.X, [x for x in eqs if x != e]).size == 0
    # M+ is the union of the MSO sets
    union = 0
    for m in ours:
        union |= m
    assert set(bits(union)) == plus


@FAST
@given(structures(max_eqs=10, max_faults=5))
def test_isolability_matches_definition(st: Structure) -> None:
    msos = list(iter_msos(st))
    feq = [sum(1 << int(e) for e in np.flatnonzero(st.F[:, f])) for f in range(st.nf)]
    # definition via tests: i is isolable from j when some MSO (a residual) is sensitive to i and not to j
    det = [any(m & feq[i] for m in msos) for i in range(st.nf)]
    iso = [[i != j and any(m & feq[i] and not m & feq[j] for m in msos) for j in range(st.nf)] for i in range(st.nf)]
    ref_det, ref_iso = reference.isolability(st)
    native = isolability(st)
    dm_based = iso_dm.isolability(st)
    assert list(native.detectable) == det == ref_det == list(dm_based.detectable)
    assert native.isolable.tolist() == iso == ref_iso == dm_based.isolable.tolist()
    # classes: detectable faults, mutually non-isolable within a class
    for c in dm_based.classes:
        for i in c:
            assert det[i]
            if len(c) > 1:  # each member is mutually non-isolable from some other member of its class
                assert any(not iso[i][j] and not iso[j][i] for j in c if j != i)
    in_class = sorted(i for c in dm_based.classes for i in c)
    assert in_class == [i for i in range(st.nf) if det[i]]
