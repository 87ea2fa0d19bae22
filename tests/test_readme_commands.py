"""The docs check: every command the README shows (its shell code blocks) and every example of a command line's
``--help`` is run or parsed here, so that none goes stale unnoticed.

- The quick ones (seconds each) run for real, in one scratch folder, in the order the README and the help texts
  give them (a later command reads what an earlier one wrote: ``drive.blf``), each with a timeout, and must exit 0.
  The scratch folder holds copies of the checkout's input files (the models, the scenarios, the DBC) at the same
  paths, so that the examples' paths resolve and no command can write into the checkout.
- The others are parsed, each listed in `PARSE_ONLY` with the reason: the two set-up commands, anything that takes
  over about a minute, needs a CAN bus or a cluster, or rewrites committed files. Parsed means: the program exists,
  and its own argparse parser accepts the options shown (the program's ``main`` is called with ``parse_args``
  stopped right after parsing); a script's file exists and ``bash -n`` accepts it; a benchmark's ``--help`` lists
  the options shown; ``apt-get`` and ``pip`` name packages and extras that exist.

A command found in no list runs for real; a `PARSE_ONLY` entry that no document shows any more fails the check.
"""

from __future__ import annotations

import argparse
import contextlib
import gzip
import io
import os
import re
import shlex
import shutil
import subprocess
import sys
import time
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from test_help_texts import subcommands

REPO = Path(__file__).resolve().parents[1]
VENV_BIN = Path(sys.executable).parent
PYPROJECT = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))
ENTRY_POINTS: dict[str, str] = PYPROJECT["project"]["scripts"]
INPUT_FOLDERS = ("analysis/models", "host_tools/scenarios", "dbc", "examples/traction_motor")
RUN_TIMEOUT_S = 120  # per command run for real; the quick ones take 2-16 s on the 2-core machine under load

BUS = "needs a CAN bus (a live process on python-can's bus)"
SLOW = "takes over a minute"
WRITES = "rewrites committed files of the checkout"

