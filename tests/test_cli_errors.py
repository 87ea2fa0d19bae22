"""Every command line of the project answers a bad input file with one line on stderr and exit 1, a bad option
with argparse's usage text and exit 2, and an exception that is not one of the project's errors (a bug: here a
library function made to raise ZeroDivisionError, KeyError or a bare ValueError) with its traceback and exit 70
(`EXIT_BUG`), never with the one line of a bad input."""

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
        "fdi-ecu": Case(["--can-config", missing_ini], "missing.ini", ["--vehicle", "nosuch"],
                        "fdi_host.live.ecu:EcuSession", KeyError, ["--can-config", missing_ini]),
        "fdi-monitor": Case(["--can-config", missing_ini], "missing.ini", ["--grace"],
                            "fdi_host.monitor.cli:Monitor", ZeroDivisionError, ["--can-config", missing_ini]),
        "fdi-replay": Case([str(f["corrupt"]), "--offline"], "corrupt.blf", [str(f["one"]), "--speed", "0"],
                           "fdi_host.replay:replay_columns", ValueError, [str(f["one"]), "--offline"]),
        "fdi-live": Case(["--can-config", missing_ini, "--out-dir", str(tmp / "live")], "missing.ini",
                         ["--transport", "nosuch"], "fdi_host.live.runner:run_here", KeyError,
                         ["--transport", "current", "--out-dir", str(tmp / "live")]),
        "fdi-quality": Case(["--quick", "--sizes", str(f["sizes"])], "sizes.toml", ["--vehicle", "nosuch"],
                            "fdi_host.quality.cli:run_suite", KeyError, ["--quick"]),
        "fdi-vehicle": Case(["glue", str(f["garbage"])], "garbage.toml", ["new", "--nosuch"],
                            "fdi_host.vehicle_cli:write_glue", KeyError, ["glue", "three_tank", "--check"]),
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
    got = _call(prog, case.bug_argv)
    err = capfd.readouterr().err
    assert got == EXIT_BUG, (got, err)
    assert "Traceback (most recent call last)" in err and f"{case.bug.__name__}: " in err and "injected" in err, err
    assert f"{prog}: internal error ({case.bug.__name__})" in err and ": error:" not in err, err


# ------------------------------------------------------------------------ issue 47 item 5, the last programs
def _one_error_line(err: str, prog: str) -> str:
    lines = [ln for ln in err.split("\n") if ln.strip() and "\r" not in ln]
    assert len(lines) == 1 and lines[0].startswith(f"{prog}: error: ") and "Traceback" not in err, err
    return lines[0]


