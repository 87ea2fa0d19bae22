"""Every log format python-can reads and writes (`fdi_host.can.logs`): a drive written in it and replayed gives the
same diagnosis; malformed lines (garbage, a truncated last line) are counted with their line numbers and skipped,
the same in python-can's path and in the numpy candump path; ``--strict`` makes the first one an error naming the
file and the line; the fleet lists the logs with skipped lines. A format whose reader needs an optional package
that is not installed says so, and its round trip is skipped with that reason."""

from __future__ import annotations

import gzip
import importlib.util
import json
import re
from pathlib import Path

import numpy as np
import pytest

from fdi_host import fleet
from fdi_host.can.frame import Frame
from fdi_host.can.log_columns import FrameColumns, candump_lines, frame_columns, read_columns_checked
from fdi_host.can.logs import (
    LOG_SUFFIXES,
    OPTIONAL_PACKAGES,
    TEXT_SUFFIXES,
    LogError,
    MalformedLogError,
    check_suffix,
    is_log,
    log_format,
    read_log,
    read_log_checked,
    write_log,
)
from fdi_host.replay import FastResult, replay_columns, replay_fleet
from fdi_host.replay import main as replay_main

FORMATS = [*LOG_SUFFIXES, *(s + ".gz" for s in TEXT_SUFFIXES)]


def _same(a: FrameColumns, b: FrameColumns) -> None:
    assert np.array_equal(a.t, b.t) and np.array_equal(a.frame_id, b.frame_id)
    assert np.array_equal(a.dlc, b.dlc) and np.array_equal(a.data, b.data)


def _missing(fmt: str) -> str | None:
    """The optional package a format needs that is not installed, or None."""
    need = OPTIONAL_PACKAGES.get(fmt.removesuffix(".gz"))
    return need[0] if need is not None and importlib.util.find_spec(need[0]) is None else None


@pytest.fixture(scope="module")
def drive(tmp_path_factory: pytest.TempPathFactory) -> tuple[list[Frame], FastResult]:
    from fdi_host.cli import main as sim_main

    out = tmp_path_factory.mktemp("formats")
    rc = sim_main(["--scenario", "fig6", "--no-scenario-faults", "--fault", "f4@2s:0.5", "--duration", "4",
                   "--start-time", "1795969960.5", "--out", str(out / "d.log"), "--quiet"])
    assert rc == 0
    frames = read_log(out / "d.log")
    ref = replay_columns(frame_columns(frames), "kin")
    assert any(r.alarm_mask for r in ref.records)  # the fault did something to compare
    return frames, ref


@pytest.mark.parametrize("fmt", FORMATS)
def test_every_format_replays_to_the_same_diagnosis(drive: tuple[list[Frame], FastResult], tmp_path: Path,
                                                    fmt: str, capsys: pytest.CaptureFixture[str]) -> None:
    frames, ref = drive
    path = tmp_path / f"drive{fmt}"
    missing = _missing(fmt)
    if missing is not None:
        with pytest.raises(LogError, match=rf"drive\{fmt}: \{fmt} logs need the optional package {missing}"):
            write_log(frames, path)
        path.write_bytes(b"not read without the package")
        with pytest.raises(LogError, match=rf"drive\{fmt}: \{fmt} logs need the optional package {missing}"):
            read_log(path)
        pytest.skip(f"{fmt}: python-can's reader and writer need {missing}, which is not installed (the error "
                    "says so, checked above)")
    assert log_format(path) == fmt and is_log(path)
    assert write_log(frames, path) == len(frames)
    read = read_log_checked(path)
    assert not read.issues and read.issues.skipped == 0
    assert [(f.frame_id, f.data) for f in read.frames] == [(f.frame_id, f.data) for f in frames]
    t_in = np.array([f.timestamp for f in frames])
    t_out = np.array([f.timestamp for f in read.frames])
    np.testing.assert_allclose(t_out - t_out[0], t_in - t_in[0], atol=2e-6)  # .asc, .trc: microseconds
    cols = read_columns_checked(path)
    _same(cols.columns, frame_columns(read.frames))
    res = replay_columns(cols.columns, "kin")
    assert [(r.alarm_mask, r.candidates, r.iso_class) for r in res.records] == \
        [(r.alarm_mask, r.candidates, r.iso_class) for r in ref.records]
    assert [r.t for r in res.records] == pytest.approx([r.t for r in ref.records], abs=2e-6)
    capsys.readouterr()
    assert replay_main([str(path), "--offline", "--vehicle", "kin"]) == 0
    assert f"{len(frames)} frames" in capsys.readouterr().out


