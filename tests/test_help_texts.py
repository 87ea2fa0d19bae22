"""The help texts say what is true: every repository path an example names exists, the shipped models listed are
models (the thresholds files are listed as such), and a shipped thresholds file is taken by name where a
command asks for ``--thresholds``."""

from __future__ import annotations

import argparse
import re
import tomllib
from collections.abc import Callable
from pathlib import Path

import pytest

from fdi_analysis.cli.common import EXIT_ERROR
from fdi_analysis.resources import model_file, shipped_models, shipped_thresholds, thresholds_file

REPO = Path(__file__).resolve().parents[1]
ENTRY_POINTS: dict[str, str] = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"][
    "scripts"]
REPO_PATH = re.compile(r"(?<![\w/.-])((?:analysis|host_tools|fw|dbc|tests|scripts)/[\w./-]*\w)")


def _main(prog: str) -> Callable[[list[str]], int]:
    module, func = ENTRY_POINTS[prog].split(":")
    return getattr(__import__(module, fromlist=[func]), func)  # type: ignore[no-any-return]


def _help(prog: str, argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    with pytest.raises(SystemExit) as exc:
        _main(prog)([*argv, "--help"])
    assert exc.value.code == 0
    return capsys.readouterr().out


def subcommands(prog: str) -> list[list[str]]:
    """Each program's argv prefixes that have their own --help: none, and every subcommand."""
    if prog == "fdi-sim":
        return [[], ["fig6"], ["live"]]
    module = __import__(ENTRY_POINTS[prog].split(":")[0], fromlist=["build_parser"])
    if not hasattr(module, "build_parser"):
        return [[]]
    parser = module.build_parser()
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return [[]] + [[name] for s in subs for name in s.choices]


@pytest.mark.parametrize("prog", sorted(ENTRY_POINTS))
def test_every_path_a_help_text_names_exists(prog: str, capsys: pytest.CaptureFixture[str]) -> None:
    missing = []
    for sub in subcommands(prog):
        text = _help(prog, sub, capsys)
        missing += [f"{prog} {' '.join(sub)}: {p}" for p in REPO_PATH.findall(text) if not (REPO / p).exists()]
    assert not missing, missing


def test_fdi_analyze_lists_models_and_thresholds_apart(capsys: pytest.CaptureFixture[str]) -> None:
    text = " ".join(_help("fdi-analyze", [], capsys).split())
    models, thresholds = shipped_models(), shipped_thresholds()
    assert "romo_grouped" in models and "romo_thresholds" in thresholds and not set(models) & set(thresholds)
    assert f"shipped with the package: {', '.join(models)} " in text
    assert f"the name of a shipped one: {', '.join(thresholds)}" in text
    for name in models:  # a model file, not a thresholds file
        assert "model" in tomllib.loads(model_file(name).read_text(encoding="utf-8")), name
    for name in thresholds:
        assert "gate" in tomllib.loads(thresholds_file(name).read_text(encoding="utf-8")), name
    assert model_file("romo_thresholds") == Path("romo_thresholds")  # not a model: left as given
    assert thresholds_file("romo_grouped") == Path("romo_grouped")


def test_a_thresholds_file_is_not_a_model(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert _main("fdi-analyze")(["report", "romo_thresholds", "-o", str(tmp_path)]) == EXIT_ERROR
    err = capsys.readouterr().err
    assert err.splitlines() == [f"fdi-analyze: error: romo_thresholds: no such file, nor a model shipped with the "
                                f"package ({', '.join(shipped_models())}); romo_thresholds is a thresholds file, "
                                "not a model"]


def test_thresholds_by_name(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``fdi-tune residuals --thresholds romo_thresholds`` reads the shipped file: what fails next is the log."""
    log = tmp_path / "missing.blf"
    assert _main("fdi-tune")(["residuals", "romo_grouped", "--thresholds", "romo_thresholds", "--log",
                              str(log)]) == EXIT_ERROR
    err = capsys.readouterr().err
    assert "missing.blf" in err and "romo_thresholds" not in err, err
