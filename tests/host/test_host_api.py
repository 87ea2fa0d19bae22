"""The host tools' notebook API (issue 47): `fdi_host.simulate`, `diagnose`, `diagnose_log` and the step-by-step
`Diagnosis`: its arrays are the ECU's per-step results (`fdi_host.ecu.offline.replay` on the same time base) and
those of `EcuSession` (what ``fdi-ecu`` and ``fdi-replay`` record); a drive and its log are diagnosed alike; short
repr, labelled HTML and DataFrame, ``ax=`` on every plot; the quality suite's tables as DataFrames."""

from __future__ import annotations

import inspect
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import fdi_host
from fdi_host import api
from fdi_host.can.frame import Frame
from fdi_host.diagnosis import STATUS, Diagnosis
from fdi_host.ecu.bindings import bus_info, table_info
from fdi_host.ecu.offline import replay
from fdi_host.ecu.session import ORIGIN_LEAD, EcuSession
from fdi_host.quality.suite import CaseResult, FaultFreeResult, SuiteConfig, SuiteResult
from fdi_host.quality.tables import cases_frame, fault_free_frame, goals_frame, summary_frame
from fdi_host.sim.faults import FaultSpec
from fdi_host.sim.vehicle_envelope import NOMINAL, draw_vehicle

REPO = Path(__file__).resolve().parents[2]
ONSET = 5.0  # after the ECU's warm-up and its estimators' start-up (4.2 s)


@pytest.fixture(scope="module")
def drive() -> api.Drive:
    """A short straight drive with the v_x sensor fault f4 at 5 s (the model plant, seeded noise)."""
    return fdi_host.simulate("straight", faults=[f"f4@{ONSET}s:0.5"], duration=8.0)


@pytest.fixture(scope="module")
def diagnosis(drive: api.Drive) -> Diagnosis:
    return fdi_host.diagnose(drive)


