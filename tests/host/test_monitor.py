"""The monitor's scoring on synthetic frames: detection delay, wrong isolation, false alarms, lost/late frames."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fdi_host.can import e2e
from fdi_host.can.dbc import CanDatabase
from fdi_host.ecu.records import DiagRecord, TableClasses
from fdi_host.ecu.session import StepRecord
from fdi_host.monitor.cli import Monitor
from fdi_host.monitor.report import plot_diagnosis, plot_residuals, score_table, write_reports
from fdi_host.monitor.score import FaultWindow, score_run, windows_from_truth

# Signatures of the kinematic table (fw/src/fdi_kin_table.c): tests 0..3 over f1..f5, all unique.
KIN = TableClasses.from_signatures([0x0D, 0x0E, 0x0F, 0x07, 0x0B], ["r1", "r2", "r3", "r4"])
F = {f"f{k}": 1 << (k - 1) for k in range(1, 26)}
DT = 0.01


def _truth(windows: list[tuple[str, float, float]], duration: float) -> dict[str, object]:
    return {"start_time": 0.0, "duration": duration,
            "faults": [{"fault": f, "intervals": [{"start": a, "end": b, "min": 1, "max": 1}]} for f, a, b in windows]}


def _diag_frame(db: CanDatabase, alarm: int, cand: int, counter: int) -> bytes:
    return db.encode("FDI_Diagnosis", {"FDI_AlarmMask": alarm, "FDI_CandidateFaults": cand,
                                       "FDI_IsolationClass": 0, "FDI_Status": 1}, counter)


def _run_monitor(db: CanDatabase, plan: list[tuple[float, float, int, int]], duration: float,
                 drop_imu: set[int], late_imu: dict[int, float]) -> Monitor:
    """IMU frames every 5 ms (some dropped / delayed) and a diagnosis frame every 10 ms following `plan`:
    (from, to, alarm mask, candidates); the bus starts at wall time 1000 s."""
    mon = Monitor(db, KIN)
    t_wall0 = 1000.0
    events: list[tuple[float, int, bytes]] = []
    c = 0
    for k in range(round(duration / 0.005)):
        if k not in drop_imu:
            data = db.encode("IMU_Motion", {"IMU_AccelX": 0.1}, c)
            events.append((t_wall0 + k * 0.005 + late_imu.get(k, 0.0), 128, data))
        c = e2e.next_counter(c)
    c = 0
    for k in range(round(duration / DT)):
        t = k * DT
        alarm, cand = 0, 0
        for a, b, am, cm in plan:
            if a <= t < b:
                alarm, cand = am, cm
        events.append((t_wall0 + t + 0.0007, 512, _diag_frame(db, alarm, cand, c)))
        c = e2e.next_counter(c)
    for t, fid, data in sorted(events, key=lambda e: e[0]):
        mon.on_frame(fid, data, t)
    return mon


@pytest.fixture(scope="module")
def scored(db: CanDatabase) -> tuple[Monitor, dict[str, object]]:
    plan = [
        (1.0, 1.2, 0b0001, 0),  # false alarm, nothing injected
        (3.25, 5.5, 0b0111, F["f4"]),  # f4 detected 0.25 s late, isolated correctly
        (7.4, 7.9, 0b1101, F["f3"]),  # f1 detected 0.4 s late, isolated to f3: wrong
        (9.0, 9.1, 0b1000, 0),  # second false alarm
    ]
    truth = _truth([("f4", 3.0, 5.0), ("f1", 7.0, 8.0), ("f6", 2.0, 2.5)], 10.0)
    mon = _run_monitor(db, plan, 10.0, drop_imu={100, 101, 102}, late_imu={500: 0.004})
    return mon, truth


def test_detection_delay_and_isolation(scored: tuple[Monitor, dict[str, object]]) -> None:
    mon, truth = scored
    s = mon.score(truth, grace=1.0)
    by = {f.fault: f for f in s.faults}
    # Monitor time = receive time - first IMU frame, diagnosis frames arrive 0.7 ms after their step.
    assert by["f4"].detected and by["f4"].detection_delay == pytest.approx(0.25 + 0.0007, abs=1e-6)
    assert by["f4"].isolation_correct is True and not by["f4"].wrong_isolation and by["f4"].verdict == "f4"
    assert by["f4"].isolation_delay == pytest.approx(0.25 + 0.0007, abs=1e-6) and by["f4"].isolated_fraction == 1.0
    assert by["f1"].detected and by["f1"].detection_delay == pytest.approx(0.4 + 0.0007, abs=1e-6)
    assert by["f1"].isolation_correct is False and by["f1"].wrong_isolation and by["f1"].verdict == "f3"
    assert by["f1"].isolation_delay is None and by["f1"].isolated_fraction == 0.0
    # f6 is outside the kinematic table: not detectable, and nothing alarmed in its window.
    assert not by["f6"].detectable and not by["f6"].detected and by["f6"].isolation_correct is None


def test_false_alarms(scored: tuple[Monitor, dict[str, object]]) -> None:
    mon, truth = scored
    s = mon.score(truth, grace=1.0)
    assert len(s.false_alarms) == 2
    assert s.false_alarms[0].start == pytest.approx(1.0007, abs=1e-6)
    assert s.false_alarms[0].end - s.false_alarms[0].start == pytest.approx(0.2, abs=DT + 1e-6)
    assert s.false_alarms[0].tests == "r1" and s.false_alarms[1].tests == "r4"
    assert s.false_alarm_time == pytest.approx(0.3, abs=2 * DT)
    # The alarm of f4 holds 0.5 s past its end (5.0..5.5), within the grace.
    by = {f.fault: f for f in s.faults}
    assert by["f4"].alarm_after_end == pytest.approx(0.5 + 0.0007, abs=DT + 1e-6) and s.held_beyond_grace == []
    # With no grace, that run is still f4's (no test joins it), now held beyond the grace, and no false alarm.
    s0 = mon.score(truth, grace=0.0)
    assert len(s0.false_alarms) == 2 and [f.fault for f in s0.held_beyond_grace] == ["f4"]
    assert "held beyond the 0 s grace: f4 0.5" in score_table(s0)


def test_an_alarm_held_past_the_window_is_the_faults_until_a_test_joins() -> None:
    """A run that starts in f4's window and goes on past end + grace with the window's tests is f4's slow
    recovery, not a false alarm; from the step another test joins, or after the run broke off, it is."""

    def run(plan: list[tuple[float, float, int]]) -> list[DiagRecord]:
        return [DiagRecord(k * DT, sum(m for a, b, m in plan if a <= k * DT < b), 0) for k in range(600)]

    f4 = [FaultWindow("f4", 1.0, 2.0)]
    held = score_run(run([(1.2, 3.5, 0b0011)]), f4, KIN, 1.0)
    assert held.false_alarms == [] and held.faults[0].alarm_after_end == pytest.approx(1.5, abs=DT)
    assert [f.fault for f in held.held_beyond_grace] == ["f4"]
    assert json.loads(json.dumps(held.to_json()))["held_beyond_grace"] == ["f4"]
    # r3 joins at 3.2 s: from there it is a false alarm (r1, r2 and r3 alarmed in it).
    joined = score_run(run([(1.2, 3.5, 0b0011), (3.2, 3.6, 0b0100)]), f4, KIN, 1.0)
    (fa,) = joined.false_alarms
    assert fa.start == pytest.approx(3.2, abs=DT) and fa.end == pytest.approx(3.6, abs=DT) and fa.tests == "r1,r2,r3"
    assert joined.faults[0].alarm_after_end == pytest.approx(1.2, abs=DT)
    # The alarm clears at 2.5 s and comes back at 3.1 s, outside the window: false.
    again = score_run(run([(1.2, 2.5, 0b0011), (3.1, 3.3, 0b0001)]), f4, KIN, 1.0)
    assert len(again.false_alarms) == 1 and again.false_alarms[0].start == pytest.approx(3.1, abs=DT)
    assert again.faults[0].alarm_after_end == pytest.approx(0.5, abs=DT) and again.held_beyond_grace == []
    # Quiet before the end: nothing held after it.
    assert score_run(run([(1.2, 1.5, 0b0011)]), f4, KIN, 1.0).faults[0].alarm_after_end == 0.0


def test_lost_and_late_frames(scored: tuple[Monitor, dict[str, object]]) -> None:
    mon, _ = scored
    imu, diag = mon.stats.messages[128], mon.stats.messages[512]
    assert imu.lost == 3 and imu.received == 2000 - 3
    assert imu.late == 1 and imu.max_lateness == pytest.approx(0.004, abs=1e-9)
    assert diag.lost == 0 and diag.late == 0 and diag.received == 1000
    assert len(mon.records) == 1000


def test_corrupted_and_unknown_frames_are_counted(db: CanDatabase) -> None:
    mon = Monitor(db, KIN)
    good = db.encode("IMU_Motion", {"IMU_AccelX": 0.1}, 0)
    mon.on_frame(128, good, 1.0)
    bad = bytes([good[0] ^ 0xFF]) + good[1:]
    assert mon.on_frame(128, bad, 1.005) is None
    mon.on_frame(0x7FF, b"\x00" * 8, 1.006)
    mon.on_frame(128, good, 1.007)  # same counter again
    assert mon.stats.messages[128].e2e_errors == 1 and mon.stats.messages[128].repeated == 1
    assert mon.stats.unknown == 1
    # A corrupted diagnosis frame is not a diagnosis.
    d = _diag_frame(db, 1, F["f4"], 0)
    assert mon.on_frame(512, bytes([d[0] ^ 1]) + d[1:], 1.01) is None and not mon.records


def test_windows_from_truth_subtracts_start_time() -> None:
    w = windows_from_truth({"start_time": 100.0, "faults": [{"fault": "f4", "intervals": [{"start": 105.0,
                                                                                           "end": 107.5}]}]})
    assert w == [FaultWindow("f4", 5.0, 7.5)]


def test_classes_and_coarse_isolation() -> None:
    tc = TableClasses.from_signatures([0b01, 0b10, 0b01, 0])
    assert tc.iso_class[:4] == (0b0101, 0b0010, 0b0101, 0)
    assert not tc.detectable("f4") and tc.detectable("f3")
    assert TableClasses((), ()).fault_names(0b0101) == "f1,f3" and TableClasses((), ()).fault_names(0) == "-"
    recs = [DiagRecord(k * DT, 1 if k >= 20 else 0, 0b0101 if k >= 20 else 0) for k in range(100)]
    s = score_run(recs, [FaultWindow("f3", 0.1, 1.0)], tc)
    assert s.faults[0].isolation_correct is True  # {f1, f3} is f3's structural class
    recs2 = [DiagRecord(r.t, r.alarm_mask, 0b0111 if r.alarm_mask else 0) for r in recs]
    s2 = score_run(recs2, [FaultWindow("f3", 0.1, 1.0)], tc)
    assert s2.faults[0].isolation_correct is False and not s2.faults[0].wrong_isolation  # too coarse
    s3 = score_run(recs, [FaultWindow("f4", 0.1, 1.0)], tc)  # f4: no test sees it, the alarms are not its
    assert s3.faults[0].detected and s3.faults[0].isolation_correct is None and not s3.faults[0].wrong_isolation


def test_part_of_the_class_isolates_only_with_the_fault() -> None:
    """Candidates within the fault's class count as its isolation when they hold the fault ({f3} of {f1, f3}:
    the library's `isolated`, as the quality suite counts it), never when they exonerate it ({f1} for f3)."""
    tc = TableClasses.from_signatures([0b01, 0b10, 0b01, 0])
    w = [FaultWindow("f3", 0.1, 1.0)]
    early = [DiagRecord(k * DT, 1 if k >= 20 else 0, 0b0101 if 20 <= k < 40 else 0b0100 if k >= 40 else 0)
             for k in range(100)]
    s = score_run(early, w, tc).faults[0]
    assert s.isolation_correct is True and s.verdict == "f3" and s.isolation_delay == pytest.approx(0.1)
    assert s.isolated_fraction == pytest.approx(1.0)
    part = [DiagRecord(r.t, r.alarm_mask, 0b0100 if r.alarm_mask else 0) for r in early]
    late = [DiagRecord(r.t, r.alarm_mask, 0b0110 if 20 <= k < 70 else r.candidates) for k, r in enumerate(part)]
    s2 = score_run(late, w, tc).faults[0]  # {f2, f3} (two classes) first, then {f3}
    assert s2.isolation_delay == pytest.approx(0.6) and s2.isolated_fraction == pytest.approx(30 / 80)
    assert s2.verdict == "f2,f3" and s2.isolation_correct is False and not s2.wrong_isolation
    wrong = [DiagRecord(r.t, r.alarm_mask, 0b0001 if r.alarm_mask else 0) for r in early]
    s3 = score_run(wrong, w, tc).faults[0]  # f3's class, named by the other fault alone
    assert s3.isolation_correct is False and s3.wrong_isolation and s3.isolation_delay is None