def test_suffixes() -> None:
    assert LOG_SUFFIXES[:3] == (".log", ".asc", ".blf") and {".trc", ".csv", ".db", ".mf4"} <= set(LOG_SUFFIXES)
    assert log_format("a/B.LOG") == ".log" and log_format("x.asc.gz") == ".asc.gz"
    assert log_format("x.blf.gz") is None and log_format("x.gz") is None and log_format("x.txt") is None
    with pytest.raises(LogError, match=r"x\.txt: unsupported log format '\.txt'; use one of \.log, \.asc"):
        check_suffix("x.txt")


# ------------------------------------------------------------------------------------------- malformed lines
GOOD = ["(1795969960.000100) can0 100#0102 R", "(1795969960.001000) can0 101#03 R",
        "(1795969960.002000) can0 7FF#0405060708090A0B R", "(1795969960.003000) can0 12345678#0C R"]


def _garbage_log(path: Path, last: str = "(1795969960.004000) can0 10") -> list[int]:
    """A candump log with garbage lines between good ones and a truncated last line; the bad line numbers."""
    lines = [GOOD[0], "garbage", GOOD[1], "(1795969960.0015x) can0 102#00 R", "", GOOD[2],
             "(1795969960.0025) can0 103#ABC R", GOOD[3], "\x00\x01\xff binary", last]
    path.write_bytes(("\n".join(lines)).encode("latin-1"))  # no line end after the last line
    return [2, 4, 7, 9, 10]


@pytest.mark.parametrize("gz", [False, True])
def test_garbage_lines_and_a_truncated_last_line_are_counted_and_skipped(tmp_path: Path, gz: bool) -> None:
    path = tmp_path / "drive.log"
    bad = _garbage_log(path)
    if gz:
        path = tmp_path / "drive.log.gz"
        path.write_bytes(gzip.compress((tmp_path / "drive.log").read_bytes()))
    read = read_log_checked(path)
    assert [(hex(f.frame_id), f.data.hex()) for f in read.frames] == \
        [("0x100", "0102"), ("0x101", "03"), ("0x7ff", "0405060708090a0b"), ("0x12345678", "0c")]
    issues = read.issues
    assert issues.skipped == len(bad) and list(issues.lines) == bad
    assert "could not convert string to float" in issues.first[1].reason  # the garbage timestamp (line 4)
    assert "payload bytes for length code" in issues.first[2].reason  # an odd number of hex digits (line 7)
    assert "truncated" in issues.first[4].reason  # the last line, without its line end
    assert issues.summary().startswith(f"{path}: 5 malformed lines skipped (lines 2, 4, 7, 9, 10; line 2: ")
    # the numpy candump path: the same frames, the same issues
    cols = read_columns_checked(path)
    _same(cols.columns, frame_columns(read.frames))
    assert cols.issues == issues
    with pytest.raises(MalformedLogError, match=rf"^{path}: line 2: malformed \(ValueError"):
        read_log_checked(path, strict=True)
    with pytest.raises(MalformedLogError, match=rf"^{path}: line 2: malformed"):
        read_columns_checked(path, strict=True)


def test_a_cut_gzip_stream_keeps_the_lines_before_it(tmp_path: Path) -> None:
    path = tmp_path / "d.log.gz"
    path.write_bytes(gzip.compress(("\n".join(GOOD * 200) + "\n").encode())[:-40])
    read = read_log_checked(path)
    assert 0 < len(read.frames) < 800 and read.issues.skipped >= 1 and "truncated" in read.issues.first[-1].reason
    cols = read_columns_checked(path)
    _same(cols.columns, frame_columns(read.frames))
    assert cols.issues == read.issues