def test_import_is_light_and_the_api_loads_on_first_use() -> None:
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    env["PYTHONPATH"] = os.pathsep.join([str(REPO / "analysis"), str(REPO / "host_tools")])
    code = ("import sys, fdi_host; before = sorted(m for m in ('numpy', 'fdi_host.api', 'fdi_host.ecu.bindings') "
            "if m in sys.modules); fdi_host.diagnose; print(before, 'fdi_host.api' in sys.modules, "
            "sorted(fdi_host.__all__))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
    assert out.stdout.strip() == "[] True ['Diagnosis', 'Drive', 'diagnose', 'diagnose_log', 'simulate']"
    with pytest.raises(AttributeError):
        _ = fdi_host.no_such_name


def test_the_arrays_are_the_ecus_results_step_by_step(drive: api.Drive, diagnosis: Diagnosis) -> None:
    """The reference: `offline.replay` (rx then poll per frame, the result after every diagnosis frame) on the
    frames shifted to the ECU's clock, behind a frame of an ID the bus does not know at the origin (the C core starts
    its step schedule at its first call)."""
    known = {i for _, i in bus_info("romo").messages}
    stranger = next(i for i in range(0x7F0, 0x800) if i not in known)
    frames = [Frame(0.0, stranger, b""), *(Frame(f.timestamp + ORIGIN_LEAD, f.frame_id, f.data) for f in drive.frames)]
    ref = replay("romo", frames)
    d = diagnosis
    assert len(d) == len(ref) > 500
    assert np.array_equal(d.detected, [r.detected for r in ref])
    assert np.array_equal(d.isolated, [r.isolated for r in ref])
    assert np.array_equal(d.candidates, [r.candidates for r in ref])
    assert np.array_equal(d.alarms, [r.alarm_mask for r in ref])
    assert np.array_equal(d.time, [r.t_us * 1e-6 for r in ref])
    assert np.array_equal(d.residuals, [r.residuals for r in ref])
    assert np.array_equal(d.ratios, [r.ratios for r in ref])
    assert [tuple(STATUS[k] for k in row) for row in d.status] == [r.test_status for r in ref]
    assert d.tests == tuple(n.split(":")[0] for n in ref[0].test_names)
    assert np.array_equal(d.alarm_matrix(), d.status == STATUS.index("alarm"))
    for k in (0, len(d) // 2, -1):
        assert d.candidate_names(k) == tuple(ref[k].candidate_labels(table_info("romo")))
    # the fault is found: detected after the onset and never before, f4 among the candidates
    first = d.first_detection
    assert first is not None and ONSET < first < ONSET + 0.5
    assert not d.detected[d.time < ONSET].any()
    assert any("f4" in c for _, _, c in d.episodes())


def test_the_time_base_is_that_of_fdi_ecu_and_fdi_replay(drive: api.Drive, diagnosis: Diagnosis) -> None:
    session = EcuSession("romo")
    session.feed_many((f.frame_id, f.data, f.timestamp) for f in drive.frames)
    steps = session.steps
    d = diagnosis
    assert drive.frames[0].timestamp == 0.0  # so the drive's t = 0 and the first frame agree
    assert len(steps) == len(d)
    assert [s.alarm_mask for s in steps] == d.alarms.tolist()
    assert [s.candidates for s in steps] == d.candidates.tolist()
    assert np.array_equal([s.residuals for s in steps], d.residuals)
    assert np.array_equal([s.ratios for s in steps], d.ratios)
    lag = np.array([s.t for s in steps]) - d.time  # the frame that triggered the step came after its boundary
    assert (lag > 0).all() and (lag < table_info("romo").dt).all()
    frames = fdi_host.diagnose(drive.frames)  # frames: t = 0 at the first frame
    assert np.array_equal(frames.candidates, d.candidates) and np.array_equal(frames.time, d.time)


def test_a_drive_and_its_log_are_diagnosed_alike(drive: api.Drive, diagnosis: Diagnosis, tmp_path: Path) -> None:
    path = drive.write_log(tmp_path / "drive.log")
    for d in (fdi_host.diagnose_log(path), fdi_host.diagnose(str(path))):
        assert d.source == str(path)
        for field in ("time", "detected", "isolated", "candidates", "alarms", "status", "residuals", "ratios"):
            assert np.array_equal(getattr(d, field), getattr(diagnosis, field)), field


def test_views_are_short_and_labelled(diagnosis: Diagnosis) -> None:
    d = diagnosis
    text = repr(d)
    assert len(text) < 300 and "\n" not in text and f"{len(d)} steps" in text and "detected" in text
    page = d._repr_html_()
    assert all(f'<th style="text-align: left">{t}</th>' in page for t in d.tests)
    assert "f4" in page and "candidates" in page
    df = d.to_dataframe()
    assert df.index.name == "time [s]" and np.array_equal(df.index.to_numpy(), d.time)
    assert list(df.columns.names) == ["quantity", "name"]
    assert list(df["ratio"].columns) == list(df["residual"].columns) == list(df["status"].columns) == list(d.tests)
    assert list(df["candidate"].columns) == list(d.faults)
    assert np.array_equal(df["ratio"].to_numpy(), d.ratios)
    assert np.array_equal(df["candidate"].to_numpy(), d.candidate_matrix())
    assert np.array_equal(df["diagnosis"]["detected"].to_numpy(), d.detected)
    k = int(np.flatnonzero(d.candidates)[0])
    assert df["diagnosis"]["candidates"].iloc[k] == ", ".join(d.candidate_names(k))
    assert set(df["status"].iloc[k]) <= set(STATUS)


def test_plots_take_ax(drive: api.Drive, diagnosis: Diagnosis) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    called = []
    for obj in (diagnosis, drive):
        for name, fn in inspect.getmembers(type(obj), inspect.isfunction):
            if not name.startswith("plot"):
                continue
            assert "ax" in inspect.signature(fn).parameters, f"{type(obj).__name__}.{name} has no ax="
            fig, ax = plt.subplots()
            assert getattr(obj, name)(ax=ax) is fig and fig.axes == [ax]
            assert ax.lines or ax.images, f"{type(obj).__name__}.{name} drew nothing"
            called.append(name)
            plt.close(fig)
    assert sorted(called) == ["plot", "plot", "plot_ratios"]
    fig = diagnosis.plot(faults=["f4", "f1"])
    assert [t.get_text() for t in fig.axes[0].get_yticklabels()] == ["detected", "f4", "f1"]
    with pytest.raises(ValueError, match="f99"):
        diagnosis.plot_ratios(tests=["f99"])
    plt.close("all")


def test_simulate_reads_faults_and_vehicles(drive: api.Drive) -> None:
    assert drive.faults == (FaultSpec("f4", ONSET, 0.5),)
    assert repr(drive).startswith("Drive(straight, model plant: 8.0 s") and len(repr(drive)) < 300
    assert "<th" in drive._repr_html_() and f"f4@{ONSET:g}s:0.5" in drive._repr_html_()
    own = fdi_host.simulate("straight", duration=0.5)
    assert own.faults == own.result.scenario.faults  # None: the scenario's own faults
    assert fdi_host.simulate("straight", faults=[], duration=0.5).faults == ()
    assert fdi_host.simulate("straight", faults=FaultSpec("f1", 0.1, 1.0), duration=0.5).faults[0].fault == "f1"
    assert api._vehicle(None) is None and api._vehicle("nominal") is NOMINAL and api._vehicle(NOMINAL) is NOMINAL
    assert api._vehicle(7) == draw_vehicle(7)
    with pytest.raises(ValueError, match="vehicle"):
        api._vehicle("heavy")
    base = fdi_host.simulate("straight", faults=[], duration=8.0)
    added = base.with_fault(f"f4@{ONSET}s:0.5")
    assert added.faults == drive.faults
    assert np.allclose(added.result.measured["vx_m"], drive.result.measured["vx_m"])
    df = drive.to_dataframe()
    assert df.index.name == "time [s]" and set(df.columns) == set(drive.result.measured) and len(df) == drive.t.size
    with pytest.raises(ValueError, match="which"):
        drive.to_dataframe("noisy")


def test_tables_without_pandas_say_how_to_get_it(diagnosis: Diagnosis, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(ImportError, match=r"romo-fdi\[notebook\]"):
        diagnosis.to_dataframe()


def _case(fault: str, scenario: str, seed: int, outcome: str, delay: float | None) -> CaseResult:
    return CaseResult(fault=fault, scenario=scenario, seed=seed, shape="step", multiplier=1.0, magnitude=0.5,
                      onset=10.0, t_ref=10.0, detected=delay is not None, delay_s=delay, outcome=outcome,
                      isolation_delay_s=0.2 if outcome == "exact" else None, exact_share=0.9,
                      final_candidates=(fault,) if outcome == "exact" else (), expected_class=(fault, "f14"),
                      pre_onset_detections=0)


def test_quality_tables_are_labelled_by_fault_and_scenario() -> None:
    cases = [_case("f4", "straight", 1, "exact", 0.1), _case("f4", "slalom", 1, "missed", None),
             _case("f10", "straight", 1, "exact", 0.25)]
    result = SuiteResult(SuiteConfig(table="romo"), table_info("romo"), {"f4": 0.5, "f10": 80.0}, cases,
                         [FaultFreeResult("straight", 1, 60.0, 0, 0, 0, 6000)])
    summary = summary_frame(result)
    assert list(summary.index) == ["f4", "f10"] and summary.index.name == "fault"
    assert summary.loc["f4", "cases"] == 2 and summary.loc["f4", "detected"] == 1
    assert summary.loc["f10", "expected_class"] == "f10, f14" and summary.loc["f10", "size"] == 80.0
    table = cases_frame(result)
    assert list(table.index.names) == ["fault", "scenario", "seed", "shape", "multiplier"]
    assert table.loc[("f4", "slalom", 1, "step", 1.0), "outcome"] == "missed"
    assert bool(table.loc[("f4", "straight", 1, "step", 1.0), "detected_in_time"])
    assert table.loc[("f10", "straight", 1, "step", 1.0), "final_candidates"] == "f10"
    goals = goals_frame(result)
    assert list(goals.index) == ["straight", "slalom"] and goals.loc["slalom", "not_detected_in_time"] == "f4, f10"
    free = fault_free_frame(result)
    assert list(free.index) == [("straight", 1)] and free.loc[("straight", 1), "steps"] == 6000
