"""`fdi-tune residuals`: the generated residuals computed offline on a CAN log equal the C ECU's, step by
step; the ECU view of a log takes each message's frames at the instant the ECU's steps align to (or holds the
last one); bad logs are refused with the reason."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np
import pytest

from fdi_host.can.dbc import CanDatabase
from fdi_host.can.ecu_view import _at_instants, bus_align, ecu_view, step_times
from fdi_host.can.frame import Frame
from fdi_host.can.logs import read_log, write_log
from fdi_host.can.traffic import build_frames
from fdi_host.sim.faults import FaultSpec
from fdi_host.sim.scenario import load_scenario
from fdi_host.sim.vehicle_sim import simulate
from fdi_host.tuning.cli import main

MODEL = "analysis/models/romo_grouped.toml"
THRESHOLDS = "analysis/models/romo_thresholds.toml"


def test_step_times_sample_and_hold_and_alignment() -> None:
    db = CanDatabase()
    sim = simulate(load_scenario("cornering"), [], duration=0.2, seed=5)
    frames = build_frames(sim, db)
    t = step_times(frames, 0.01)
    assert t[0] == pytest.approx(frames[0].timestamp + 0.01) and np.allclose(np.diff(t), 0.01)
    assert t[-1] < frames[-1].timestamp  # a step runs once a later frame has arrived
    assert bus_align(db) == pytest.approx(0.02)  # the brake message's cycle, covered by 4 wheel-robot cycles
    brake = {round(f.timestamp * 1e3): db.decode_sim(272, f.data)["P_f_m"] for f in frames if f.frame_id == 272}
    k = int(np.argmin(np.abs(t - 0.05)))
    # align 0 (default), sample-and-hold: the brake message (20 ms cycle, 7 ms offset) at the step of 0.05 s: the
    # frame of 0.047 s
    tv, view = ecu_view(frames, 0.01, db)
    assert np.array_equal(tv, t)
    assert view["P_f_m"][k] == brake[47]
    # aligned: the instant 0.03 s, 3 ms after the frame of 0.027 s and 17 ms before that of 0.047 s
    _, aligned = ecu_view(frames, 0.01, db, align=bus_align(db))
    assert aligned["P_f_m"][k] == pytest.approx(brake[27] + 0.15 * (brake[47] - brake[27]))
    with pytest.raises(ValueError, match="step must be positive"):
        step_times(frames, 0.0)
    with pytest.raises(ValueError, match="align must be >= 0"):
        ecu_view(frames, 0.01, db, align=-0.01)
    assert step_times([], 0.01).size == 0 and step_times([Frame(1.0, 128, bytes(8))], 0.01).size == 0


def test_alignment_rules_mirror_the_ecu() -> None:
    """The cases of tests/fw/test_fdi_ecu.c test_time_alignment on one 10 ms message (timeout 30 ms): a ramp
    interpolated at T_k - 20 ms, the oldest kept frame before the instant is reached, across a 70 ms gap the
    newer frame once it has arrived (the last frame before it until then)."""
    times = np.asarray([1, 11, 21, 31, 41, 111, 121], dtype=np.int64) * 1000
    values = times * 1e-6  # 1 m/s per s
    steps = np.asarray([10, 30, 50, 60, 110, 120, 130], dtype=np.int64) * 1000
    got = _at_instants(times, values, steps, steps - 20000, 30000)
    # T=10: all after s=-10 -> oldest (1); 30: s=10 between 1 and 11; 50: s=30 between 21 and 31; 60: s=40;
    # 110: s=90 in the gap, 111 not yet seen -> 41; 120: s=100 in the gap, 111 seen -> 111; 130: s=110, still
    # between 41 and 111 -> 111
    assert got == pytest.approx(np.asarray([1, 10, 30, 40, 41, 111, 111]) * 1e-3)
    assert _at_instants(times, values, steps, steps, 30000) == pytest.approx(  # align 0: hold
        np.asarray([1, 21, 41, 41, 41, 111, 121]) * 1e-3)


@pytest.fixture(scope="module")
def faulty_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("log") / "drive.blf"
    sim = simulate(load_scenario("cornering"), [FaultSpec("f10", 12.0, -120.0)], duration=18.0, seed=31)
    write_log(build_frames(sim, t0=100.0), out)
    return out


def test_offline_residuals_equal_the_ecu(repo: Path, faulty_log: Path, tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    table = tmp_path / "r.csv"
    code = main(["residuals", str(repo / MODEL), "--thresholds", str(repo / THRESHOLDS), "--log", str(faulty_log),
                 "--csv", str(table), "--plot", str(tmp_path / "r.png"), "--compare-ecu"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "agree: largest deviation" in out
    with table.open(encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    names = rows[0][1:]
    assert rows[0][0] == "t_s" and names and all(n.startswith("MSO") for n in names)
    assert len(rows) - 1 == 1799  # steps of the 18 s log: 10 ms from its first frame, while frames follow
    # a test sensitive to f10 (a wheel-1 current fault) alarms after its onset, and none before it
    alarms = [float(m.group(1)) for m in re.finditer(r"^MSO\S+ .* ([0-9.]+) s$", out, re.MULTILINE)]
    t_first = read_log(faulty_log)[0].timestamp  # the fault starts 12 s after the first frame
    assert alarms and min(alarms) >= t_first + 12.0, out
    assert (tmp_path / "r.png").stat().st_size > 10_000


def test_aligned_offline_residuals_equal_the_aligned_ecu(repo: Path, faulty_log: Path,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    """With the signals of one instant (--align, the ECU's align_us) the offline view and the C core agree too."""
    code = main(["residuals", str(repo / MODEL), "--thresholds", str(repo / THRESHOLDS), "--log", str(faulty_log),
                 "--align", str(bus_align()), "--compare-ecu"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "agree: largest deviation" in out
    assert main(["residuals", str(repo / MODEL), "--thresholds", str(repo / THRESHOLDS), "--log",
                 str(faulty_log), "--align", "-0.01"]) == 1
    assert "--align -0.01 is not a time >= 0" in capsys.readouterr().err
    assert main(["residuals", str(repo / MODEL), "--thresholds", str(repo / THRESHOLDS), "--log",
                 str(faulty_log), "--align", "0.05", "--compare-ecu"]) == 1
    assert "the ECU core refuses --align 0.05: a message's kept frames do not reach back that far (0.02 s" in (
        capsys.readouterr().err)


def test_bad_logs_are_refused_with_the_reason(repo: Path, faulty_log: Path, tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    frames = read_log(faulty_log)
    no_brake = tmp_path / "no_brake.log"
    write_log([f for f in frames if f.frame_id != 272], no_brake)
    args = ["residuals", str(repo / MODEL), "--thresholds", str(repo / THRESHOLDS), "--log"]
    assert main([*args, str(no_brake)]) == 1
    err = capsys.readouterr().err
    assert "P_f_m" in err or "P_r_m" in err, err
    empty = tmp_path / "empty.log"
    empty.write_text("", encoding="utf-8")
    assert main([*args, str(empty)]) == 1
    assert "0 frame(s)" in capsys.readouterr().err
    bad = tmp_path / "drive.xyz"
    bad.write_text("x", encoding="utf-8")
    assert main([*args, str(bad)]) == 1
    assert "cannot read" in capsys.readouterr().err
