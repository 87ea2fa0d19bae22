"""DM decomposition and single-fault isolability, cross-checked against Fault Diagnosis Toolbox (PyPI).

FDT is an independent implementation (CSparse dmperm in C); it is a dev dependency, and these tests are
skipped with a message where it does not install.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fdi_analysis.dm import dulmage_mendelsohn, equivalence_classes, overdetermined_part
from fdi_analysis.isolability import isolability
from fdi_analysis.model_loader import load_model
from fdi_analysis.random_structures import random_structure
from fdi_analysis.structure import Structure

fdt = pytest.importorskip("faultdiagnosistoolbox", reason="faultdiagnosistoolbox (test oracle) not installed")
from faultdiagnosistoolbox import dmperm as fdt_dmperm  # noqa: E402

ROMO = ["romo_quasistatic", "romo_grouped", "romo_full_vertical"]


def fdt_model(st: Structure) -> object:
    return fdt.DiagnosisModel(
        {"type": "MatrixStruc", "X": st.X.astype(int), "F": st.F.astype(int), "Z": st.Z.astype(int),
         "x": list(st.unknowns), "f": list(st.faults), "z": list(st.knowns)}
    )


def random_matrix(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    ne, nx = int(rng.integers(5, 60)), int(rng.integers(5, 60))
    return (rng.random((ne, nx)) < rng.uniform(0.03, 0.2)).astype(np.int8)


def assert_same_dm(X: np.ndarray) -> None:
    ours = dulmage_mendelsohn(X)
    ref = fdt_dmperm.GetDMParts((X != 0).astype(np.float64))
    assert sorted(ours.plus_eqs) == sorted(int(i) for i in ref.Mp.row)
    assert sorted(ours.plus_vars) == sorted(int(i) for i in ref.Mp.col)
    assert sorted(ours.minus_eqs) == sorted(int(i) for i in ref.Mm.row)
    assert sorted(ours.minus_vars) == sorted(int(i) for i in ref.Mm.col)
    ref_blocks = {(tuple(sorted(int(i) for i in b.row)), tuple(sorted(int(i) for i in b.col))) for b in ref.M0}
    assert set(ours.zero_blocks) == ref_blocks
    # our block order is a solving order: once M+ is solved, a block needs only its own variables and
    # those of earlier blocks (never M- variables)
    known: set[int] = set(ours.plus_vars)
    for eqs, vs in ours.zero_blocks:
        known |= set(vs)
        for e in eqs:
            assert {int(v) for v in np.flatnonzero(X[e])} <= known


@pytest.mark.parametrize("seed", range(40))
def test_dm_random_matrices(seed: int) -> None:
    assert_same_dm(random_matrix(seed))


@pytest.mark.parametrize("name", ROMO)
def test_dm_romo(models_dir: Path, name: str) -> None:
    st = load_model(models_dir / f"{name}.toml").structure()
    assert_same_dm(st.X)
    # with fault equations removed there are non-trivial M0 and M- parts as well
    assert_same_dm(st.X[~st.F.any(axis=1)])


def fdt_isolable(st: Structure) -> np.ndarray:
    im = np.asarray(fdt_model(st).IsolabilityAnalysis(causality="mixed"))  # type: ignore[attr-defined]
    # FDT: im[i, j] = 1 when fault i can NOT be told apart from fault j
    return im == 0


@pytest.mark.parametrize("name", ROMO)
def test_isolability_romo(models_dir: Path, name: str) -> None:
    st = load_model(models_dir / f"{name}.toml").structure()
    res = isolability(st)
    np.testing.assert_array_equal(res.isolable, fdt_isolable(st))
    # FDT's DetectabilityAnalysis fails on faults that enter several equations (the tyre faults), so
    # detectability is checked against FDT's M+ directly.
    plus = set(int(e) for e in fdt_dmperm.Mplus(st.X, causality="mixed"))
    fdt_det = {st.faults[f] for f in range(st.nf) if plus & set(int(e) for e in np.flatnonzero(st.F[:, f]))}
    assert {st.faults[i] for i in np.flatnonzero(res.detectable)} == fdt_det


@pytest.mark.parametrize("seed", range(30))
def test_isolability_random(seed: int) -> None:
    rng = np.random.default_rng(1000 + seed)
    st = random_structure(seed, ne=int(rng.integers(20, 80)), redundancy=int(rng.integers(1, 8)),
                          nf=int(rng.integers(3, 15)))
    res = isolability(st)
    np.testing.assert_array_equal(res.isolable, fdt_isolable(st))


@pytest.mark.parametrize("seed", range(10))
def test_equivalence_classes_partition_the_overdetermined_part(seed: int) -> None:
    st = random_structure(seed, ne=40, redundancy=4, nf=5)
    plus = set(int(e) for e in overdetermined_part(st.X))
    classes = equivalence_classes(st.X)
    assert sorted(e for c in classes for e in c) == sorted(plus)
    for c in classes:  # removing any member removes exactly its class from M+
        for e in c:
            kept = set(int(x) for x in overdetermined_part(st.X, sorted(plus - {e})))
            assert plus - kept == set(c)