PARSE_ONLY: dict[str, str] = {
    # README: set-up and the two commands
    "bash scripts/bootstrap.sh": "the set-up: installs Debian packages (root) and the venv, minutes from nothing",
    "pip install -c constraints.txt '.[sat,notebook]'": "installs into the running environment; "
                                                        "scripts/test_wheel.sh installs the wheel in CI",
    "sudo apt-get install build-essential cmake python3-venv libcmocka-dev cppcheck clang clang-tidy valgrind "
    "gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm iproute2 qemu-system-x86 busybox-static":
        "needs root and changes the system; the packages are checked against scripts/bootstrap.sh's list",
    "bash scripts/main.sh": "the main job: about 11 minutes from nothing, and a live bus",
    "bash scripts/test.sh": "all tests (this check among them): about 30 minutes; it is what CI runs",
    # README: longer jobs
    "fdi-live --scenario fig6 --fault f4@5s:0.5 --vehicle kin --out-dir out/live": BUS + ", in real time",
    "fdi-quality --vehicle romo --out out/quality-romo": SLOW + ": the full suite, about 17 minutes",
    "fdi-tune screen analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml --sizes "
    "host_tools/scenarios/fault_sizes.toml --out analysis/models/romo_screening.json.gz":
        SLOW + " (about 22 minutes) and " + WRITES,
    "python analysis/bench/bench_mso.py": SLOW + ": FDT runs up to 30 s per structure; writes docs/results.md",
    "bash scripts/bench_fw.sh": SLOW + ": C builds, callgrind, qemu; writes docs/results.md",
    "bash scripts/fleet_quality.sh": SLOW + ": 27 truth-plant vehicles, about 13 minutes; writes docs/results.md",
    # fdi-analyze
    "fdi-analyze export-c analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml "
    "--fault-sizes host_tools/scenarios/fault_sizes.toml --out fw/vehicles/romo/generated":
        WRITES + " (the generated C; scripts/generate.sh and the staleness tests cover it)",
    "fdi-analyze select analysis/models/romo_full_vertical.toml --candidates mtes -o out/full_vertical":
        SLOW + ": the MTES search and SAT proofs on the full vertical model",
    "fdi-analyze robustness romo_full_vertical": SLOW + ": the structure of the 114-equation model",
    "fdi-analyze practical analysis/models/romo_grouped.toml --screening analysis/models/romo_screening.json.gz "
    "--thresholds analysis/models/romo_thresholds.toml -o out/practical":
        WRITES + " (the [selection] of the thresholds file)",
    # fdi-tune: every command synthesises the tests on board (fdi-tune residuals alone: 35 s) or simulates
    "fdi-tune calibrate analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml":
        SLOW + " and " + WRITES + " (the gates)",
    "fdi-tune calibrate analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml "
    "--fleet 12": SLOW + " (about 7 minutes) and " + WRITES,
    "fdi-tune fault-sizes analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml "
    "--sizes host_tools/scenarios/fault_sizes.toml": SLOW + " (about 45 minutes) and " + WRITES,
    "fdi-tune residuals analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml "
    "--log out/drive.blf --plot out/residuals.png --compare-ecu": "35 s: the synthesis of the 12 tests on board",
    "fdi-sim --scenario cornering --out out/drive.blf": "the first half of the fdi-tune residuals example, parsed "
                                                        "with it",
    "fdi-tune residuals analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml "
    "--log out/drive.blf --csv out/residuals.csv --plot out/residuals.png --compare-ecu":
        "35 s: the synthesis of the 12 tests on board",
    "fdi-tune uncertainty analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml "
    "--sizes host_tools/scenarios/fault_sizes.toml --out out/uncertainty":
        "the synthesis of the 12 tests on board (35 s alone) and a drive of every calibration scenario",
    "fdi-tune kin-calibration --out fw/vehicles/romo/generated/fdi_kin_calibration.h": SLOW + " and " + WRITES,
    # fdi-sim
    "fdi-sim live --scenario fig6 --fault f4@5s:0.5 --interface udp_multicast": BUS + ", in real time",
    "fdi-sim live --scenario fig6 --fault f4@5s:0.5 --interface udp_multicast --channel 239.74.163.2":
        BUS + ", in real time",
    "fdi-sim live --scenario straight --duration 10 --speed 10 --out sent.blf --truth sent.truth.json": BUS,
    "fdi-sim live --scenario fig6 --interface socketcan --channel vcan0": BUS + ", in real time",
    "fdi-sim live --scenario fig6 --can-config bus.ini": BUS + " (from a configuration file), in real time",
    "fdi-sim live --scenario slalom --bus-load 4000": BUS + ", in real time",
    "fdi-sim live --scenario fig6 --resume --origin-file out/live/origin.txt --counter-start 9":
        BUS + "; resumes a drive fdi-live started",
    # fdi-ecu, fdi-monitor, fdi-live: processes on a bus
    "fdi-ecu --interface udp_multicast --vehicle kin --log out/ecu.json": BUS,
    "fdi-ecu --interface socketcan --channel vcan0 --vehicle romo": BUS,
    "fdi-ecu --interface pcan --channel PCAN_USBBUS1 --bitrate 500000 --vehicle romo": BUS + " (a PEAK adapter)",
    "fdi-ecu --can-config bus.ini --can-context vehicle --vehicle romo": BUS + " (from a configuration file)",
    "fdi-ecu --interface udp_multicast --vehicle kin --idle-exit 2": BUS,
    "fdi-monitor --interface udp_multicast --vehicle kin --truth out/live/truth.json --out-dir out/live": BUS,
    "fdi-monitor --interface udp_multicast --vehicle kin --truth t.json --ecu-log out/ecu.json --idle-exit 2": BUS,
    "fdi-monitor --interface kvaser --channel 0 --bitrate 500000 --vehicle romo": BUS + " (a Kvaser adapter)",
    "fdi-monitor --classes classes.json": BUS + "; the example elides the rest of its options (...)",
    "fdi-live --scenario straight --duration 12 --no-scenario-faults --fault f4@4s:0.5:end=8s --vehicle kin":
        BUS + ", in real time",
    "fdi-live --transport current": BUS + "; the example elides the rest of its options (...)",
    "fdi-live --interface socketcan --channel vcan1": BUS + "; the example elides the rest of its options (...)",
    "fdi-live --can-config bus.ini --can-context bench": BUS + "; the example elides the rest of its options (...)",
    "fdi-live --scenario cornering --fault f4@5s:0.5 --vehicle kin --bus-load 4000": BUS + ", in real time",
    "fdi-live --scenario fig6 --duration 21.5 --no-scenario-faults --fault f4@16s:0.5 --vehicle kin "
    "--restart-ecu-at 1.5 --restart-sim-at 8.5 --sim-counter-start 9": BUS + ", in real time",
    # fdi-replay
    "fdi-replay drive.blf --speed 1 --interface udp_multicast": BUS + ", in real time",
    "fdi-replay drive.log --speed 10 --interface socketcan --channel vcan0": BUS,
    "fdi-replay drive.trc --interface pcan --channel PCAN_USBBUS1 --bitrate 500000": BUS + " (a PEAK adapter)",
    "fdi-replay drive.asc --can-config bus.ini --can-context bench": BUS + " (from a configuration file)",
    "fdi-replay 'fleet/**/*.blf' --scheduler tcp://10.0.0.5:8786": "needs a Dask cluster",
    # fdi-quality
    "fdi-quality --vehicle romo --quick --out out/quality-quick":
        "45 s; tests/host/test_quality_suite.py runs the quick suite itself",
    "fdi-quality --vehicle romo --faults f6 f10 --scenarios cornering slalom --shapes step ramp --multipliers 1 2":
        SLOW + ": 48 cases and 30 fault-free minutes",
    "fdi-quality --vehicle romo --linearity --seeds 2001 --out out/linearity": SLOW + ": about 7 minutes",
    "fdi-quality --vehicle romo --ecu noise_allowance=2 --out out/quality-na2": SLOW + ": the full suite",
    "fdi-quality --fleet 25 --out out/fleet": SLOW + ": about 40 minutes",
    "fdi-quality --fleet 2 --quick --out out/fleet-quick":
        "over a minute; tests/host/test_quality_fleet.py runs the quick fleet itself",
    "fdi-quality --replot out/fleet/fleet.json": "needs the output of a fleet run (out/fleet/fleet.json)",
}