def test_reports_and_plots(scored: tuple[Monitor, dict[str, object]], tmp_path: Path) -> None:
    mon, truth = scored
    s = mon.score(truth, grace=1.0)
    paths = write_reports(tmp_path, s, mon.stats, {"table": "kin"})
    doc = json.loads((tmp_path / "report.json").read_text())
    assert doc["score"]["false_alarm_count"] == 2 and doc["frames"]["messages"]["0x080"]["lost"] == 3
    md = (tmp_path / "report.md").read_text()
    assert "f4" in md and "WRONG" in md and "false alarms: 2 episodes" in score_table(s)
    windows = windows_from_truth(truth)
    steps = [StepRecord(k, k * DT + 0.0005, 128, 0, 0.0, 0.0, 1 if k > 300 else 0, 0xF, 0, 0,
                        [0.0] * 4, [0.5, 1.5 if k > 300 else 0.2, 0.1, 0.1], k % 15) for k in range(1000)]
    assert plot_residuals(tmp_path / "r.png", steps, windows, KIN, 0.0005) is not None
    assert plot_diagnosis(tmp_path / "d.png", mon.records, windows, KIN) is not None
    for p in [*paths, tmp_path / "r.png", tmp_path / "d.png"]:
        assert p.stat().st_size > 0


def test_live_table_shows_alarms_and_candidates(db: CanDatabase) -> None:
    mon = Monitor(db, KIN)
    mon.on_frame(128, db.encode("IMU_Motion", {}, 0), 5.0)
    assert mon.table()[-1].startswith("candidates: -")
    mon.on_frame(512, db.encode("FDI_Diagnosis", {"FDI_AlarmMask": 0b0111, "FDI_CandidateFaults": F["f4"],
                                                  "FDI_IsolationClass": 4, "FDI_Status": 3}, 0), 5.01)
    rows = mon.table()
    assert [r.split()[:3] for r in rows[2:6]] == [["r1", "ALARM", "1"], ["r2", "ALARM", "1"], ["r3", "ALARM", "1"],
                                                 ["r4", "ok", "0"]]
    assert rows[-1] == "candidates: f4  (isolated)"
    assert "alarm [r1,r2,r3]" in mon.status_line()


