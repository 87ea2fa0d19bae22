"""Live vs offline: the diagnosis of a live run over the bus equals the offline replay through the bindings.

1. Exact: the frames the live ECU received (with their receive times, ecu_rx.log, and the same step
   alignment, origin.txt) replayed offline give
   step for step the same alarms, candidates and residuals as the live ECU process produced: the process,
   the bus and the timer polls do not change the diagnosis.
2. The drive as sent (drive.blf, nominal times) replayed offline agrees with the live diagnosis on nearly
   every step (>= 98 %); steps may differ only where the live sender fell behind its schedule by more than
   half a millisecond (a frame then reaches the ECU after a step boundary; the machine is shared).
Skipped (with the reason) only where a network namespace cannot be made.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from fdi_host.can.logs import read_log
from fdi_host.ecu.session import StepRecord, load_steps
from fdi_host.live.netns import check_unshare
from fdi_host.replay import replay_offline

pytest.importorskip("msgpack", reason="python-can's udp_multicast interface needs msgpack")


@pytest.fixture(scope="module")
def live_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    chk = check_unshare()
    if not chk.ok:
        pytest.skip(f"no private network namespace for udp_multicast: {chk.reason}")
    out = tmp_path_factory.mktemp("equiv")
    cmd = [sys.executable, "-m", "fdi_host.live.runner", "--transport", "netns", "--scenario", "cornering",
           "--no-scenario-faults", "--fault", "f5@4s:0.4:end=6s", "--duration", "8", "--vehicle", "kin",
           "--out-dir", str(out), "--channel", "239.74.163.8"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=240, check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return out


def _by_step(steps: list[StepRecord]) -> dict[int, StepRecord]:
    return {s.step: s for s in steps}


def test_offline_replay_of_received_frames_is_identical(live_run: Path) -> None:
    live = _by_step(load_steps(live_run / "ecu.json"))
    frames = read_log(live_run / "ecu_rx.log")
    t0 = float((live_run / "origin.txt").read_text())  # the live ECU aligned its steps to the sender's t = 0
    off = _by_step(replay_offline(frames, "kin", t0=t0).session.steps)
    common = sorted(set(live) & set(off))
    assert len(common) >= 790 and len(common) >= len(off) - 1
    for k in common:
        a, b = live[k], off[k]
        assert (a.alarm_mask, a.evaluable_mask, a.candidates, a.iso_class) == \
            (b.alarm_mask, b.evaluable_mask, b.candidates, b.iso_class), k
        assert a.residuals == pytest.approx(b.residuals, rel=1e-6, abs=1e-9), k
    assert any(live[k].alarm_mask for k in common)  # the fault did something to compare


def test_offline_replay_of_sent_drive_agrees(live_run: Path) -> None:
    live = _by_step(load_steps(live_run / "ecu.json"))
    off = _by_step(replay_offline(read_log(live_run / "drive.blf"), "kin").session.steps)
    common = sorted(set(live) & set(off))
    assert len(common) >= 790
    same = sum((live[k].alarm_mask, live[k].candidates) == (off[k].alarm_mask, off[k].candidates) for k in common)
    assert same >= 0.98 * len(common), (same, len(common))
    first_live = min(k for k in common if live[k].alarm_mask)
    first_off = min(k for k in common if off[k].alarm_mask)
    assert abs(first_live - first_off) <= 2


# ----------------------------------------------------------------------------------- without a network namespace
@pytest.fixture(scope="module")
def short_drive(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from fdi_host.cli import main as sim_main

    out = tmp_path_factory.mktemp("drive")
    rc = sim_main(["--scenario", "fig6", "--no-scenario-faults", "--fault", "f4@3.5s:0.5", "--duration", "5",
                   "--out", str(out / "d.blf"), "--out", str(out / "d.log"), "--out", str(out / "d.asc"), "--quiet"])
    assert rc == 0
    return out


def test_log_formats_give_the_same_offline_diagnosis(short_drive: Path) -> None:
    runs = {ext: replay_offline(read_log(short_drive / f"d.{ext}"), "kin") for ext in ("blf", "log", "asc")}
    ref = runs["blf"].session.steps
    assert len(ref) >= 500 and any(s.alarm_mask for s in ref)
    for ext in ("log", "asc"):
        other = runs[ext].session.steps
        assert [(s.step, s.alarm_mask, s.candidates) for s in other] == [(s.step, s.alarm_mask, s.candidates)
                                                                         for s in ref], ext
        for a, b in zip(ref, other, strict=True):
            assert a.residuals == pytest.approx(b.residuals, rel=1e-6, abs=1e-9)


def test_replay_onto_a_bus_delivers_every_frame(short_drive: Path) -> None:
    import can

    from fdi_host.replay import main as replay_main

    rx = can.Bus(interface="virtual", channel="replay-test")
    try:
        assert replay_main([str(short_drive / "d.log"), "--speed", "max", "--interface", "virtual",
                            "--channel", "replay-test"]) == 0
        got = []
        while (m := rx.recv(timeout=0.0)) is not None:
            got.append((m.arbitration_id, bytes(m.data)))
    finally:
        rx.shutdown()
    sent = [(f.frame_id, f.data) for f in read_log(short_drive / "d.log")]
    assert got == sent


def test_replay_rejects_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from fdi_host.replay import main as replay_main

    assert replay_main([str(tmp_path / "missing.blf"), "--offline"]) == 1  # a bad input, not a usage error
    assert "missing.blf: no such file" in capsys.readouterr().err
    bad = tmp_path / "x.txt"
    bad.write_text("hello")
    with pytest.raises(SystemExit):
        replay_main([str(bad), "--offline"])
    empty = tmp_path / "e.log"
    empty.write_text("")
    assert replay_main([str(empty), "--offline"]) == 1
    with pytest.raises(SystemExit):
        replay_main([str(empty), "--speed", "0"])
    assert "no data frames" in capsys.readouterr().err


def test_real_time_pacing(short_drive: Path) -> None:
    """At speed 1 (and 5) each frame leaves at its log time: the send times follow the schedule."""
    import can
    import numpy as np

    from fdi_host.live.sender import send_paced

    frames = [f for f in read_log(short_drive / "d.log") if f.timestamp < 0.6]
    bus = can.Bus(interface="virtual", channel="pacing-test")
    try:
        for speed in (1.0, 5.0):
            log = send_paced(bus, frames, speed)
            lag = (np.asarray(log.wall) - log.start_wall) - np.asarray(log.sim_t) / speed
            assert len(log.wall) == len(frames)
            assert float(np.median(lag)) < 0.002 and float(lag.min()) > -0.001  # never early, mostly on time
            assert log.wall[-1] - log.start_wall == pytest.approx(frames[-1].timestamp / speed, abs=0.05)
    finally:
        bus.shutdown()


def test_one_call_replay_equals_frame_by_frame(short_drive: Path) -> None:
    """fdi-replay --offline's fast path (one C call) gives the diagnosis of the per-frame EcuSession path."""
    from fdi_host.replay import replay_offline_fast

    frames = read_log(short_drive / "d.blf")
    slow = replay_offline(frames, "kin").session.records()
    fast = replay_offline_fast(frames, "kin").records
    slow_by_t = {round(r.t, 6): r for r in slow}
    assert len(fast) >= 490 and any(r.alarm_mask for r in fast)
    for r in fast:
        s = slow_by_t[round(r.t, 6)]
        assert (r.alarm_mask, r.candidates, r.iso_class) == (s.alarm_mask, s.candidates, s.iso_class), r.t
    assert len(slow) - len(fast) <= 1  # the per-frame path adds the step due after the last frame