def _gzip_log(work: Path) -> None:
    """``drive.log.gz`` for the --strict example, from the candump log an earlier fdi-sim example wrote."""
    with (work / "drive.log").open("rb") as src, gzip.open(work / "drive.log.gz", "wb") as dst:
        shutil.copyfileobj(src, dst)


def _fleet_folder(work: Path) -> None:
    """``fleet/`` for the fleet replay example: the BLF logs earlier examples wrote, with their truth files."""
    (work / "fleet").mkdir(exist_ok=True)
    for log in ("drive.blf", "clean.blf"):
        shutil.copy(work / log, work / "fleet" / log)


# what a command run for real needs that no earlier command writes, made just before it
PREPARE: dict[str, Callable[[Path], None]] = {
    "fdi-replay drive.log.gz --offline --vehicle kin --strict": _gzip_log,
    "fdi-replay fleet/ --out-dir out/fleet": _fleet_folder,
}


@dataclass(frozen=True)
class Command:
    argv: tuple[str, ...]
    source: str  # where it is shown: README.md, or "fdi-sim --help"

    @property
    def key(self) -> str:
        return shlex.join(self.argv)


# ---- the commands the documents show -------------------------------------------------------------------------

SHELL_FENCE = re.compile(r"^```(sh|bash|shell|console)\s*$")