def test_the_numpy_path_takes_the_plain_lines_of_a_mixed_log(tmp_path: Path) -> None:
    """Lines with and without a direction, remote and FD frames, garbage: the plain lines are parsed with numpy,
    the others by python-can, merged in line order; the same columns as python-can's reader alone."""
    lines = [GOOD[0], "(1795969960.000500) can0 200#R R", GOOD[1].removesuffix(" R"), "junk", GOOD[2],
             "(1795969960.002500) can0 300##1AABBCCDDEEFF00112233 T", GOOD[3], "(1795969960.0035) can0 301#05"]
    raw = ("\n".join(lines) + "\n").encode()
    split = candump_lines(raw)
    assert split.line.tolist() == [1, 3, 5, 7, 8] and [n for n, _ in split.other] == [2, 4, 6]
    assert not split.uniform
    path = tmp_path / "mixed.log"
    path.write_bytes(raw)
    cols = read_columns_checked(path)
    read = read_log_checked(path)
    _same(cols.columns, frame_columns(read.frames))
    assert cols.columns.frame_id.tolist() == [0x100, 0x101, 0x7FF, 0x300, 0x12345678, 0x301]
    assert cols.issues == read.issues and read.issues.lines == (4,)


@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_the_numpy_path_equals_python_cans_on_mutated_logs(tmp_path: Path, seed: int) -> None:
    """Random bytes of a candump log replaced, deleted or doubled: the numpy path gives python-can's frames and
    the same malformed lines, whatever the damage."""
    rng = np.random.default_rng(seed)
    path = tmp_path / "d.log"
    good = [Frame(1795969960.0 + 0.0013 * i, int(rng.integers(0, 0x800)) if i % 3 else int(rng.integers(0, 2**29)),
                  bytes(rng.integers(0, 256, int(rng.integers(0, 9))).astype(np.uint8))) for i in range(3000)]
    write_log(good, path)
    raw = bytearray(path.read_bytes())
    for at in rng.integers(0, len(raw), 60):
        kind = int(rng.integers(0, 3))
        if kind == 0:
            raw[at] = int(rng.choice(list(b"#( )R.xG\t\r\n\x00\xff0")))
        elif kind == 1:
            del raw[at]
        else:
            raw[at:at] = raw[at: at + int(rng.integers(1, 30))]
    path.write_bytes(bytes(raw[: len(raw) - int(rng.integers(0, 2)) * 7]))
    read = read_log_checked(path)
    cols = read_columns_checked(path)
    _same(cols.columns, frame_columns(read.frames))
    assert cols.issues == read.issues and read.issues.skipped > 0
    assert len(read.frames) > 2800


