"""MTES, structural isolability and the intermediate-variable reduction (paper's step 4)."""

from __future__ import annotations

from functools import reduce
from pathlib import Path

import numpy as np
import pytest

from fdi_analysis.model_loader import load_model
from fdi_analysis.mso import (
    find_msos,
    isolability,
    isolability_from_signatures,
    iter_msos,
    minimal_signatures,
    mtes,
    reduce_intermediate,
    reference,
)
from fdi_analysis.random_structures import sparse_random_structure
from fdi_analysis.structure import Structure

MODELS = Path(__file__).resolve().parents[2] / "analysis" / "models"


def romo(name: str) -> Structure:
    """A ROMO model of the repository as a structure: grouped (41 equations), quasistatic (82) or full
    (the full vertical dynamics, 115)."""
    files = {"grouped": "romo_grouped.toml", "quasistatic": "romo_quasistatic.toml",
             "full": "romo_full_vertical.toml"}
    return load_model(MODELS / files[name]).structure()

try:
    from faultdiagnosistoolbox import DiagnosisModel

    HAVE_FDT = True
except ImportError:  # pragma: no cover
    HAVE_FDT = False


def random_structure(seed: int, ne: int, phi: int, nf: int = 8, maxdeg: int = 3) -> Structure:
    return sparse_random_structure(seed, ne, phi, nf=nf, maxdeg=maxdeg, one_fault_per_equation=True)


SEEDS = range(10)


@pytest.mark.parametrize("seed", SEEDS)
def test_mtes_matches_brute_force(seed: int) -> None:
    s = random_structure(seed, 16 + seed % 5, 3 + seed % 3)
    ours = {(t.equations, t.faults) for t in mtes(s).mtes}
    assert ours == reference.mtes(s)


@pytest.mark.skipif(not HAVE_FDT, reason="faultdiagnosistoolbox not importable")
@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_mtes_matches_fdt(seed: int) -> None:
    s = random_structure(seed, 30, 5)
    model = DiagnosisModel(
        {"type": "MatrixStruc", "X": s.X.tolist(), "F": s.F.tolist(), "Z": np.zeros((s.ne, 0)).tolist()}
    )
    theirs = {sum(1 << int(e) for e in m) for m in model.MTES()}
    ours = [t.equations for t in mtes(s).mtes]
    assert len(ours) == len(set(ours))
    assert set(ours) == theirs


@pytest.mark.parametrize("seed", SEEDS)
def test_isolability_equals_definition_and_mso_signatures(seed: int) -> None:
    s = random_structure(seed, 20, 4)
    det, iso = reference.isolability(s)
    got = isolability(s)
    assert got.detectable.tolist() == det
    assert got.isolable.tolist() == iso
    sigs = {reference.signature(s, m) for m in iter_msos(s)}
    assert (isolability_from_signatures(s.nf, sigs) == got.isolable).all()
    tes = {t.faults for t in mtes(s, all_tes=True).tes}
    assert (isolability_from_signatures(s.nf, tes) == got.isolable).all()


def test_minimal_signatures() -> None:
    assert minimal_signatures({0b011, 0b001, 0b110, 0b100, 0b111}) == frozenset({0b001, 0b100})


def test_romo_grouped_isolability_from_all_msos_equals_dm() -> None:
    g = romo("grouped")
    summary = find_msos(g, workers=2, progress=False)
    from_msos = isolability_from_signatures(g.nf, summary.signature_set())
    direct = isolability(g)
    assert (from_msos == direct.isolable).all()
    assert direct.detectable.all()


def test_romo_full_isolability_is_fast() -> None:
    g = romo("full")
    res = isolability(g)
    assert res.elapsed_s < 5.0
    assert res.detectable.all()
    assert len(res.non_isolable_pairs()) > 0


def _union_closed(kept: set[int], lost: set[int]) -> bool:
    """Every lost signature is the union of kept signatures it contains."""
    return all(reduce(lambda a, b: a | b, [k for k in kept if k & ~x == 0], 0) == x for x in lost)


@pytest.mark.parametrize("seed", range(12))
def test_reduction_keeps_isolability_and_only_drops_low_priority_msos(seed: int) -> None:
    s = random_structure(100 + seed, 22, 5, nf=10)
    red = reduce_intermediate(s)
    r = red.structure
    assert r.ne == s.ne - len(red.intermediate)
    assert r.nx == s.nx - len(red.intermediate)
    a, b = isolability(s), isolability(r)
    assert (a.isolable == b.isolable).all()
    assert (a.detectable == b.detectable).all()
    full = {reference.signature(s, m) for m in iter_msos(s)}
    reduced = {reference.signature(r, m) for m in iter_msos(r)}
    assert reduced <= full
    assert _union_closed(reduced, full - reduced)


def test_reduction_finds_a_chain() -> None:
    # e0: x0 = g(z) (fault-free) ; e1: x1 = h(x0) (fault-free) ; e2, e3: faulty equations in x1, x2
    X = [[1, 0, 0], [1, 1, 0], [0, 1, 1], [0, 0, 1]]
    F = [[0, 0], [0, 0], [1, 0], [0, 1]]
    s = Structure.from_fdt_dict({"X": X, "F": F, "x": ["a", "b", "c"]})
    red = reduce_intermediate(s)
    assert red.intermediate == (("a", "e1"), ("b", "e2"))
    assert red.structure.unknowns == ("c",)
    assert red.new_knowns == {"a": "a~", "b": "b~"}
    assert red.structure.Z[:, -1].tolist() == [1, 0]  # b~ enters e3 (first kept equation)


@pytest.mark.parametrize("name", ["quasistatic", "full"])
def test_reduction_on_romo_keeps_isolability(name: str) -> None:
    g = romo(name)
    red = reduce_intermediate(g)
    assert len(red.intermediate) > 0
    a, b = isolability(g), isolability(red.structure)
    assert (a.isolable == b.isolable).all()
    assert (a.detectable == b.detectable).all()
