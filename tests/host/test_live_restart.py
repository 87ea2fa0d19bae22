"""The live loop survives restarts: fdi-live in a private network namespace (udp_multicast) kills the ECU
process and, later, the simulator (SIGKILL), and starts each again after a down time; a vx sensor fault f4
follows on the kinematic table. The monitor must report both silences as gaps with plausible times, the ECU
must recover after each (diagnosis frames again, tests evaluable after the warm-up, the restarted
simulator's frames with restarted alive counters accepted after at most one rejected frame per message), nothing may
be isolated or alarmed before the fault, and the fault must still be detected and isolated.
Skipped (with the reason) only where a network namespace cannot be made, as test_live_netns.py.

Also, without a bus: the restart schedule, the restarted sender's frames, the ECU joining a drive under way.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from fdi_host.can import e2e
from fdi_host.can.dbc import CanDatabase
from fdi_host.can.frame import Frame
from fdi_host.can.logs import LogError, read_log, write_log
from fdi_host.ecu.session import ORIGIN_LEAD, EcuSession, load_steps
from fdi_host.live.netns import check_unshare
from fdi_host.live.restart import RestartEvent, restart_schedule
from fdi_host.live.sender import resume_frames

# Timeline (drive seconds): the restarted ECU is back ~1 s after its start and warms up for ~3.2 s (the kin
# table's settling time) before the simulator is killed; the simulator is back ~1-1.5 s after its start, the
# ECU warms up again, then the fault, which stays to the end (fault-free, then faulty: no removal transient);
# the ECU exonerates a quiet test, i.e. isolates, only after 3 s of alarm. The cornering scenario (steady
# turn from 5 s): every test of f4's signature reacts, so f4 is isolable exactly.
DURATION = 21.5
ECU_KILL, ECU_DOWN = 1.5, 1.0
SIM_KILL, SIM_DOWN = 8.5, 1.0
COUNTER_START = 9
FAULT = ("f4", 16.0)


@pytest.fixture(scope="module")
def restart_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    pytest.importorskip("msgpack", reason="python-can's udp_multicast interface needs msgpack")
    chk = check_unshare()
    if not chk.ok:
        pytest.skip(f"no private network namespace for udp_multicast: {chk.reason}")
    out = tmp_path_factory.mktemp("restart")
    f, a = FAULT
    cmd = [sys.executable, "-m", "fdi_host.live.runner", "--transport", "netns", "--scenario", "cornering",
           "--no-scenario-faults", "--fault", f"{f}@{a}s:0.5", "--duration", str(DURATION),
           "--vehicle", "kin", "--out-dir", str(out), "--channel", "239.74.163.8",
           "--restart-ecu-at", str(ECU_KILL), "--ecu-down", str(ECU_DOWN),
           "--restart-sim-at", str(SIM_KILL), "--sim-down", str(SIM_DOWN), "--sim-counter-start", str(COUNTER_START)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=240, check=False)
    (out / "runner.txt").write_text(proc.stdout + proc.stderr)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return out


N_SENSOR_MESSAGES = 8


def _doc(run: Path, name: str) -> Any:
    return json.loads((run / name).read_text())


def test_both_gaps_reported(restart_run: Path) -> None:
    score = _doc(restart_run, "report.json")["score"]
    restarts = _doc(restart_run, "restarts.json")
    assert score["gap_count"] == {"diagnosis": 1, "sensors": 1}, score["gaps"]
    gaps = {g["stream"]: g for g in score["gaps"]}
    for stream, proc, down in (("diagnosis", "ecu", ECU_DOWN), ("sensors", "simulator", SIM_DOWN)):
        g = gaps[stream]
        (killed,) = restarts[proc]["killed_at"]
        (started,) = restarts[proc]["started_at"]
        assert g["resumed"]
        # The silence starts with the kill (the last frame before it) and lasts the down time plus the time
        # the new process needs to be back on the bus (seconds at most, on a loaded 2-core machine).
        assert killed - 0.15 <= g["start"] <= killed + 0.05, (g, killed)
        assert started - killed == pytest.approx(down, abs=0.2)
        assert down - 0.1 <= g["duration"] <= down + 8.0, g
        assert g["end"] >= started
    assert restarts["ecu"]["ready_at"][0] <= gaps["diagnosis"]["end"] + 0.5  # polled by the runner, 20 ms
    md = (restart_run / "report.md").read_text()
    assert "## Gaps" in md and "ECU silent" in md and "simulator silent" in md
    runner = (restart_run / "runner.txt").read_text()
    assert "ECU killed (SIGKILL)" in runner and "simulator started again" in runner and "gap: ECU silent" in runner


def test_ecu_recovers_after_each_gap(restart_run: Path) -> None:
    gaps = {g["stream"]: g for g in _doc(restart_run, "report.json")["score"]["gaps"]}
    dg, sg = gaps["diagnosis"], gaps["sensors"]
    # ecu.json is the restarted ECU's log (the killed one writes nothing): it starts at the end of the ECU gap.
    steps = load_steps(restart_run / "ecu.json")
    t = [s.t - ORIGIN_LEAD for s in steps]
    assert t[0] == pytest.approx(dg["end"], abs=0.1)
    all_tests = max(s.evaluable_mask for s in steps)
    assert all_tests == 0b1111
    # Warmed up after its restart: every test evaluable before the simulator was killed.
    assert any(s.evaluable_mask == all_tests for s, ts in zip(steps, t, strict=True) if ts < sg["start"])
    # While the simulator is down the inputs time out: nothing is evaluable, nothing alarms, nothing isolated.
    during = [s for s, ts in zip(steps, t, strict=True) if sg["start"] + 0.1 < ts < sg["end"]]
    assert len(during) >= 0.5 * (sg["duration"] - 0.1) / 0.01  # the ECU keeps stepping on its timer
    assert all(s.evaluable_mask == 0 and s.alarm_mask == 0 and s.candidates == 0 for s in during)
    # Back after the simulator's restart: diagnosis frames and, after the warm-up, every test evaluable again.
    after = [ts for s, ts in zip(steps, t, strict=True) if ts > sg["end"] and s.evaluable_mask == all_tests]
    assert after and after[0] < FAULT[1], "tests not evaluable again before the fault"
    ecu = _doc(restart_run, "ecu.json")["counters"]
    # The restarted simulator's counters start at 9: the ECU re-synchronises on the first frame of each message,
    # which is rejected as a counter jump, or as a repeat where the killed sender's last counter happened to be
    # 9 too (or accepted where 9 continued its sequence), so at most one rejected frame per message.
    rejected = {k: v for k, v in ecu["rejected"].items() if v}
    assert set(rejected) <= {"counter_jump", "repeated_counter"}, rejected
    per_message = {k: sum(m["rejected"].values()) for k, m in ecu["messages"].items()}
    assert len(per_message) == N_SENSOR_MESSAGES and max(per_message.values()) <= 1, per_message
    assert all(m["timeouts"] >= 1 for m in ecu["messages"].values())  # the simulator's gap timed every one out
    diag = _doc(restart_run, "report.json")["frames"]["messages"]["0x200"]
    assert diag["gaps"] == 1 and diag["lost"] == 0 and diag["e2e_errors"] == 0


def test_no_false_isolation_and_fault_still_detected(restart_run: Path) -> None:
    score = _doc(restart_run, "report.json")["score"]
    assert score["false_alarm_count"] == 0, score["false_alarms"]
    steps = load_steps(restart_run / "ecu.json")
    before = [s for s in steps if s.t - ORIGIN_LEAD < FAULT[1]]
    assert before and all(s.alarm_mask == 0 and s.candidates == 0 for s in before)
    (f4,) = [f for f in score["faults"] if f["fault"] == "f4"]
    assert f4["gap_overlap"] == 0.0 and not f4["not_evaluable"]
    assert f4["detected"] and f4["detection_delay"] >= 0.0
    # Detected within 1 s of the moment the tests can see it: the onset, or, where a sensor message timed out
    # after the restart (frames more than 3 cycle times apart on a loaded machine), the end of the warm-up.
    full = max(s.evaluable_mask for s in steps)
    timed = [(s.t - ORIGIN_LEAD, s) for s in steps]
    alarm = next(t for t, s in timed if t >= FAULT[1] and s.alarm_mask)
    blind = [t for t, s in timed if t <= alarm and s.evaluable_mask != full]
    seeing_from = max([FAULT[1], *(t + 0.01 for t in blind)])
    assert alarm - seeing_from < 1.0, (alarm, seeing_from, f4["detection_delay"])
    assert f4["isolation_delay"] is not None and f4["isolated_fraction"] > 0.0 and not f4["wrong_isolation"]


# ------------------------------------------------------------------------------------------ without a bus


def test_restart_schedule() -> None:
    ev = restart_schedule([3.0], [8.0, 2.0], ecu_down=1.0, sim_down=0.5)
    assert ev == [RestartEvent(2.0, "sim", "kill"), RestartEvent(2.5, "sim", "start"),
                  RestartEvent(3.0, "ecu", "kill"), RestartEvent(4.0, "ecu", "start"),
                  RestartEvent(8.0, "sim", "kill"), RestartEvent(8.5, "sim", "start")]
    assert restart_schedule([], [], 0.0, 0.0) == []
    with pytest.raises(ValueError, match="down time"):
        restart_schedule([3.0], [], 0.0, 1.0)
    with pytest.raises(ValueError, match="overlaps"):
        restart_schedule([3.0, 3.5], [], 1.0, 1.0)
    with pytest.raises(ValueError, match=">= 0"):
        restart_schedule([], [-1.0], 1.0, 1.0)


def test_resumed_frames_restart_counters_with_valid_crc(tmp_path: Path) -> None:
    db = CanDatabase()
    frames = []
    for k in range(40):  # IMU every 5 ms, velocity every 10 ms, counters running from 0
        frames.append(Frame(k * 0.005, 128, db.encode("IMU_Motion", {"IMU_AccelX": 0.01 * k}, k % 15)))
        if k % 2 == 0:
            frames.append(Frame(k * 0.005, 136, db.encode("VelocitySensor", {}, (k // 2) % 15)))
    out = resume_frames(frames, 0.1, 13, db)
    assert [f.timestamp for f in out] == [f.timestamp for f in frames if f.timestamp >= 0.1]
    for fid, name in ((128, "IMU_Motion"), (136, "VelocitySensor")):
        mine = [f for f in out if f.frame_id == fid]
        assert [e2e.counter_of(f.data) for f in mine[:4]] == [13, 14, 0, 1]
        did = db.data_id(name)
        assert did is not None and all(e2e.p11_crc(f.data, did) == f.data[0] for f in mine)
        # The payload is unchanged apart from CRC and counter.
        orig = [f for f in frames if f.frame_id == fid and f.timestamp >= 0.1]
        assert all(a.data[2:] == b.data[2:] and a.data[1] >> 4 == b.data[1] >> 4 for a, b in zip(orig, mine,
                                                                                                  strict=True))
    assert resume_frames(frames, 99.0, 0, db) == []
    with pytest.raises(ValueError, match="counter start"):
        resume_frames(frames, 0.0, 15, db)

    log = tmp_path / "d.blf"
    write_log([Frame(f.timestamp, f.frame_id, f.data) for f in frames], log)
    back = read_log(log)
    assert [(f.frame_id, f.data) for f in back] == [(f.frame_id, f.data) for f in frames]
    with pytest.raises(LogError, match="unsupported"):
        read_log(tmp_path / "d.txt")
    with pytest.raises(LogError, match="no such file"):
        read_log(tmp_path / "missing.blf")
    good = log.read_bytes()  # a real .blf with its object headers garbled
    (tmp_path / "corrupt.blf").write_bytes(good[:144] + b"\xff" * 100 + good[244:])
    with pytest.raises(LogError, match=r"corrupt\.blf: not a readable \.blf log"):
        read_log(tmp_path / "corrupt.blf")


def test_ecu_joining_a_drive_under_way_starts_on_the_step_grid() -> None:
    """A restarted ECU anchors to the drive's t = 0 and starts at the step boundary before its first frame:
    no catch-up (or skipped) steps for the time it was down, steps on the same k * dt grid."""
    db = CanDatabase()
    s = EcuSession("kin")
    origin = 1000.0
    first = origin + 12.3455  # frames on whole milliseconds of the drive, 0.5 ms late on the bus
    s.anchor(origin, 0.0, first)
    assert s.last_t == pytest.approx(12.34, abs=1e-9)  # floor((12.3455 + 0.0005) / 0.01) * 0.01
    for k in range(200):  # 1 s of IMU frames
        s.feed(128, db.encode("IMU_Motion", {}, k % 15), first + k * 0.005)
    c = s.ecu.counters()
    assert c.steps_skipped == 0 and 98 <= c.steps <= 101
    k = s.next_step / s.dt
    assert k == pytest.approx(round(k), abs=1e-6)  # still on the grid of the drive's t = 0
    # Joining at the drive's start is the usual anchoring (first step at 0).
    s0 = EcuSession("kin")
    s0.anchor(origin, 0.0, origin + 0.0002)
    assert s0.last_t == 0.0