def readme_commands(path: Path = REPO / "README.md") -> list[Command]:
    """Every command of the document's shell code blocks: one per line (``\\`` continues it), comments dropped."""
    out: list[Command] = []
    in_block, pending = False, ""
    for line in path.read_text(encoding="utf-8").splitlines():
        if not in_block:
            in_block = bool(SHELL_FENCE.match(line))
            continue
        if line.startswith("```"):
            in_block = False
            continue
        text = pending + line
        if text.rstrip().endswith("\\"):
            pending = text.rstrip()[:-1] + " "
            continue
        pending = ""
        argv = shlex.split(text, comments=True)
        if argv:
            out.append(Command(tuple(argv), path.name))
    return out


def _help_text(prog: str, sub: list[str]) -> str:
    module, func = ENTRY_POINTS[prog].split(":")
    main = getattr(__import__(module, fromlist=[func]), func)
    buf = io.StringIO()
    try:
        with contextlib.redirect_stdout(buf):
            main([*sub, "--help"])
    except SystemExit as exc:
        assert exc.code == 0, f"{prog} {' '.join(sub)} --help exited {exc.code}"
    return buf.getvalue()


COMMENT = re.compile(r"\s{2,}[(#].*$")
PARENS = re.compile(r"\s\([^)]*\)")


def _split(text: str, source: str) -> list[Command]:
    """One example line (maybe ``cmd1 && cmd2``) as commands; ``...`` (the rest of the options) dropped."""
    out = []
    for part in text.split("&&"):
        argv = [a for a in shlex.split(part) if a != "..."]
        if argv and argv[0] in ENTRY_POINTS:
            out.append(Command(tuple(argv), source))
    return out


def help_examples(help_text: str, source: str) -> list[Command]:
    """The examples of a help text: the lines of an ``examples:`` block that start with a program (continued by a
    trailing ``\\`` or by a deeper line starting with ``--``; anything after two spaces and ``(`` or ``#`` is a
    comment), and the commands of an ``example:`` paragraph (wrapped by argparse; parentheses are comments)."""
    out: list[Command] = []
    lines = help_text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.strip() == "examples:":
            current: str | None = None
            continued = False
            i += 1
            while i < len(lines) and lines[i].startswith(" "):
                raw = lines[i]
                text = COMMENT.sub("", raw).rstrip()
                starts = re.match(r"^ {2}(fdi-[\w-]+)\b", raw) is not None
                if starts:
                    if current is not None:
                        out += _split(current, source)
                    current = text.strip()
                elif current is not None and (continued or text.strip().startswith("--")):
                    current += " " + text.strip()
                continued = current is not None and current.endswith("\\")
                if continued and current is not None:
                    current = current[:-1].rstrip()
                i += 1
            if current is not None:
                out += _split(current, source)
            continue
        if line.startswith("example: "):
            para = [line[len("example: "):]]
            i += 1
            while i < len(lines) and lines[i].strip():
                para.append(lines[i].strip())
                i += 1
            out += _split(PARENS.sub("", " ".join(para)), source)
            continue
        i += 1
    return out


def all_commands() -> list[Command]:
    """The README's commands, then the help texts' examples, each once (the first place it is shown)."""
    seen: dict[str, Command] = {}
    found = readme_commands()
    for prog in ENTRY_POINTS:
        for sub in subcommands(prog):
            found += help_examples(_help_text(prog, sub), " ".join([prog, *sub, "--help"]))
    for cmd in found:
        seen.setdefault(cmd.key, cmd)
    return list(seen.values())


COMMANDS = all_commands()
RUN = [c for c in COMMANDS if c.key not in PARSE_ONLY]
PARSED = [c for c in COMMANDS if c.key in PARSE_ONLY]


# ---- run for real ----------------------------------------------------------------------------------------------

def _executable(argv: tuple[str, ...]) -> list[str]:
    if argv[0] in ENTRY_POINTS:
        return [str(VENV_BIN / argv[0]), *argv[1:]]
    if argv[0] == "python":
        return [sys.executable, *argv[1:]]
    return list(argv)


@dataclass
class Outcome:
    returncode: int
    seconds: float
    output: str