@pytest.mark.parametrize("fmt", [".asc", ".trc", ".csv"])
def test_other_text_formats_skip_garbage_and_truncated_lines(drive: tuple[list[Frame], FastResult],
                                                             tmp_path: Path, fmt: str) -> None:
    frames = drive[0][:200]
    good = tmp_path / f"good{fmt}"
    write_log(frames, good)
    lines = good.read_text(encoding="utf-8").splitlines(keepends=True)
    frame_line = {".asc": r"\s*\d+\.\d+\s+1\s", ".trc": r"\s*\d+\s", ".csv": r"\d"}[fmt]
    first = next(i for i, line in enumerate(lines) if re.match(frame_line, line))  # the first frame's line
    garbage = {".asc": "   0.123456 1  12G             Rx   d 8 00 01 02 03 04 05 06 07\n",
               ".trc": "garbage\n", ".csv": "garbage\n"}[fmt]
    bad_lines = [*lines[: first + 5], garbage, *lines[first + 5: -1]]
    cut = lines[-1][: len(lines[-1]) // 2]  # the last line cut in the middle, no line end
    if fmt == ".asc":  # the last lines of an .asc are its end marker: cut a frame line instead
        bad_lines = [*lines[: first + 5], garbage, *lines[first + 5: first + 50]]
        cut = lines[first + 50][:40]
    path = tmp_path / f"bad{fmt}"
    path.write_text("".join(bad_lines) + cut, encoding="utf-8")
    read = read_log_checked(path)
    assert read.issues.skipped == 2, read.issues.summary()
    assert read.issues.lines == (first + 6, len(bad_lines) + 1)
    expected = frames[: first + 50 - first] if fmt == ".asc" else frames[:-1]
    assert [(f.frame_id, f.data) for f in read.frames] == [(f.frame_id, f.data) for f in expected]
    with pytest.raises(MalformedLogError, match=rf"bad\{fmt}: line {first + 6}: malformed"):
        read_log(path, strict=True)


def test_a_cut_blf_keeps_its_frames_and_says_so(drive: tuple[list[Frame], FastResult], tmp_path: Path) -> None:
    frames = drive[0]
    path = tmp_path / "d.blf"
    write_log(frames, path)
    raw = path.read_bytes()
    cut = tmp_path / "cut.blf"
    cut.write_bytes(raw[: len(raw) // 2])
    read = read_log_checked(cut)
    assert 0 < len(read.frames) < len(frames)
    assert [(f.frame_id, f.data) for f in read.frames] == [(f.frame_id, f.data) for f in frames[: len(read.frames)]]
    assert read.issues.skipped == 1 and read.issues.first[0].line is None
    assert "truncated" in read.issues.summary() and f"after frame {len(read.frames)}" in read.issues.summary()
    with pytest.raises(MalformedLogError, match=rf"cut\.blf: the record after frame {len(read.frames)}: malformed"):
        read_log(cut, strict=True)


def test_replay_reports_skipped_lines_and_strict_fails_with_the_line(tmp_path: Path,
                                                                     capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "drive.log"
    _garbage_log(path)
    assert replay_main([str(path), "--offline", "--vehicle", "kin"]) == 0
    out = capsys.readouterr().out
    assert f"skipped: {path}: 5 malformed lines skipped (lines 2, 4, 7, 9, 10;" in out and "4 frames" in out
    assert replay_main([str(path), "--offline", "--vehicle", "kin", "--ecu-log", str(tmp_path / "e.json")]) == 0
    assert "5 malformed lines skipped" in capsys.readouterr().out
    assert replay_main([str(path), "--offline", "--vehicle", "kin", "--strict"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"fdi-replay: error: {path}: line 2: malformed (ValueError")
    only_garbage = tmp_path / "g.log"
    only_garbage.write_text("garbage\nmore garbage\n", encoding="utf-8")
    assert replay_main([str(only_garbage), "--offline"]) == 1
    assert "g.log: holds no data frames (" in capsys.readouterr().err


def test_fleet_lists_logs_with_skipped_lines_and_strict_fails_them(drive: tuple[list[Frame], FastResult],
                                                                   tmp_path: Path,
                                                                   capsys: pytest.CaptureFixture[str]) -> None:
    logs = tmp_path / "logs"
    logs.mkdir()
    frames = drive[0]
    write_log(frames, logs / "clean.trc")
    write_log(frames, logs / "cut.log")
    text = (logs / "cut.log").read_text(encoding="utf-8")
    at = text.index("\n", 1000) + 1  # a garbage line after a whole line, and the last line cut
    (logs / "cut.log").write_text(text[:at] + "garbage\n" + text[at:-20], encoding="utf-8")
    (logs / "residuals.csv").write_text("t,r1\n0.0,1.5\n", encoding="utf-8")  # a .csv that is not a CAN log
    write_log(frames[:100], logs / "short.csv")
    assert [p.name for p in fleet.find_logs([logs])] == ["clean.trc", "cut.log", "short.csv"]
    (logs / "short.csv").unlink()
    report = replay_fleet([logs], "kin", workers=1)
    rows = {Path(r.log).name: r for r in report.logs}
    assert not report.failed and rows["clean.trc"].skipped == 0 and rows["cut.log"].skipped == 2
    assert rows["cut.log"].frames == len(frames) - 1
    assert [Path(r.log).name for r in report.with_skipped] == ["cut.log"]
    assert fleet.skipped_lines(report) == [rows["cut.log"].skipped_note]
    assert "1 logs with malformed lines skipped (2 lines)" in fleet.summary_line(report)
    assert "## Logs with malformed lines (skipped)" in fleet.markdown(report)
    assert replay_main([str(logs), "--workers", "1", "--vehicle", "kin", "--out-dir", str(tmp_path / "out"),
                        "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "logs with malformed lines (skipped): 1" in out and "cut.log: 2 malformed lines skipped (lines" in out
    doc = json.loads((tmp_path / "out" / "fleet.json").read_text(encoding="utf-8"))
    assert doc["logs_with_skipped_lines"] == 1 and doc["skipped_lines"] == 2
    assert replay_main([str(logs), "--workers", "1", "--vehicle", "kin", "--out-dir", str(tmp_path / "out"),
                        "--quiet", "--strict"]) == 1
    err = capsys.readouterr().err
    assert "1 of 2 logs could not be replayed (first: " in err and "cut.log: line " in err and ": malformed" in err
