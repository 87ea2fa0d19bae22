"""MSO engine: C core == pure-Python reference == Fault Diagnosis Toolbox, streaming, parallel, Ctrl-C."""

from __future__ import annotations

import os
import signal
import subprocess
from pathlib import Path

import numpy as np
import pytest

from fdi_analysis.model_loader import load_model
from fdi_analysis.mso import MsoSummary, bits, find_msos, iter_msos, mtes, prepare, reference
from fdi_analysis.mso.engine import split_tasks
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
    import faultdiagnosistoolbox as fdt
    from faultdiagnosistoolbox import dmperm

    HAVE_FDT = True
except ImportError:  # pragma: no cover - depends on the environment
    HAVE_FDT = False
needs_fdt = pytest.mark.skipif(not HAVE_FDT, reason="faultdiagnosistoolbox not importable (pip install '.[dev]')")


def random_structure(seed: int, ne: int, phi: int, maxdeg: int = 3, nf: int = 12, mindeg: int = 1) -> Structure:
    return sparse_random_structure(seed, ne, phi, nf=nf, maxdeg=maxdeg, mindeg=mindeg)


def fdt_msos(s: Structure) -> set[int]:
    return {sum(1 << int(e) for e in m) for m in dmperm.MSO(s.X)}


def fdt_example_structures() -> list[Structure]:
    from faultdiagnosistoolbox import models

    out = []
    for m in (models.three_tank, models.electric_motor, models.induction_motor):
        out.append(Structure.from_fdt_dict({"X": m.X.tolist(), "F": m.F.tolist(), "Z": m.Z.tolist(), "name": m.name}))
    return out


SMALL = [(seed, 14 + seed % 7, 2 + seed % 4) for seed in range(12)]
# (seed, equations, nominal redundancy); the redundancy of the overdetermined part is 3 to 14
MEDIUM = [(100, 40, 3), (101, 60, 5), (102, 80, 6), (105, 70, 8)]


@needs_fdt
def test_fdt_example_models_match() -> None:
    for s in fdt_example_structures():
        ours = list(iter_msos(s))
        assert len(ours) == len(set(ours)), s.name
        assert set(ours) == reference.msos(s) == fdt_msos(s), s.name
        assert len(ours) > 0


@pytest.mark.parametrize(("seed", "ne", "phi"), SMALL)
def test_small_random_matches_reference(seed: int, ne: int, phi: int) -> None:
    s = random_structure(seed, ne, phi)
    ours = list(iter_msos(s))
    assert len(ours) == len(set(ours))
    assert set(ours) == reference.msos(s)
    if HAVE_FDT:
        assert set(ours) == fdt_msos(s)


@needs_fdt
@pytest.mark.parametrize(("seed", "ne", "phi"), MEDIUM)
def test_medium_random_matches_fdt(seed: int, ne: int, phi: int) -> None:
    s = random_structure(seed, ne, phi, maxdeg=3)
    ours = list(iter_msos(s))
    theirs = fdt_msos(s)
    assert len(ours) == len(set(ours)) == len(theirs)
    assert set(ours) == theirs


@pytest.mark.parametrize("width", [130, 250, 282, 700])
def test_wide_bitsets_same_msos_after_padding(width: int) -> None:
    """More than 128 equations (3, 4, 5 and 12-word bitsets): pad a structure with non-redundant equations at
    random positions; the MSO sets are the original ones under the index map."""
    base = random_structure(102, 80, 6)
    rng = np.random.default_rng(width)
    npad = width - base.ne
    X = np.zeros((width, base.nx + npad), dtype=np.int8)
    F = np.zeros((width, base.nf), dtype=np.int8)
    order = rng.permutation(width)
    pos_base = np.sort(order[: base.ne])
    pos_pad = np.sort(order[base.ne :])
    X[pos_base, : base.nx] = base.X
    F[pos_base] = base.F
    for k, e in enumerate(pos_pad):
        X[e, base.nx + k] = 1  # private unknown: never overdetermined
        X[e, rng.integers(base.nx)] = 1
    wide = Structure.from_fdt_dict({"X": X.tolist(), "F": F.tolist()})
    expected = {sum(1 << int(pos_base[e]) for e in bits(m)) for m in iter_msos(base)}
    got = list(iter_msos(wide))
    assert len(got) == len(set(got)) == len(expected) > 100
    assert set(got) == expected
    assert max(m.bit_length() for m in got) > 128 or width < 200
    if HAVE_FDT:
        assert set(got) == fdt_msos(wide)


def test_each_mso_has_redundancy_one_and_is_minimal() -> None:
    s = random_structure(7, 30, 4)
    p = prepare(s)
    inc = s.incidence
    for m in iter_msos(p):
        eqs = bits(m)
        nvars = int(inc[eqs].any(axis=0).sum())
        assert len(eqs) - nvars == 1
        for e in eqs:  # removing any equation leaves nothing overdetermined
            from fdi_analysis.mso import mplus

            assert mplus(p, m & ~(1 << e)) == 0


def _aggregate_python(s: Structure, sets: list[int]) -> tuple[int, dict[int, int], dict[int, tuple[int, int, int]]]:
    hist: dict[int, int] = {}
    sigs: dict[int, tuple[int, int, int]] = {}
    for m in sets:
        k = m.bit_count()
        hist[k] = hist.get(k, 0) + 1
        f = reference.signature(s, m)
        c, size, best = sigs.get(f, (0, 10**9, 0))
        key_new = (k, bits(m))
        if key_new < (size, bits(best)):
            size, best = k, m
        sigs[f] = (c + 1, size, best)
    return len(sets), hist, sigs