@pytest.fixture(scope="module")
def ran(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Outcome]:
    """Every quick command run once, in order, in one scratch folder; their outcomes by command."""
    work = tmp_path_factory.mktemp("docs_commands")
    for folder in INPUT_FOLDERS:
        shutil.copytree(REPO / folder, work / folder)
    env = dict(os.environ, MPLBACKEND="Agg")
    outcomes: dict[str, Outcome] = {}
    for cmd in RUN:
        if cmd.key in PREPARE:
            PREPARE[cmd.key](work)
        start = time.perf_counter()
        try:
            proc = subprocess.run(_executable(cmd.argv), cwd=work, env=env, capture_output=True, text=True,
                                  timeout=RUN_TIMEOUT_S)
            outcome = Outcome(proc.returncode, time.perf_counter() - start, proc.stdout + proc.stderr)
        except subprocess.TimeoutExpired as exc:
            outcome = Outcome(-1, time.perf_counter() - start, f"timed out after {exc.timeout} s")
        outcomes[cmd.key] = outcome
    return outcomes


@pytest.mark.parametrize("cmd", RUN, ids=[c.key[:80] for c in RUN])
def test_quick_command_runs(cmd: Command, ran: dict[str, Outcome]) -> None:
    out = ran[cmd.key]
    tail = "\n".join(out.output.splitlines()[-15:])
    assert out.returncode == 0, f"{cmd.key} (shown in {cmd.source}) exited {out.returncode}:\n{tail}"


# ---- parsed ----------------------------------------------------------------------------------------------------

class _Parsed(BaseException):  # not an Exception: the command lines' run() must not take it for a bug
    def __init__(self, namespace: argparse.Namespace) -> None:
        super().__init__()
        self.namespace = namespace


def parse_with_the_cli(argv: tuple[str, ...], monkeypatch: pytest.MonkeyPatch) -> argparse.Namespace:
    """The namespace the program's own parser makes of `argv`: its ``main`` runs until ``parse_args`` returns
    (argparse's exit 2 on anything it does not accept fails the test)."""
    original = argparse.ArgumentParser.parse_args

    def parse_then_stop(self: argparse.ArgumentParser, *args: Any, **kwargs: Any) -> argparse.Namespace:
        raise _Parsed(original(self, *args, **kwargs))

    monkeypatch.setattr(argparse.ArgumentParser, "parse_args", parse_then_stop)
    module, func = ENTRY_POINTS[argv[0]].split(":")
    main = getattr(__import__(module, fromlist=[func]), func)
    try:
        main(list(argv[1:]))
    except _Parsed as parsed:
        return parsed.namespace
    raise AssertionError(f"{shlex.join(argv)}: main returned without parsing its arguments")


def _options(argv: tuple[str, ...]) -> list[str]:
    return [a.split("=")[0] for a in argv if a.startswith("--")]


def _bootstrap_packages() -> set[str]:
    text = (REPO / "scripts" / "bootstrap.sh").read_text(encoding="utf-8")
    match = re.search(r"debs=\(([^)]*)\)", text)
    assert match, "scripts/bootstrap.sh: no debs=(...) list"
    return set(match.group(1).split())