def test_unexplained_alarms_are_not_a_wrong_isolation() -> None:
    recs = [DiagRecord(k * DT, 0b0101 if k >= 20 else 0, 0) for k in range(100)]  # alarms, no candidate
    s = score_run(recs, [FaultWindow("f4", 0.1, 1.0)], KIN)
    f = s.faults[0]
    assert f.detected and f.isolation_correct is False and not f.wrong_isolation and f.verdict == "-"
    assert "unexplained" in score_table(s)


def test_merged_diagnosis_steps_count_one_late_frame(db: CanDatabase) -> None:
    """The ECU merges steps that fall due together (one frame, counter + 1): one late frame, no drift after."""
    mon = Monitor(db, KIN)
    mon.on_frame(128, db.encode("IMU_Motion", {}, 0), 1.0)
    t, c = 1.0007, 0
    for k in range(200):
        t += 0.04 if k == 100 else DT  # a 40 ms stall of the ECU, then on time again
        mon.on_frame(512, _diag_frame(db, 0, 0, c), t)
        c = e2e.next_counter(c)
    st = mon.stats.messages[512]
    assert st.received == 200 and st.lost == 0 and st.late == 1
    assert st.max_lateness == pytest.approx(0.03, abs=1e-9)


def _run_with_silences(db: CanDatabase, duration: float, imu_off: tuple[float, float] | None,
                       diag_off: tuple[float, float] | None, plan: list[tuple[float, float, int, int]] = (),
                       restart_counter: int = 9) -> Monitor:
    """IMU frames every 5 ms and diagnosis frames every 10 ms (alarms per `plan`), each stream silent over
    its `*_off` interval [a, b) of the drive's clock; after a silence the stream's counter restarts at
    `restart_counter` (a restarted sender). Drive t = 0 at wall time 1000 s (the first IMU frame)."""
    mon = Monitor(db, KIN)
    events: list[tuple[float, int, bytes]] = []
    for fid, cycle, off in ((128, 0.005, imu_off), (512, DT, diag_off)):
        c, silent_before = 0, False
        for k in range(round(duration / cycle)):
            t = k * cycle
            if off is not None and off[0] <= t < off[1]:
                silent_before = True
                continue
            if silent_before:
                c, silent_before = restart_counter, False
            if fid == 128:
                data = db.encode("IMU_Motion", {"IMU_AccelX": 0.1}, c)
                events.append((1000.0 + t, fid, data))
            else:
                alarm, cand = 0, 0
                for a, b, am, cm in plan:
                    if a <= t < b:
                        alarm, cand = am, cm
                events.append((1000.0 + t + 0.0007, fid, _diag_frame(db, alarm, cand, c)))
            c = e2e.next_counter(c)
    for t, fid, data in sorted(events, key=lambda e: e[0]):
        mon.on_frame(fid, data, t)
    return mon


