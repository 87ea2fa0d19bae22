"""Every structure Fault Diagnosis Toolbox (FDT 0.12.5) loads and analyses loads here too, with the same results.

FDT's example models (the three it ships, Commault's and the small linear example written from their published
matrices, each also with the sensors FDT's sensor placement adds: repeated equation names) and large random
structures (beyond the former 256-equation limit) go through the FDT JSON loading path (`load_model` on a
.json file); DM decomposition, structural redundancy, MSO sets and MTES sets are compared with FDT's own.
What FDT accepts and this project used to refuse is a one-line warning; malformed files stay one-line errors
naming the file and the equation or variable.
"""

from __future__ import annotations

import importlib.util
import json
import sys
import warnings
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest

from fdi_analysis.dm import dulmage_mendelsohn
from fdi_analysis.model import ModelError
from fdi_analysis.model_loader import load_model
from fdi_analysis.mso import iter_msos, mtes
from fdi_analysis.random_structures import sparse_random_structure
from fdi_analysis.structure import Structure, StructureWarning

fdt = pytest.importorskip("faultdiagnosistoolbox", reason="faultdiagnosistoolbox (test oracle) not installed")

BENCH = Path(__file__).resolve().parents[2] / "analysis" / "bench"


def _bench_module(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(f"bench_{name}", BENCH / f"{name}.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


examples = _bench_module("fdt_examples")
EXAMPLES = examples.example_models()


def load_json(tmp_path: Path, d: dict[str, Any]) -> tuple[Structure, list[str]]:
    """Load an FDT JSON document through the product's loader; the structure and the warning lines."""
    p = tmp_path / "model.json"
    p.write_text(json.dumps(d), encoding="utf-8")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        st = load_model(p).structure()
    lines = [str(w.message) for w in caught if issubclass(w.category, StructureWarning)]
    return st, lines


def bitsets(sets: list[Any]) -> set[int]:
    return {sum(1 << int(e) for e in s) for s in sets}


def one_fault_per_equation(st: Structure) -> bool:
    """FDT's MTES assumes each fault in one equation and at most one fault per equation."""
    F = st.F != 0
    return bool((F.sum(axis=0) == 1).all() and (F.sum(axis=1) <= 1).all())


def assert_same_as_fdt(st: Structure, model: Any) -> None:
    ours = dulmage_mendelsohn(st.X)
    ref = model.GetDMParts()
    assert sorted(ours.plus_eqs) == sorted(int(i) for i in ref.Mp.row)
    assert sorted(ours.plus_vars) == sorted(int(i) for i in ref.Mp.col)
    assert sorted(ours.minus_eqs) == sorted(int(i) for i in ref.Mm.row)
    assert sorted(ours.minus_vars) == sorted(int(i) for i in ref.Mm.col)
    assert set(ours.zero_blocks) == {
        (tuple(sorted(int(i) for i in b.row)), tuple(sorted(int(i) for i in b.col))) for b in ref.M0
    }
    assert ours.redundancy == model.Redundancy()
    got = list(iter_msos(st))
    assert len(got) == len(set(got))
    assert set(got) == bitsets(model.MSO())
    if one_fault_per_equation(st):
        got_mtes = [t.equations for t in mtes(st).mtes]
        assert len(got_mtes) == len(set(got_mtes))
        assert set(got_mtes) == bitsets(model.MTES())


@pytest.mark.parametrize(("label", "model"), EXAMPLES, ids=[label for label, _ in EXAMPLES])
def test_fdt_example_models(tmp_path: Path, label: str, model: Any) -> None:
    st, lines = load_json(tmp_path, examples.fdt_dict(model))
    assert st.ne == model.X.shape[0] and st.nx == len(model.x) and st.nf == len(model.f)
    assert_same_as_fdt(st, model)
    repeated = len(model.e) - len(set(model.e))
    assert sum("repeats" in line for line in lines) == repeated


def test_examples_include_repeated_names() -> None:
    assert any(len(m.e) != len(set(m.e)) for _, m in EXAMPLES)


def fdt_model(st: Structure) -> Any:
    return fdt.DiagnosisModel(
        {"type": "MatrixStruc", "X": st.X.astype(int).tolist(), "F": st.F.astype(int).tolist(),
         "Z": st.Z.astype(int).tolist()}
    )


def padded(base: Structure, width: int, seed: int) -> Structure:
    """`base` with non-redundant equations inserted at random positions up to `width` equations."""
    rng = np.random.default_rng(seed)
    npad = width - base.ne
    X = np.zeros((width, base.nx + npad), dtype=np.int8)
    F = np.zeros((width, base.nf), dtype=np.int8)
    order = rng.permutation(width)
    pos_base, pos_pad = np.sort(order[: base.ne]), np.sort(order[base.ne :])
    X[pos_base, : base.nx] = base.X
    F[pos_base] = base.F
    for k, e in enumerate(pos_pad):
        X[e, base.nx + k] = 1
        X[e, rng.integers(base.nx + k + 1)] = 1
    return Structure.from_fdt_dict({"X": X.tolist(), "F": F.tolist(), "name": f"padded-{width}"})


@pytest.mark.parametrize(
    ("seed", "ne", "phi", "width"),
    [(21, 60, 5, 60), (22, 90, 6, 90), (23, 120, 4, 120), (24, 70, 5, 282), (25, 80, 6, 300)],
)
def test_random_structures_same_as_fdt(tmp_path: Path, seed: int, ne: int, phi: int, width: int) -> None:
    base = sparse_random_structure(seed, ne, phi, nf=10, one_fault_per_equation=True)
    st0 = padded(base, width, seed) if width > ne else base
    st, lines = load_json(tmp_path, st0.to_fdt_dict())
    assert st.ne == width and not lines
    assert_same_as_fdt(st, fdt_model(st))


def test_unused_known_and_repeated_names_load_with_one_line_warnings(tmp_path: Path) -> None:
    d = {
        "type": "MatrixStruc",
        "X": [[1, 0], [1, 1], [0, 1], [1, 0]],
        "F": [[1, 0], [0, 0], [0, 0], [0, 0]],
        "Z": [[1, 0], [0, 0], [0, 0], [1, 0]],
        "z": ["u1", "u3"],
        "e": ["e1", "e2", "e3", "e3"],
    }
    st, lines = load_json(tmp_path, d)
    assert st.equations == ("e1", "e2", "e3", "e3_2")
    assert lines == [
        "equation name 'e3' repeats; this one renamed to 'e3_2'",
        "known 'u3' appears in no equation; loaded, it takes no part in the analysis",
        "fault 'f2' appears in no equation; loaded, it takes no part in the analysis",
    ]
    assert all("\n" not in line for line in lines)
    assert_same_as_fdt(st, fdt.DiagnosisModel(d))


def test_varstruc_form_loads(tmp_path: Path) -> None:
    d = {"type": "VarStruc", "x": ["a", "b"], "f": ["f1"], "z": ["y1", "y2"],
         "rels": [["a", "y1"], ["a", "b"], ["b", "y2", "f1"], ["a", "b", "y2"]]}
    st, lines = load_json(tmp_path, d)
    assert st.X.tolist() == [[1, 0], [1, 1], [0, 1], [1, 1]]
    assert st.F.tolist() == [[0], [0], [1], [0]] and not lines
    assert_same_as_fdt(st, fdt.DiagnosisModel(d))


@pytest.mark.parametrize(
    ("d", "needle"),
    [
        ({"type": "VarStruc", "x": ["a"], "z": ["y"], "rels": [["a", "y"], ["a", "w"]]},
         "equation 2 of 'rels': variable 'w' is not declared"),
        ({"X": [[1, 0], [1, 4]], "e": ["p", "q"], "x": ["a", "b"]}, "equation 'q', variable 'b': X entry 4"),
        ({"X": [[3, 0], [1, 1]]}, "equation 'e1' is marked as a differential constraint"),
    ],
    ids=["undeclared-variable", "bad-entry", "bad-differential"],
)
def test_bad_input_is_one_line_naming_file_and_equation(tmp_path: Path, d: dict[str, Any], needle: str) -> None:
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(d), encoding="utf-8")
    with pytest.raises(ModelError) as exc:
        load_model(p)
    msg = str(exc.value)
    assert "\n" not in msg and "bad.json" in msg and needle in msg