@pytest.mark.parametrize("cmd", PARSED, ids=[c.key[:80] for c in PARSED])
def test_long_command_parses(cmd: Command, monkeypatch: pytest.MonkeyPatch,
                             capsys: pytest.CaptureFixture[str]) -> None:
    argv = cmd.argv
    if argv[0] in ENTRY_POINTS:
        assert (VENV_BIN / argv[0]).is_file(), f"{argv[0]} is not installed in {VENV_BIN}"
        parse_with_the_cli(argv, monkeypatch)
    elif argv[0] == "bash":
        script = REPO / argv[1]
        assert script.is_file(), f"{cmd.key}: no {argv[1]}"
        check = subprocess.run(["bash", "-n", str(script)], capture_output=True, text=True)
        assert check.returncode == 0, check.stderr
    elif argv[0] == "python":
        script = REPO / argv[1]
        assert script.is_file(), f"{cmd.key}: no {argv[1]}"
        proc = subprocess.run([sys.executable, str(script), "--help"], capture_output=True, text=True, timeout=120)
        assert proc.returncode == 0, proc.stderr
        missing = [o for o in _options(argv) if o not in proc.stdout]
        assert not missing, f"{cmd.key}: --help does not list {missing}"
    elif argv[:3] == ("sudo", "apt-get", "install"):
        unknown = set(argv[3:]) - _bootstrap_packages()
        assert not unknown, f"not among scripts/bootstrap.sh's Debian packages: {unknown}"
        assert _bootstrap_packages() <= set(argv[3:]), "the README lists fewer packages than bootstrap.sh installs"
    elif argv[:2] == ("pip", "install"):
        extras = PYPROJECT["project"]["optional-dependencies"]
        for arg in argv[2:]:
            if arg.startswith(".["):
                named = set(arg[2:].rstrip("]").split(","))
                assert named <= set(extras), f"no such extra: {named - set(extras)}"
            elif not arg.startswith("-"):
                assert (REPO / arg).exists(), f"{cmd.key}: no {arg}"
    else:
        raise AssertionError(f"{cmd.key}: no way to parse it; run it (drop it from PARSE_ONLY) or teach the check")


# ---- the lists themselves --------------------------------------------------------------------------------------

def test_every_parse_only_entry_is_still_shown() -> None:
    stale = sorted(set(PARSE_ONLY) - {c.key for c in COMMANDS})
    assert not stale, f"PARSE_ONLY names commands no document shows any more: {stale}"


def test_the_check_finds_the_commands() -> None:
    """The extraction sees the README's blocks and both forms of help examples (a block and a wrapped paragraph);
    the two set-up commands are among the README's, and the tour's commands run for real."""
    readme = {c.key for c in readme_commands()}
    assert {"bash scripts/main.sh", "bash scripts/test.sh"} <= readme
    sources = {c.source for c in COMMANDS}
    assert "fdi-sim --help" in sources and "fdi-tune residuals --help" in sources  # a block, a paragraph
    assert any(c.source == "README.md" for c in RUN)
    block = "examples:\n  fdi-sim --list\n  fdi-live --x 1   (note\n                 more)\n" \
            "  fdi-ecu --a 1 \\\n      --b 2\n           --c 3\n\n"
    assert [c.key for c in help_examples(block, "t")] == ["fdi-sim --list", "fdi-live --x 1",
                                                          "fdi-ecu --a 1 --b 2 --c 3"]
    para = "example: fdi-sim --scenario x --out a.blf && fdi-tune residuals m\n--log a.blf (a comment)\n"
    assert [c.key for c in help_examples(para, "t")] == ["fdi-sim --scenario x --out a.blf",
                                                         "fdi-tune residuals m --log a.blf"]


def test_ci_runs_the_readme_test_command() -> None:
    """.ci/run runs the test command of the README's two commands, as it is written there."""
    lines = [ln.strip() for ln in (REPO / ".ci" / "run").read_text(encoding="utf-8").splitlines()]
    commands = [ln for ln in lines if ln and not ln.startswith(("#", "set ", "cd "))]
    assert commands, ".ci/run runs nothing"
    readme = {c.key for c in readme_commands()}
    assert commands[-1] in readme and commands[-1] == "bash scripts/test.sh", commands


def test_parsing_refuses_an_option_the_program_lacks(monkeypatch: pytest.MonkeyPatch,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    """The parse of a long command is the program's own: a shown option it does not have fails it."""
    ns = parse_with_the_cli(("fdi-quality", "--vehicle", "romo", "--out", "out/q"), monkeypatch)
    assert ns.vehicle == "romo" and str(ns.out) == "out/q"
    for argv in (("fdi-quality", "--vehicle", "romo", "--no-such-option"), ("fdi-live", "--scenario")):
        with pytest.raises(SystemExit) as exc:
            parse_with_the_cli(argv, monkeypatch)
        assert exc.value.code == 2
    assert "usage:" in capsys.readouterr().err