def test_ecu_and_simulator_silences_are_gaps_not_lost_frames(db: CanDatabase) -> None:
    mon = _run_with_silences(db, 10.0, imu_off=(6.0, 7.5), diag_off=(2.0, 3.2))
    assert [(g.stream, g.resumed) for g in mon.gaps.gaps] == [("diagnosis", True), ("sensors", True)]
    d, s = mon.gaps.gaps
    # The gap runs from the last frame before the silence to the first after it.
    assert d.start == pytest.approx(1.9907, abs=1e-6) and d.end == pytest.approx(3.2007, abs=1e-6)
    assert d.duration == pytest.approx(1.21, abs=1e-6)
    assert s.start == pytest.approx(5.995, abs=1e-6) and s.duration == pytest.approx(1.505, abs=1e-6)
    imu, diag = mon.stats.messages[128], mon.stats.messages[512]
    # Counters restarting at 9 after the silence: not lost frames, and the nominal times start afresh.
    assert (imu.gaps, imu.lost, imu.late, imu.repeated) == (1, 0, 0, 0)
    assert (diag.gaps, diag.lost, diag.late, diag.repeated) == (1, 0, 0, 0)
    assert imu.gap_time == pytest.approx(1.505, abs=1e-6) and diag.gap_time == pytest.approx(1.21, abs=1e-6)
    assert [g.stream for g in mon.new_gaps] == ["diagnosis", "sensors"]
    # Live table while a silence lasts, and after.
    assert mon.silence_note(1000.0 + 10.5) == "DIAGNOSIS SILENT for 0.5 s  SENSORS SILENT for 0.5 s"
    assert mon.silence_note(1000.0 + 9.0) == "" and mon.table(1000.0 + 9.0)[-2].startswith("  gap: ECU silent")


