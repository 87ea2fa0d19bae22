"""The model file format: loading, templates, derived structure, and clear errors for bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fdi_analysis.model import ModelError
from fdi_analysis.model_loader import export_fdt_json, load_model
from fdi_analysis.structure import Structure

TANK = """
[model]
name = "tank"
[parameters]
a = { value = 2.0, unit = "1/s" }
b = { expr = "2*a", unit = "1/s" }
[[unknown]]
foreach = { n = ["h", "dh", "q"] }
name = "{n}"
[[known]]
name = "u"
[[known]]
name = "y"
[[fault]]
name = "fy"
[[fault]]
name = "fq"
[[equation]]
id = "e1"
expr = "dh = -a*h + q"
[[equation]]
id = "e2"
differential = ["dh", "h"]
[[equation]]
id = "e3"
expr = "q = b*u + fq"
[[equation]]
id = "e4"
expr = "y = h + fy"
"""


def write(tmp_path: Path, text: str, name: str = "m.toml") -> Path:
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def test_structure_is_derived_from_expressions(tmp_path: Path) -> None:
    m = load_model(write(tmp_path, TANK))
    st = m.structure()
    assert st.unknowns == ("h", "dh", "q")
    assert m.parameters["b"].value == pytest.approx(4.0)
    assert st.X.tolist() == [[1, 1, 1], [2, 3, 0], [0, 0, 1], [1, 0, 0]]
    assert st.Z.tolist() == [[0, 0], [0, 0], [1, 0], [0, 1]]
    assert st.F.tolist() == [[0, 0], [0, 0], [0, 1], [1, 0]]
    assert [e.kind for e in m.equations] == ["normal", "differential", "measurement", "measurement"]
    assert m.symbolic


def test_fdt_json_round_trip(tmp_path: Path) -> None:
    m = load_model(write(tmp_path, TANK))
    out = tmp_path / "tank.json"
    export_fdt_json(m, out)
    back = load_model(out)
    st, st2 = m.structure(), back.structure()
    assert st2.equations == st.equations and st2.unknowns == st.unknowns
    assert np.array_equal(st.X, st2.X) and np.array_equal(st.F, st2.F) and np.array_equal(st.Z, st2.Z)
    assert not back.symbolic
    assert Structure.from_fdt_json(out).to_fdt_dict() == st.to_fdt_dict()


def test_structural_only_model(tmp_path: Path) -> None:
    text = TANK.replace('expr = "q = b*u + fq"', 'unknowns = ["q"]\nknowns = ["u"]\nfaults = ["fq"]')
    m = load_model(write(tmp_path, text))
    assert not m.symbolic
    assert m.equation("e3").unknowns == ("q",) and m.equation("e3").faults == ("fq",)


@pytest.mark.parametrize(
    ("change", "needle"),
    [
        (('expr = "dh = -a*h + q"', 'expr = "dh = -a*h + qq"'), "equation 'e1': undeclared symbol 'qq'"),
        (('name = "u"', 'name = "h"'), "variable 'h' declared twice"),
        (('expr = "q = b*u + fq"', 'expr = "0 = b*u + fq"'), "equation 'e3': equation has no unknowns"),
        (('differential = ["dh", "h"]', 'differential = ["dh"]'), "equation 'e2': differential constraint needs"),
        (('differential = ["dh", "h"]', 'differential = ["dh", "hh"]'), "'hh' is not a declared unknown"),
        (('expr = "y = h + fy"', 'expr = "y = h + * fy"'), "equation 'e4': cannot parse"),
        (('expr = "y = h + fy"', 'expr = "y = h + fy = 2"'), "equation 'e4': more than one '='"),
        (('expr = "y = h + fy"', 'expr = "y = foo(h) + fy"'), "equation 'e4': unknown function 'foo'"),
        (('expr = "y = h + fy"', 'expr = "y = h"'), "fault 'fy' appears in no equation"),
    ],
)
def test_bad_input_names_file_equation_and_symbol(tmp_path: Path, change: tuple[str, str], needle: str) -> None:
    old, new = change
    assert old in TANK
    p = write(tmp_path, TANK.replace(old, new, 1))
    with pytest.raises(ModelError) as info:
        load_model(p)
    msg = str(info.value)
    assert str(p) in msg
    assert needle in msg


def test_undeclared_symbol_is_reported_as_symbol(tmp_path: Path) -> None:
    p = write(tmp_path, TANK.replace('expr = "dh = -a*h + q"', 'expr = "dh = -a*h + q + E"'))
    with pytest.raises(ModelError) as info:
        load_model(p)
    assert info.value.equation == "e1" and info.value.symbol == "E"


def test_not_valid_toml(tmp_path: Path) -> None:
    p = write(tmp_path, "[model\nname=")
    with pytest.raises(ModelError, match="not valid TOML"):
        load_model(p)


def test_malformed_fdt_json(tmp_path: Path) -> None:
    p = write(tmp_path, '{"X": [[1, 0], [0, 1]], "F": [[1]], "x": ["a"]}', "bad.json")
    with pytest.raises(ModelError, match=r"bad\.json"):
        load_model(p)


def test_extends_remove_and_eliminate(tmp_path: Path) -> None:
    write(tmp_path, TANK, "base.toml")
    derived = """
[model]
name = "tank2"
extends = "base.toml"
[[eliminate]]
variable = "q"
equation = "e3"
"""
    m = load_model(write(tmp_path, derived, "derived.toml"))
    e1 = m.equation("e1")
    assert [v.name for v in m.unknowns] == ["h", "dh"]
    assert e1.knowns == ("u",) and e1.faults == ("fq",)
    assert e1.merged_from == ("e1", "e3")
    assert "q" not in {str(s) for s in e1.residual.free_symbols}


def test_extends_cycle_is_an_error(tmp_path: Path) -> None:
    write(tmp_path, '[model]\nextends = "b.toml"\n', "a.toml")
    write(tmp_path, '[model]\nextends = "a.toml"\n', "b.toml")
    with pytest.raises(ModelError, match="cycle"):
        load_model(tmp_path / "a.toml")


def test_inline_derivative_made_explicit(tmp_path: Path) -> None:
    text = TANK.replace('expr = "dh = -a*h + q"', 'expr = "der(h) = -a*h + q"')
    text = text.replace('foreach = { n = ["h", "dh", "q"] }', 'foreach = { n = ["h", "q"] }')
    text = text.replace('[[equation]]\nid = "e2"\ndifferential = ["dh", "h"]\n', "")
    base = write(tmp_path, text, "base.toml")
    m = load_model(base)
    assert m.equation("e1").derivatives == ("h",)
    derived = write(tmp_path, '[model]\nextends = "base.toml"\nexplicit_derivatives = true\n', "x.toml")
    mx = load_model(derived)
    assert [v.name for v in mx.unknowns] == ["h", "q", "dh"]
    assert mx.equation("D.h").differential == ("dh", "h")
    assert mx.equation("e1").derivatives == ()
