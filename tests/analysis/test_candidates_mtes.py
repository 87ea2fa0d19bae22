"""MTES candidates: a selection source that never enumerates MSO sets, checked against the MSO candidates."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from fdi_analysis.cli import main
from fdi_analysis.fault_matrix import fault_matrix
from fdi_analysis.random_structures import sparse_random_structure
from fdi_analysis.selection import optimal, reaches_same_matrix
from fdi_analysis.selection.candidates import full_isolability_reached, mso_candidates, mtes_candidates


@pytest.mark.parametrize("seed", [3, 11, 23])
def test_mtes_candidates_reach_the_fault_matrix_of_all_msos(seed: int) -> None:
    st = sparse_random_structure(seed, 30, 4)
    _, msos = mso_candidates(st, workers=1, progress=False)
    _, mt = mtes_candidates(st)
    assert full_isolability_reached(st, mt)
    for method in ("A", "B"):
        all_mso = fault_matrix([c.faults for c in msos], st.nf, method)
        assert np.array_equal(fault_matrix([c.faults for c in mt], st.nf, method), all_mso)
        sel = optimal(mt, st.nf, method, time_limit_s=20.0)
        assert reaches_same_matrix(sel, msos, st.nf)


def test_mtes_candidates_are_cheapest_per_support_and_numbered() -> None:
    st = sparse_random_structure(5, 30, 4)
    result, cands = mtes_candidates(st)
    assert len({c.faults for c in cands}) == len(cands) == len({t.faults for t in result.mtes})
    assert [c.label for c in cands] == [f"MTES{k + 1}" for k in range(len(cands))]
    assert [c.cost for c in cands] == sorted(c.cost for c in cands)
    inc = st.incidence
    for c in cands:
        same = [t for t in result.mtes if t.faults == c.faults]
        unknowns = [int(inc[[e for e in range(st.ne) if t.equations >> e & 1]].any(axis=0).sum()) for t in same]
        assert c.cost == min(unknowns)


def test_select_with_mtes_candidates(tmp_path: Path) -> None:
    st = sparse_random_structure(3, 30, 4)
    path = tmp_path / "s.json"
    st.to_fdt_json(path)
    out = tmp_path / "o"
    assert main(["select", str(path), "--candidates", "mtes", "-o", str(out), "--no-progress"]) == 0
    data = json.loads((out / "selection.json").read_text())
    assert data["candidate_source"] == "MTES"
    for method in "AB":
        assert data["selections"][f"optimal {method}"]["tests"] <= data["selections"][f"greedy {method}"]["tests"]