def test_short_jitter_is_no_gap(db: CanDatabase) -> None:
    mon = _run_with_silences(db, 3.0, imu_off=(1.0, 1.2), diag_off=(2.0, 2.2))  # 0.2 s < 0.25 s threshold
    assert mon.gaps.gaps == [] and mon.finish_gaps(3.0) == []
    assert mon.stats.messages[128].gaps == 0


def test_silences_that_never_end(db: CanDatabase) -> None:
    # The ECU dies at 6 s and never comes back while the drive goes on to 10 s: an open diagnosis gap.
    mon = _run_with_silences(db, 10.0, imu_off=None, diag_off=(6.0, 99.0))
    (g,) = mon.finish_gaps(10.0)
    assert g.stream == "diagnosis" and not g.resumed and g.end == pytest.approx(9.995, abs=1e-6)
    # The simulator dies at 7 s of a 10 s drive: an open sensor gap up to the drive's end; the ECU's frames
    # go on meanwhile (its timer), so the diagnosis stream has no gap.
    mon = _run_with_silences(db, 10.0, imu_off=(7.0, 99.0), diag_off=None)
    (g,) = mon.finish_gaps(10.0)
    assert g.stream == "sensors" and not g.resumed and g.duration == pytest.approx(3.005, abs=1e-6)
    # The normal end of a drive is no gap.
    assert _run_with_silences(db, 10.0, None, None).finish_gaps(10.0) == []


