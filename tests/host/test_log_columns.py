"""fdi_host.can.log_columns: a log's data frames as columns. The candump parser gives exactly python-can's frames
(read_log, then frame_columns) for the plain logs it takes, and hands every other file to python-can, so that
read_log_columns always equals frame_columns(read_log(path)), errors included; the one-call replay from the
columns gives the same diagnosis as from the frame objects."""

from __future__ import annotations

import random
from pathlib import Path

import numpy as np
import pytest

from fdi_host.can.frame import Frame
from fdi_host.can.log_columns import FrameColumns, frame_columns, parse_candump, read_log_columns
from fdi_host.can.logs import LogError, read_log, write_log
from fdi_host.replay import replay_columns, replay_offline_fast


def _same(a: FrameColumns, b: FrameColumns) -> None:
    assert a.t.dtype == b.t.dtype and a.frame_id.dtype == b.frame_id.dtype and a.data.dtype == b.data.dtype
    assert np.array_equal(a.t, b.t)
    assert np.array_equal(a.frame_id, b.frame_id)
    assert np.array_equal(a.dlc, b.dlc)
    assert np.array_equal(a.data, b.data)


def _frames(n: int, seed: int = 1) -> list[Frame]:
    """Standard and extended IDs, every payload length 0-8, times from small to epoch-sized."""
    rng = random.Random(seed)
    out = []
    t = rng.choice([0.0, 12.345678, 1795969960.938318])
    for _ in range(n):
        t += rng.random() * 0.002
        fid = rng.choice([rng.randrange(0x800), rng.randrange(0x800, 0x20000000), 0x7FF, 0x1FFFFFFF, 0])
        out.append(Frame(t, fid, bytes(rng.randrange(256) for _ in range(rng.randrange(9)))))
    return out


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_written_candump_logs_parse_to_python_cans_frames(tmp_path: Path, seed: int) -> None:
    path = tmp_path / "drive.log"
    write_log(_frames(3000, seed), path)
    raw = path.read_bytes()
    fast = parse_candump(raw)
    assert fast is not None  # the fast path took it
    _same(fast, frame_columns(read_log(path)))
    _same(read_log_columns(path), frame_columns(read_log(path)))


def test_lines_without_direction_and_candump_style_ids(tmp_path: Path) -> None:
    path = tmp_path / "candump.log"
    path.write_text("(1795969960.000100) can0 123#DEADBEEF\n(1795969960.000200) vcan1 00000123#\n"
                    "(1795969960.010300) can0 1FFFFFFF#0102030405060708\n(0000000001.5) x 7ff#aB\n")
    fast = parse_candump(path.read_bytes())
    assert fast is not None
    _same(fast, frame_columns(read_log(path)))
    assert fast.frame_id.tolist() == [0x123, 0x123, 0x1FFFFFFF, 0x7FF]
    assert fast.dlc.tolist() == [4, 0, 8, 1]


def test_timestamps_are_exactly_floats_of_their_text(tmp_path: Path) -> None:
    rng = random.Random(7)
    texts = [f"{rng.uniform(0, 2e9):.6f}" for _ in range(2000)] + [f"{rng.uniform(0, 100):.{d}f}" for d in
                                                                     range(1, 10) for _ in range(50)]
    texts += ["9007199254.740991", "0.1", "0.000001", "123456789012345.6"]
    path = tmp_path / "times.log"
    path.write_text("".join(f"({s}) can0 100#00 R\n" for s in texts))
    fast = parse_candump(path.read_bytes())
    assert fast is not None
    assert fast.t.tolist() == [float(s) for s in texts]


@pytest.mark.parametrize("line", [
    "(1.000300) can0 123#R R",  # a remote frame
    "(1.000300) can0 20000080#0000000000000000 R",  # an error frame (CAN_ERR_FLAG | CAN_ERR_BUSERROR)
    "(1.000300) can0 20000001#00 R",  # CAN_ERR_FLAG without BUSERROR: a data frame of id 1 for python-can
    "(1.000300) can0 123##1AABBCCDDEEFF00112233 R",  # CAN FD
    "(1.000300)\tcan0 123#00 R",  # a tab
    "",  # a blank line
    "(1e-3) can0 123#00 R",  # an exponent
    "(-1.5) can0 123#00 R",  # a sign
    "(1.5) can0 123#ABC R",  # an odd number of data digits
    "(1.5) can0 123#000102030405060708 R",  # 9 bytes without FD
    "(1.5) can0 123#00 X",  # not a direction
    "(1.5) can0 123#00",  # three tokens among fours
    "(1.5) can0 12G#00 R",  # not hex
    "(1.5) can0 #00 R",  # no identifier
    "(1.5) can0 123456789#00 R",  # nine identifier digits
    "(12345678901234567.0) can0 123#00 R",  # beyond the exact range of the fast timestamps
    "garbage",
])
def test_any_other_line_goes_to_python_can_with_the_same_result(tmp_path: Path, line: str) -> None:
    path = tmp_path / "odd.log"
    path.write_text(f"(1.000100) can0 100#0102 R\n{line}\n(1.000200) can0 101#03 T\n")
    assert parse_candump(path.read_bytes()) is None
    try:
        expected = frame_columns(read_log(path))
    except LogError as exc:
        with pytest.raises(LogError) as got:
            read_log_columns(path)
        assert str(got.value) == str(exc)
    else:
        _same(read_log_columns(path), expected)


@pytest.mark.parametrize("raw", [b"", b"(1.5) can0 100#00 R", b"(1.5) can0 100#00 R\r\n", b" (1.5) can0 100#00 R\n",
                                 b"(1.5)  can0 100#00 R\n", b"(1.5) can0 100#00 R \n", b"(1.5) can0 100#\xc3\xa9 R\n"])
def test_layouts_other_than_the_plain_one_are_not_parsed(raw: bytes) -> None:
    assert parse_candump(raw) is None


def test_other_formats_go_through_python_can(tmp_path: Path) -> None:
    frames = _frames(500)
    for suffix in (".blf", ".asc"):
        path = tmp_path / f"drive{suffix}"
        write_log(frames, path)
        _same(read_log_columns(path), frame_columns(read_log(path)))
    with pytest.raises(LogError, match="no such file"):
        read_log_columns(tmp_path / "missing.log")


def test_replay_from_columns_equals_replay_from_frames(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from fdi_host.cli import main as sim_main
    from fdi_host.replay import main as replay_main

    rc = sim_main(["--scenario", "fig6", "--no-scenario-faults", "--fault", "f4@2s:0.5", "--duration", "4",
                   "--out", str(tmp_path / "drive.log")])
    assert rc == 0
    path = tmp_path / "drive.log"
    assert parse_candump(path.read_bytes()) is not None
    a = replay_columns(read_log_columns(path), "kin")
    b = replay_offline_fast(read_log(path), "kin")
    assert a.frames == b.frames and a.log_duration == b.log_duration
    assert a.records == b.records
    assert any(r.alarm_mask for r in a.records)  # the fault did something to compare
    capsys.readouterr()
    assert replay_main([str(path), "--offline", "--vehicle", "kin"]) == 0  # the CLI's one-call path: the columns
    out = capsys.readouterr().out
    n_alarms = sum(1 for r in a.records if r.alarm_mask)
    assert f"{a.frames} frames, {a.log_duration:.2f} s of log" in out
    assert f"{len(a.records)} diagnosis steps; {n_alarms} with an alarm" in out