def test_replay_of_a_missing_log_is_one_line_and_exit_1(tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    """A log that does not exist is a bad input, not a usage error: no usage text, exit 1, the file named."""
    missing = tmp_path / "nosuch.blf"
    assert _call("fdi-replay", [str(missing)]) == EXIT_ERROR
    err = capfd.readouterr().err
    assert "usage:" not in err, err
    assert _one_error_line(err, "fdi-replay") == f"fdi-replay: error: {missing}: no such file"


@pytest.mark.parametrize("content, says", [
    ("{", "not a JSON file of fault signatures"),
    ("[13, 14]", "expected an object with a 'signature' list"),
    ('{"test_names": ["r1"]}', "expected an object with a 'signature' list"),
    ('{"signature": ["13"]}', "'signature' must list one test bitmask"),
    ('{"signature": [13], "test_names": "r1"}', "'test_names' must be a list of names"),
    ('{"signature": [13], "dt": 0}', "'dt' must be the diagnosis step in seconds (> 0), not 0"),
    (b"\xff\xfe{", "not a JSON file of fault signatures"),
    (None, "No such file or directory"),
])
def test_monitor_with_a_bad_classes_file_is_one_line_naming_it(content: str | bytes | None, says: str, tmp_path: Path,
                                                                 capfd: pytest.CaptureFixture[str]) -> None:
    """``fdi-monitor --classes FILE``: a file that is not fault signatures is one line naming it, exit 1, before
    the bus is opened."""
    path = tmp_path / "classes.json"
    if isinstance(content, str):
        path.write_text(content, encoding="utf-8")
    elif isinstance(content, bytes):
        path.write_bytes(content)
    assert _call("fdi-monitor", ["--classes", str(path), "--interface", "no-such-interface"]) == EXIT_ERROR
    line = _one_error_line(capfd.readouterr().err, "fdi-monitor")
    assert line.startswith(f"fdi-monitor: error: --classes {path}: ") and says in line, line


def test_monitor_reads_a_good_classes_file(tmp_path: Path) -> None:
    from fdi_host.monitor.cli import read_classes

    path = tmp_path / "classes.json"
    path.write_text('{"signature": [3, 3, 4, 0], "test_names": ["r1", "r2", "r3"], "dt": 0.02}', encoding="utf-8")
    classes, step = read_classes(path)
    assert classes.signature == (3, 3, 4, 0) and classes.iso_class == (3, 3, 4, 0) and step == 0.02
    assert classes.test_names == ("r1", "r2", "r3")


def test_monitor_classes_bug_keeps_its_traceback(monkeypatch: pytest.MonkeyPatch,
                                                 capfd: pytest.CaptureFixture[str]) -> None:
    """The catch around the fault signatures takes the project's errors, a missing file and missing bindings
    only: a bare ValueError, KeyError or RuntimeError from there is a bug."""
    for exc in (ValueError, KeyError, RuntimeError):
        _patch(monkeypatch, "fdi_host.monitor.cli:classes_for", exc)
        assert _call("fdi-monitor", ["--interface", "no-such-interface"]) == EXIT_BUG
        err = capfd.readouterr().err
        assert f"fdi-monitor: internal error ({exc.__name__})" in err and ": error:" not in err, err


@pytest.mark.parametrize("prog, argv", [
    ("fdi-replay", ["one.log", "--interface", "no-such-interface"]),
    ("fdi-monitor", ["--classes", "classes.json", "--interface", "no-such-interface"]),
])
def test_a_bus_that_cannot_be_opened_is_the_common_error_line(prog: str, argv: list[str], tmp_path: Path,
                                                              capfd: pytest.CaptureFixture[str]) -> None:
    files = _files(tmp_path)
    (tmp_path / "classes.json").write_text('{"signature": [1, 2, 4]}', encoding="utf-8")
    argv = [str(files[a.split(".")[0]]) if a.split(".")[0] in files else a for a in argv]
    assert _call(prog, argv) == EXIT_ERROR
    line = _one_error_line(capfd.readouterr().err, prog)
    assert line.startswith(f"{prog}: error: cannot open the CAN bus (no-such-interface): "), line


def test_ecu_that_cannot_load_its_table_is_one_line_and_a_bare_runtime_error_a_bug(
        monkeypatch: pytest.MonkeyPatch, capfd: pytest.CaptureFixture[str]) -> None:
    from fdi_host.ecu.bindings import EcuError

    argv = ["--interface", "no-such-interface"]
    _patch(monkeypatch, "fdi_host.live.ecu:EcuSession", EcuError)
    assert _call("fdi-ecu", argv) == EXIT_ERROR
    line = _one_error_line(capfd.readouterr().err, "fdi-ecu")
    assert line.startswith("fdi-ecu: error: cannot load the ECU bindings (injected"), line
    for exc in (RuntimeError, ValueError):
        _patch(monkeypatch, "fdi_host.live.ecu:EcuSession", exc)
        assert _call("fdi-ecu", argv) == EXIT_BUG
        assert f"fdi-ecu: internal error ({exc.__name__})" in capfd.readouterr().err


def test_replay_offline_ecu_error_is_one_line_and_a_bare_runtime_error_a_bug(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capfd: pytest.CaptureFixture[str]) -> None:
    from fdi_host.ecu.bindings import EcuError

    argv = [str(_files(tmp_path)["one"]), "--offline"]
    _patch(monkeypatch, "fdi_host.replay:replay_columns", ImportError)
    assert _call("fdi-replay", argv) == EXIT_ERROR
    line = _one_error_line(capfd.readouterr().err, "fdi-replay")
    assert line.startswith("fdi-replay: error: cannot load the ECU bindings (injected"), line
    _patch(monkeypatch, "fdi_host.replay:replay_columns", EcuError)
    assert _call("fdi-replay", argv) == EXIT_ERROR
    line = _one_error_line(capfd.readouterr().err, "fdi-replay")  # an EcuError mid-log: run()'s one line
    assert line == "fdi-replay: error: injected: a bug, not a bad input", line
    _patch(monkeypatch, "fdi_host.replay:replay_columns", RuntimeError)
    assert _call("fdi-replay", argv) == EXIT_BUG
    assert "fdi-replay: internal error (RuntimeError)" in capfd.readouterr().err


def test_tune_residuals_log_reader_bug_keeps_its_traceback(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                          capfd: pytest.CaptureFixture[str]) -> None:
    """``fdi-tune residuals`` catches the log's LogError (an FdiError) and an unreadable file, not a bare
    ValueError from the reader."""
    _patch(monkeypatch, "fdi_host.can.logs:read_log", ValueError)
    argv = ["residuals", "romo_grouped", "--thresholds", "romo_thresholds", "--log", str(_files(tmp_path)["one"])]
    assert _call("fdi-tune", argv) == EXIT_BUG
    err = capfd.readouterr().err
    assert "fdi-tune: internal error (ValueError)" in err and ": error:" not in err, err


@pytest.mark.parametrize(("content", "says"), [
    ("gate = [", "not a TOML file"),
    ("gate = 5.0\n[design]\ndt = 0.01\n", "no 'cutoff_hz'"),
    ("gate = 5.0\nvariance = 3\n[design]\ndt = 0.01\ncutoff_hz = 5.0\nzeta = 0.7\nobs_gain = 1.0\n",
     "a value of the wrong type"),
])
def test_a_bad_thresholds_file_is_an_input_error_naming_it(content: str, says: str, tmp_path: Path) -> None:
    from fdi_analysis.errors import InputError
    from fdi_analysis.export.thresholds import Thresholds

    bad = tmp_path / "bad_thresholds.toml"
    bad.write_text(content, encoding="utf-8")
    with pytest.raises(InputError, match=rf"bad_thresholds\.toml: {says}"):
        Thresholds.load(bad)


@pytest.mark.parametrize(("name", "content", "says"), [
    ("s.json.gz", b"not gzip", "not a screening"),
    ("s.json", b"{", "not a screening"),
    ("s.json", b"[1, 2]", r"not a screening \(a JSON object expected"),
    ("s.json", b'{"detect_s": 0.27, "seeds": [1], "candidates": []}', "no 'model'"),
])
def test_a_bad_screening_is_a_screening_error_naming_it(name: str, content: bytes, says: str, tmp_path: Path) -> None:
    from fdi_analysis.selection.practical import Screening, ScreeningError

    bad = tmp_path / name
    bad.write_bytes(content)
    with pytest.raises(ScreeningError, match=rf"{name.replace('.', chr(92) + '.')}: {says}"):
        Screening.load(bad)