def test_gaps_in_scoring_and_reports(db: CanDatabase, tmp_path: Path) -> None:
    plan = [(8.5, 9.5, 0b0111, F["f4"])]  # f4's second window detected; the alarm before the gap is false
    plan.append((1.0, 1.95, 0b0001, 0))
    mon = _run_with_silences(db, 10.0, imu_off=(4.0, 5.0), diag_off=(1.95, 3.0), plan=plan)
    # f1 falls into the ECU's gap, f2 into the simulator's, f4 after both; f5 overlaps nothing and is missed.
    truth = _truth([("f1", 2.0, 2.5), ("f2", 4.2, 4.6), ("f4", 8.4, 9.0), ("f5", 6.0, 6.5)], 10.0)
    s = mon.score(truth, grace=0.5)
    by = {f.fault: f for f in s.faults}
    assert by["f1"].not_evaluable and not by["f1"].detected and by["f1"].gap_overlap == pytest.approx(1.0, abs=0.02)
    assert by["f2"].not_evaluable and by["f2"].gap_overlap == pytest.approx(0.8, abs=0.02)
    assert by["f4"].detected and not by["f4"].not_evaluable and by["f4"].gap_overlap == 0.0
    assert not by["f5"].detected and not by["f5"].not_evaluable  # a plain miss stays a miss
    assert [g.stream for g in s.gaps] == ["diagnosis", "sensors"]
    table = score_table(s)
    assert table.count("not eval.") == 2 and "missed" in table and "gaps: diagnosis 1" in table
    assert "ECU silent (no FDI_Diagnosis) from 1.94 s to 3.00 s" in table
    write_reports(tmp_path, s, mon.stats, {"table": "kin"})
    doc = json.loads((tmp_path / "report.json").read_text())
    assert doc["score"]["gap_count"] == {"diagnosis": 1, "sensors": 1}
    assert [round(g["duration"], 2) for g in doc["score"]["gaps"]] == [1.06, 1.0]
    assert doc["frames"]["messages"]["0x080"]["gaps"] == 1
    assert "## Gaps" in (tmp_path / "report.md").read_text()
    assert plot_diagnosis(tmp_path / "d.png", mon.records, windows_from_truth(truth), KIN, s.gaps) is not None


def test_a_gap_is_not_a_detection() -> None:
    """Alarms of diagnosis frames inside a sensor gap are not a detection (the ECU's inputs are stale);
    a false-alarm episode does not run on across an ECU gap."""
    from fdi_host.monitor.gaps import Gap

    recs = [DiagRecord(k * DT, 0b0111 if 200 <= k < 260 else 0, F["f4"] if 200 <= k < 260 else 0)
            for k in range(500)]
    gaps = [Gap("sensors", 1.9, 2.7)]
    s = score_run(recs, [FaultWindow("f4", 1.95, 2.5)], KIN, 0.1, gaps)
    assert not s.faults[0].detected and s.faults[0].not_evaluable
    assert score_run(recs, [FaultWindow("f4", 1.95, 2.5)], KIN, 0.1).faults[0].detected  # without the gap
    recs = [r for r in recs if not 2.2 <= r.t < 2.5]
    split = score_run(recs, [], KIN, 0.1, [Gap("diagnosis", 2.19, 2.5)])
    assert len(split.false_alarms) == 2 and len(score_run(recs, [], KIN, 0.1).false_alarms) == 1