@pytest.mark.parametrize("seed", [3, 11, 12])
def test_streaming_aggregation_equals_aggregation_of_yielded_sets(seed: int) -> None:
    s = random_structure(seed, 40, 5)
    sets = list(iter_msos(s))
    count, hist, sigs = _aggregate_python(s, sets)
    summary = find_msos(s, workers=1, progress=False)
    assert summary.complete
    assert summary.count == count
    assert summary.by_equations == hist
    assert {e.faults: (e.count, e.smallest_size, e.smallest) for e in summary.signatures} == sigs


def test_task_split_is_an_exact_partition() -> None:
    s = random_structure(5, 50, 6)
    p = prepare(s)
    from fdi_analysis.mso import _core

    tasks = split_tasks(p, 40)
    assert len(tasks) > 4
    seen: list[int] = []
    for t_s, t_r in tasks:
        it = _core.iter_new(p.model, t_s, t_r)
        while chunk := _core.iter_next(it, 1000):
            seen.extend(chunk)
    assert len(seen) == len(set(seen))
    assert set(seen) == set(iter_msos(p))


def test_parallel_equals_serial() -> None:
    s = random_structure(21, 70, 7)
    a = find_msos(s, workers=1, progress=False)
    b = find_msos(s, workers=2, progress=False, tasks_per_worker=16)
    assert a.count > 1000
    assert b.tasks > 2
    assert (a.count, a.by_equations, a.signatures) == (b.count, b.by_equations, b.signatures)


def test_grouped_romo_parallel_equals_serial_and_reduction_free() -> None:
    g = romo("grouped")
    a = find_msos(g, workers=2, progress=False)
    b = find_msos(g, workers=1, progress=False)
    assert a.complete and b.complete
    assert (a.count, a.by_equations, a.signatures) == (b.count, b.by_equations, b.signatures)
    assert sum(a.by_equations.values()) == a.count == sum(e.count for e in a.signatures)


@pytest.mark.parametrize("workers", [1, 2])
def test_ctrl_c_gives_partial_result(workers: int) -> None:
    g = romo("grouped")
    full = find_msos(g, workers=1, progress=False).count
    # like Ctrl-C: SIGINT from outside (a thread could not run while the C loop holds the GIL). On a loaded
    # machine the signal may come only after the search ended (the result is then complete, and equal to the
    # full one); such a run proves nothing and is repeated with an earlier signal.
    # A process started in the background by a non-interactive shell inherits SIGINT ignored (POSIX), so
    # Python has no KeyboardInterrupt handler there: install it as an interactive session has it.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        part, sent_during_search = _interrupt_search(g, workers)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert sent_during_search and part is not None, "SIGINT never arrived during the search"
    assert not part.complete
    assert 0 <= part.count < full


def _interrupt_search(g: Structure, workers: int) -> tuple[MsoSummary | None, bool]:
    part = None
    sent_during_search = False
    for delay in (0.3, 0.15, 0.08, 0.04):
        killer = subprocess.Popen(["sh", "-c", f"sleep {delay}; kill -INT {os.getpid()}"])
        part = None
        try:
            part = find_msos(g, workers=workers, progress=False, tasks_per_worker=8)
            killer.wait()
            # a signal that came after every task finished leaves a complete result: the search had ended
            sent_during_search = not part.complete
        except KeyboardInterrupt:  # arrived after find_msos returned
            killer.wait()
            sent_during_search = False
        if sent_during_search:
            break
    return part, sent_during_search


def test_no_size_limit_at_256_equations() -> None:
    s = Structure.from_fdt_dict({"X": np.eye(300, 10, dtype=int).tolist()})
    # the 290 equations without unknowns are one MSO set each
    assert find_msos(s, progress=False).count == sum(1 for _ in iter_msos(s)) == 290


@pytest.mark.parametrize(
    ("ne", "phi", "nf", "faulty"), [(90, 6, 64, 50), (90, 6, 65, 50), (90, 6, 150, 50), (70, 4, 150, 70)]
)
def test_more_than_64_faults_keep_their_signatures(ne: int, phi: int, nf: int, faulty: int) -> None:
    """The engine keys signatures on 64 bits; above 64 faults it keys on distinct fault rows and the keys are
    merged back into fault sets (over 64 distinct rows the signatures come from the yielded sets): the
    signature table equals the one computed from the yielded sets, and MTES carry their fault sets."""
    base = random_structure(11, ne, phi)
    F = np.zeros((base.ne, nf), dtype=np.int8)
    rng = np.random.default_rng(nf + faulty)
    for j in range(nf):  # faults on `faulty` equations, some on two
        F[rng.integers(faulty, size=1 + j % 2), j] = 1
    s = Structure.from_fdt_dict({"X": base.X.tolist(), "F": F.tolist()})
    p = prepare(s)
    expected: dict[int, int] = {}
    for m in iter_msos(s):
        f = p.faults_of(m)
        expected[f] = expected.get(f, 0) + 1
    summary = find_msos(s, workers=1, progress=False)
    assert {e.faults: e.count for e in summary.signatures} == expected
    assert summary.count == sum(expected.values())
    assert max(expected).bit_length() > 64 or nf < 100
    assert p.keyed == (faulty == 50)
    assert all(t.faults == p.faults_of(t.equations) for t in mtes(s).mtes)


def test_no_redundancy_gives_no_mso() -> None:
    s = Structure.from_fdt_dict({"X": np.eye(5, dtype=int).tolist()})
    assert find_msos(s, progress=False).count == 0
    assert list(iter_msos(s)) == []


@needs_fdt
def test_fdt_version_is_the_measured_one() -> None:
    assert fdt.__version__.startswith("0.12")
