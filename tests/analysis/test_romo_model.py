"""The ROMO model files: counts of the paper, redundancy 9, detectability, the MSO sets of Table II rows 1-4."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from msos_bruteforce import all_msos

from fdi_analysis.dm import redundancy
from fdi_analysis.isolability import isolability
from fdi_analysis.model_loader import load_model


def test_quasistatic_counts(models_dir: Path) -> None:
    m = load_model(models_dir / "romo_quasistatic.toml")
    c = m.counts()
    assert (c["normal_equations"], c["measurement_equations"], c["unknowns"], c["knowns"], c["faults"]) == (
        63, 19, 73, 19, 25)
    assert m.symbolic
    knowns = {v.name for v in m.knowns}
    assert knowns == {"ax_m", "ay_m", "psidot_m", "vx_m", "vy_m", *(f"delta{i}_m" for i in range(1, 5)),
                      *(f"iTM{i}_m" for i in range(1, 5)), "P_f_m", "P_r_m", *(f"omega{i}_m" for i in range(1, 5))}
    # one measurement equation per measurement
    st = m.structure()
    assert (st.Z.sum(axis=0) == 1).all() and (st.Z.sum(axis=1) <= 1).all()
    assert redundancy(st.X) == 9


def test_table_one_fault_equations(models_dir: Path) -> None:
    m = load_model(models_dir / "romo_quasistatic.toml")
    where = {f.name: [e.id for e in m.equations if f.name in e.faults] for f in m.faults}
    assert where["f1"] == ["S1"] and where["f5"] == ["S5"]
    assert [where[f"f{k}"] for k in range(6, 10)] == [[f"S.delta{i}"] for i in range(1, 5)]
    assert [where[f"f{k}"] for k in range(10, 14)] == [[f"W{i}.TM"] for i in range(1, 5)]
    assert [where[f"f{k}"] for k in range(14, 18)] == [[f"W{i}.DB"] for i in range(1, 5)]
    assert [where[f"f{k}"] for k in range(18, 22)] == [[f"W{i}.FL", f"W{i}.FS"] for i in range(1, 5)]
    assert [where[f"f{k}"] for k in range(22, 26)] == [[f"S.omega{i}"] for i in range(1, 5)]


@pytest.mark.parametrize(
    ("name", "eqs", "unknowns"),
    [("romo_quasistatic", 82, 73), ("romo_grouped", 41, 32), ("romo_full_vertical", 114, 105)],
)
def test_variants_have_redundancy_nine_and_all_faults_detectable(
    models_dir: Path, name: str, eqs: int, unknowns: int
) -> None:
    m = load_model(models_dir / f"{name}.toml")
    st = m.structure()
    assert (st.ne, st.nx) == (eqs, unknowns)
    assert redundancy(st.X) == 9
    iso = isolability(st)
    assert iso.detectable.all()
    pairs = {(st.faults[i], st.faults[j]) for i, j in iso.non_isolable_pairs()}
    assert pairs == {("f10", "f14"), ("f11", "f15"), ("f12", "f16"), ("f13", "f17")}


@pytest.mark.parametrize(
    ("faults", "n_unknowns", "paper_constraints"),
    [
        ({1, 3, 4, 5}, 5, {"K1", "D1"}),
        ({2, 3, 4, 5}, 5, {"K2", "D2"}),
        ({1, 2, 3, 4}, 7, {"K1", "K2", "D1", "D2"}),
        ({1, 2, 3, 5}, 7, {"K1", "K2", "D1", "D2"}),
    ],
)
def test_table_two_rows_one_to_four(
    models_dir: Path, faults: set[int], n_unknowns: int, paper_constraints: set[str]
) -> None:
    """Search, among equations whose faults lie in the row's fault set, the MSOs with exactly that set."""
    st = load_model(models_dir / "romo_quasistatic.toml").structure()
    target = np.zeros(st.nf, dtype=bool)
    target[[f - 1 for f in faults]] = True
    allowed = np.flatnonzero(~(st.F.astype(bool) & ~target).any(axis=1))
    hits = [m for m in all_msos(st, allowed) if np.array_equal(st.equation_faults(sorted(m)), target)]
    sizes = sorted(int((st.X[sorted(m)] != 0).any(axis=0).sum()) for m in hits)
    assert n_unknowns in sizes
    smallest = min(hits, key=len)
    names = {st.equations[e] for e in smallest}
    assert paper_constraints <= names
    assert int((st.X[sorted(smallest)] != 0).any(axis=0).sum()) == n_unknowns
