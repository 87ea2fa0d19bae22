"""Bad model input: malformed files, structurally singular models, models without redundancy, faults on no
equation. Each gives a clear error (or a reported problem) naming what is wrong, never a traceback."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fdi_analysis.model import ModelError
from fdi_analysis.model_loader import load_model
from fdi_analysis.summary import summarize

HEAD = '[model]\nname = "m"\n'


def var(role: str, *names: str) -> str:
    return "".join(f'[[{role}]]\nname = "{n}"\n' for n in names)


def eq(eid: str, body: str) -> str:
    return f'[[equation]]\nid = "{eid}"\n{body}\n'


def write(tmp_path: Path, text: str | bytes, name: str = "m.toml") -> Path:
    p = tmp_path / name
    if isinstance(text, bytes):
        p.write_bytes(text)
    else:
        p.write_text(text, encoding="utf-8")
    return p


def load_error(path: Path) -> str:
    with pytest.raises(ModelError) as info:
        load_model(path)
    msg = str(info.value)
    assert msg.startswith(str(path)), msg  # the file is named first, once
    assert msg.count(str(path)) == 1, msg
    return msg


GOOD_VARS = var("unknown", "x") + var("known", "u", "y") + var("fault", "f1")


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        (b"\x00\xff\xfe[[[", "not a UTF-8 text file"),
        ("", "the model has no equations"),
        (HEAD + GOOD_VARS, "the model has no equations"),
        (HEAD + "[parameters]\np = { value = \"abc\" }\n" + GOOD_VARS + eq("e1", 'expr = "x = p*u + f1"'),
         "parameter 'p': 'value' must be a finite number, got 'abc'"),
        (HEAD + "[parameters]\np = { value = nan }\n" + GOOD_VARS + eq("e1", 'expr = "x = p*u + f1"'),
         "parameter 'p': 'value' must be a finite number"),
        (HEAD + "[parameters]\np = { expr = \"1/0\" }\n" + GOOD_VARS + eq("e1", 'expr = "x = p*u + f1"'),
         "parameter 'p'"),
        (HEAD + GOOD_VARS + eq("e1", "expr = 3"), "equation 'e1': 'expr' must be a string"),
        (HEAD + GOOD_VARS + eq("e1", 'unknowns = "x"\nfaults = ["f1"]'), "equation 'e1': 'unknowns' must be a list"),
        (HEAD + GOOD_VARS + eq("e1", 'expr = "x = u + f1"') + eq("e2", 'expr = "y = x"') + "[[fault]]\nname = 'f2'\n",
         "fault 'f2' appears in no equation"),
        (HEAD + GOOD_VARS + eq("e1", 'unknowns = ["x"]\nfaults = ["u"]'),
         "equation 'e1': 'u' is listed under faults but declared as known"),
        ("bogus = 1\n" + HEAD + GOOD_VARS, "unknown top-level key 'bogus'"),
        (HEAD + "extend = 'base.toml'\n" + GOOD_VARS, "unknown key 'extend' in [model]"),
        ("[model\n", "not valid TOML"),
    ],
    ids=["binary", "empty", "no-equations", "param-string", "param-nan", "param-div0", "expr-number",
         "list-as-string", "fault-on-no-equation", "fault-role", "top-level-key", "model-key", "toml-syntax"],
)
def test_malformed_toml_names_what_is_wrong(tmp_path: Path, text: str | bytes, needle: str) -> None:
    assert needle in load_error(write(tmp_path, text))


@pytest.mark.parametrize(
    ("doc", "needle"),
    [
        ({"X": [[1, 0], [1]], "F": [[1], [0]]}, "X is not a numeric matrix"),
        ({"X": [[1, 0], [1, 5]], "F": [[1], [0]]}, "X entry 5 is not one of 0, 1, 2, 3"),
        ({"X": [[1], [1]], "F": [[1], [0]], "f": ["a", "b"]}, "name list 'f' has 2 entries, matrix has 1"),
        ({"X": [[1], [1]], "F": [[1]]}, "F has 1 rows but X has 2"),
        ({"X": [[1], [1]], "F": [[2], [0]]}, "F and Z must hold only 0 and 1"),
        ({"F": [[1]]}, "missing key 'X'"),
        ([1, 2], "expected a JSON object"),
    ],
    ids=["ragged", "bad-entry", "name-count", "row-count", "bad-F", "no-X", "not-object"],
)
def test_malformed_fdt_json_names_what_is_wrong(tmp_path: Path, doc: object, needle: str) -> None:
    assert needle in load_error(write(tmp_path, json.dumps(doc), "s.json"))


def test_json_that_is_not_json(tmp_path: Path) -> None:
    assert "not valid JSON" in load_error(write(tmp_path, "{X: ", "s.json"))
    assert "not a UTF-8 text file" in load_error(write(tmp_path, b"\xff\xfe\x00", "b.json"))


def test_structurally_singular_model_names_the_undetermined_unknowns(tmp_path: Path) -> None:
    text = (HEAD + var("unknown", "x", "w", "v") + var("known", "u", "y", "y2") + var("fault", "f1")
            + eq("e1", 'expr = "x = u*w + f1"') + eq("e2", 'expr = "y = v"') + eq("e3", 'expr = "y2 = v"'))
    s = summarize(load_model(write(tmp_path, text)))
    problems = s.problems()
    assert any(p.startswith("structurally singular") and "x, w" in p and "e1" in p for p in problems), problems
    assert any("not detectable" in p and "f1" in p for p in problems), problems
    assert s.to_dict()["problems"] == problems


def test_model_without_redundancy_says_no_residual_exists(tmp_path: Path) -> None:
    text = HEAD + var("unknown", "x") + var("known", "u") + var("fault", "f1") + eq("e1", 'expr = "x = u + f1"')
    s = summarize(load_model(write(tmp_path, text)))
    assert s.redundancy == 0
    assert any(p.startswith("no structural redundancy") for p in s.problems())
    assert not s.isolability.detectable.any()


@pytest.mark.parametrize("command", [["mso"], ["select"], ["select", "--candidates", "mtes"],
                                     ["export-c", "--thresholds", "analysis/models/romo_thresholds.toml", "--out"]])
def test_commands_that_need_tests_refuse_a_model_without_redundancy(
    tmp_path: Path, command: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    from fdi_analysis.cli import main

    text = HEAD + var("unknown", "x") + var("known", "u") + var("fault", "f1") + eq("e1", 'expr = "x = u + f1"')
    model = str(write(tmp_path, text))
    argv = [command[0], model, *command[1:]] + ([str(tmp_path / "out")] if command[-1] == "--out" else [])
    assert main([*argv, "--no-progress"]) == 1
    err = capsys.readouterr().err
    assert "error: no structural redundancy" in err and "add measurements" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_good_model_has_no_problems(tmp_path: Path) -> None:
    text = (HEAD + var("unknown", "x") + var("known", "u", "y") + var("fault", "f1", "f2")
            + eq("e1", 'expr = "x = u + f1"') + eq("e2", 'expr = "y = x + f2"'))
    s = summarize(load_model(write(tmp_path, text)))
    assert s.redundancy == 1 and s.problems() == []


def test_romo_model_has_no_problems(models_dir: Path) -> None:
    assert summarize(load_model(models_dir / "romo_quasistatic.toml")).problems() == []
