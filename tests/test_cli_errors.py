"""Every command line of the project answers a bad input file with one line on stderr and exit 1, a bad option
with argparse's usage text and exit 2, and an exception that is not one of the project's errors (a bug: here a
library function made to raise ZeroDivisionError, KeyError or a bare ValueError) with its traceback and exit 70
(`EXIT_BUG`), never with the one line of a bad input (fdi-quality, which has its own main, lets it propagate)."""

from __future__ import annotations

import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from fdi_analysis.cli.common import EXIT_BUG, EXIT_ERROR, EXIT_USAGE

REPO = Path(__file__).resolve().parents[1]
ENTRY_POINTS: dict[str, str] = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"][
    "scripts"]


def _main(prog: str) -> Callable[[list[str]], int]:
    module, func = ENTRY_POINTS[prog].split(":")
    return getattr(__import__(module, fromlist=[func]), func)  # type: ignore[no-any-return]


def _call(prog: str, argv: list[str]) -> int | str | None:
    try:
        return _main(prog)(argv)
    except SystemExit as exc:
        return exc.code


@dataclass(frozen=True)
class Case:
    bad_input: list[str]  # arguments naming a bad input file
    names: str  # what the one error line says (the file, where the program names it)
    bad_option: list[str]
    bug_target: str  # "module:attribute" made to raise
    bug: type[Exception]
    bug_argv: list[str]  # arguments that reach the patched function


def _files(tmp: Path) -> dict[str, Path]:
    (tmp / "garbage.toml").write_text("this is = = not toml\n", encoding="utf-8")
    (tmp / "scen.toml").write_text("[scenario\n", encoding="utf-8")
    (tmp / "sizes.toml").write_text("[sizes]\nf1 = 0\n", encoding="utf-8")
    (tmp / "classes.json").write_text("{", encoding="utf-8")
    (tmp / "corrupt.blf").write_bytes(b"LOGG" + bytes(range(256)) * 2)
    (tmp / "one.log").write_text("(0.000000) vcan0 100#0102030405060708\n(0.010000) vcan0 100#0102030405060708\n",
                                 encoding="utf-8")
    return {p.stem: p for p in tmp.iterdir()}


def _cases(f: dict[str, Path], tmp: Path) -> dict[str, Case]:
    missing_ini = str(tmp / "missing.ini")
    return {
        "fdi-analyze": Case(["report", str(f["garbage"])], "garbage.toml", ["report", "romo_grouped", "--nosuch"],
                            "fdi_analysis.model_loader:_ModelBuilder.build", ValueError,
                            ["report", "romo_grouped", "-o", str(tmp / "report")]),
        "fdi-sim": Case(["--scenario", str(f["scen"]), "--duration", "0.1", "--quiet"], "scen.toml", ["--nosuch"],
                        "fdi_host.cli:simulate_from_args", KeyError, ["--scenario", "fig6", "--quiet"]),
        "fdi-tune": Case(["residuals", "romo_grouped", "--thresholds", "romo_thresholds", "--log",
                          str(f["corrupt"])], "corrupt.blf", ["residuals", "--nosuch"],
                         "fdi_analysis.export.thresholds:Thresholds.load", ZeroDivisionError,
                         ["residuals", "romo_grouped", "--thresholds", "romo_thresholds", "--log", str(f["one"])]),
        "fdi-ecu": Case(["--can-config", missing_ini], "missing.ini", ["--table", "nosuch"],
                        "fdi_host.live.ecu:EcuSession", KeyError, ["--can-config", missing_ini]),
        "fdi-monitor": Case(["--can-config", missing_ini], "missing.ini", ["--grace"],
                            "fdi_host.monitor.cli:Monitor", ZeroDivisionError, ["--can-config", missing_ini]),
        "fdi-replay": Case([str(f["corrupt"]), "--offline"], "corrupt.blf", [str(f["one"]), "--speed", "0"],
                           "fdi_host.replay:replay_columns", ValueError, [str(f["one"]), "--offline"]),
        "fdi-live": Case(["--can-config", missing_ini, "--out-dir", str(tmp / "live")], "missing.ini",
                         ["--transport", "nosuch"], "fdi_host.live.runner:run_here", KeyError,
                         ["--transport", "current", "--out-dir", str(tmp / "live")]),
        "fdi-quality": Case(["--quick", "--sizes", str(f["sizes"])], "sizes.toml", ["--table", "nosuch"],
                            "fdi_host.quality.cli:run_suite", KeyError, ["--quick"]),
    }


def _patch(monkeypatch: pytest.MonkeyPatch, target: str, exc: type[Exception]) -> None:
    module, attr = target.split(":")
    obj: Any = __import__(module, fromlist=["_"])
    *owners, name = attr.split(".")
    for o in owners:
        obj = getattr(obj, o)

    def boom(*_a: object, **_k: object) -> object:
        raise exc("injected: a bug, not a bad input")

    monkeypatch.setattr(obj, name, boom)


def test_every_command_line_is_covered() -> None:
    assert set(_cases({k: Path(k) for k in ("garbage", "scen", "sizes", "corrupt", "one")}, Path("t"))) == set(
        ENTRY_POINTS)


@pytest.mark.parametrize("prog", sorted(ENTRY_POINTS))
def test_bad_input_file_is_one_line_and_exit_1(prog: str, tmp_path: Path,
                                               capfd: pytest.CaptureFixture[str]) -> None:
    case = _cases(_files(tmp_path), tmp_path)[prog]
    got = _call(prog, case.bad_input)
    err = capfd.readouterr().err
    lines = [ln for ln in err.split("\n") if ln.strip() and "\r" not in ln]  # progress bars redraw with \r
    assert got == EXIT_ERROR, (got, err)
    assert "Traceback" not in err, err
    assert len(lines) == 1 and lines[0].startswith(f"{prog}: ") and case.names in lines[0], err


@pytest.mark.parametrize("prog", sorted(ENTRY_POINTS))
def test_bad_option_is_a_usage_error(prog: str, tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    case = _cases(_files(tmp_path), tmp_path)[prog]
    assert _call(prog, case.bad_option) == EXIT_USAGE
    err = capfd.readouterr().err
    assert "usage:" in err and "Traceback" not in err, err


@pytest.mark.parametrize("prog", sorted(ENTRY_POINTS))
def test_a_bug_keeps_its_traceback(prog: str, tmp_path: Path, capfd: pytest.CaptureFixture[str],
                                   monkeypatch: pytest.MonkeyPatch) -> None:
    case = _cases(_files(tmp_path), tmp_path)[prog]
    _patch(monkeypatch, case.bug_target, case.bug)
    if prog == "fdi-quality":  # no common run(): the exception propagates (Python prints it, exit 1)
        with pytest.raises(case.bug, match="injected"):
            _call(prog, case.bug_argv)
        return
    got = _call(prog, case.bug_argv)
    err = capfd.readouterr().err
    assert got == EXIT_BUG, (got, err)
    assert "Traceback (most recent call last)" in err and f"{case.bug.__name__}: " in err and "injected" in err, err
    assert f"{prog}: internal error ({case.bug.__name__})" in err and ": error:" not in err, err
