"""The diagnosis quality suite (fdi_host.quality.suite): quick mode end to end through the ECU core, the case
evaluation on hand-made result sequences, the sensor-fault shortcut against a full simulation, the fault-size
file's errors."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from fdi_host.ecu.bindings import EcuResult
from fdi_host.quality.cli import main, quick_config
from fdi_host.quality.report import markdown, to_dict
from fdi_host.quality.suite import (
    DEFAULT_SIZES,
    QualityError,
    SuiteConfig,
    evaluate_case,
    load_fault_sizes,
    run_suite,
    scenario_goals,
    summary_rows,
)
from fdi_host.sim.faults import FaultSpec
from fdi_host.sim.scenario import load_scenario
from fdi_host.sim.vehicle_sim import faulty_drive, simulate


def result(t: float, candidates: int = 0, alarm: int = 0, class_mask: int | None = None) -> EcuResult:
    """A step of the ECU; every fault its own class unless `class_mask` gives the class of the candidates."""
    iso = candidates != 0 and (candidates in (1, 2, 4, 8, 16) or class_mask is not None)
    return EcuResult(
        step=int(t * 100), t_us=round(t * 1e6), status=3 if iso else (2 if alarm else 1), validity=0x7FFFF,
        alarm_mask=alarm, evaluable_mask=0xF, accused_mask=alarm, candidates=candidates,
        class_mask=candidates if class_mask is None else class_mask,
        n_classes=1 if iso else (0 if candidates == 0 else 2), detected=alarm != 0, isolated=iso,
        iso_class=0, test_status=("ok",) * 4, residuals=(0.0,) * 4, ratios=(0.0,) * 4, test_names=("",) * 4,
    )


def test_evaluate_case_outcomes() -> None:
    spec = FaultSpec("f4", 5.0, 0.5)
    quiet = [result(4.0 + 0.01 * k) for k in range(100)]
    # detected 120 ms after the onset, isolated as f4 from 300 ms on: 180 ms after the detection
    seq = quiet + [result(5.0 + 0.01 * k, *((8, 7) if k >= 30 else ((0, 2) if k >= 12 else (0, 0))))
                   for k in range(100)]
    det, delay, outcome, iso_delay, share, final, pre = evaluate_case(seq, spec, 5.0, 8)
    assert det and delay == pytest.approx(0.12) and outcome == "exact" and iso_delay == pytest.approx(0.18)
    assert share == pytest.approx(70 / 88) and final == ("f4",) and pre == 0
    # one step isolating f5 makes it "wrong", whatever else happens
    wrong = [*seq[:150], result(5.5, 16, 3), *seq[151:]]
    assert evaluate_case(wrong, spec, 5.0, 8)[2] == "wrong"
    # never detected: missed; a detection before the onset is counted
    missed = [result(3.9, 0, 1), *quiet, *(result(5.0 + 0.01 * k) for k in range(50))]
    det, delay, outcome, _, _, _, pre = evaluate_case(missed, spec, 5.0, 8)
    assert not det and delay is None and outcome == "missed" and pre == 1
    # detected, never a single class
    unexplained = quiet + [result(5.0 + 0.01 * k, 0, 2) for k in range(50)]
    assert evaluate_case(unexplained, spec, 5.0, 8)[2] == "not isolated"


def test_part_of_the_class_is_exact_only_with_the_fault() -> None:
    """f4 in a class {f4, f5} (bits 8 | 16): candidates {f4} isolate it exactly (the library's `isolated`,
    class_mask the class); {f5} alone names the right class but exonerates the fault: wrong."""
    spec = FaultSpec("f4", 5.0, 0.5)
    quiet = [result(4.0 + 0.01 * k) for k in range(100)]
    part = quiet + [result(5.0 + 0.01 * k, *((8, 3, 24) if k >= 20 else (0, 0))) for k in range(100)]
    det, delay, outcome, iso_delay, share, final, _ = evaluate_case(part, spec, 5.0, 24)
    assert det and delay == pytest.approx(0.2) and outcome == "exact" and iso_delay == pytest.approx(0.0)
    assert share == pytest.approx(1.0) and final == ("f4",)
    other = quiet + [result(5.0 + 0.01 * k, *((16, 3, 24) if k >= 20 else (0, 0))) for k in range(100)]
    assert evaluate_case(other, spec, 5.0, 24)[2] == "wrong"


def test_sensor_fault_shortcut_equals_full_simulation() -> None:
    scen = load_scenario("cornering")
    base = simulate(scen, [], seed=5, duration=3.0)
    for spec in (FaultSpec("f4", 1.0, 0.5), FaultSpec("f23", 1.5, 2.0, shape="ramp", ramp=1.0)):
        fast = faulty_drive(base, spec)
        full = simulate(scen, [spec], seed=5, duration=3.0)
        assert set(fast.measured) == set(full.measured)
        for name in full.measured:
            np.testing.assert_allclose(fast.measured[name], full.measured[name], rtol=0, atol=1e-9, err_msg=name)
        np.testing.assert_array_equal(fast.fault_values, full.fault_values)


def test_fault_sizes_file(tmp_path: Path) -> None:
    """The required sizes of the committed file are the issue's engineering requirement (Table I units); bad
    files are refused naming the file and the entry."""
    sizes = load_fault_sizes(DEFAULT_SIZES)
    required = {"f1": 0.5, "f2": 0.5, "f3": 0.05, "f4": 0.6, "f5": 0.6, **{f"f{k}": 0.06 for k in range(6, 10)},
                **{f"f{k}": 150.0 for k in range(10, 18)}, **{f"f{k}": 600.0 for k in range(18, 22)},
                **{f"f{k}": 3.0 for k in range(22, 26)}}
    assert sizes == required
    for text, needle in (("[requirement]\nf99 = 1\n", "unknown fault 'f99'"),
                         ("[requirement]\nf1 = -1\n", "size of f1 must be a positive number"),
                         ("[requirement]\nf1 = true\n", "size of f1 must be a positive number"),
                         ("f1 = 1\n", "expected a [requirement] table"), ("[requirement\n", "s.toml")):
        p = tmp_path / "s.toml"
        p.write_text(text, encoding="utf-8")
        with pytest.raises(QualityError, match=needle.replace("[", r"\[")):
            load_fault_sizes(p)
    with pytest.raises(QualityError, match="unknown fault shape"):
        SuiteConfig(shapes=("sine",))
    with pytest.raises(QualityError, match="at least one noise seed"):
        SuiteConfig(seeds=())


@pytest.mark.parametrize("table", ["kin", "romo"])
def test_quick_suite(table: str, tmp_path: Path) -> None:
    """Quick mode (CI): every fault of the table on the cornering drive (a noise seed no calibration used), a step
    at its required size, plus a fault-free drive. Never a wrong class, no false detection; the reports hold every
    case. The kinematic table detects every fault and, by reaction sizes after a 3 s window, isolates exactly but
    later. The generated ROMO table, calibrated on the truth-plant fleet with its estimators, detects the
    motion-sensor faults f1-f5 and isolates f1 within 1 s (with the model plant's sigmas it detected all 25 and
    isolated 20: the price of robustness, measured in docs/results.md)."""
    res = run_suite(quick_config(table))
    rows = {r["fault"]: r for r in summary_rows(res)}
    n = 5 if table == "kin" else 25
    assert list(rows) == [f"f{k}" for k in range(1, n + 1)]
    detected = {f for f, r in rows.items() if r["detected"] == r["cases"]}
    if table == "romo":
        # calibrated on the truth-plant fleet (issue 45), its sigmas hold what the model does not know of a real
        # vehicle: the motion-sensor faults stand out of them, the wheel-level faults at their required sizes do not
        # (docs/robust_diagnosis.md, docs/results.md)
        assert {"f1", "f2", "f3", "f4", "f5"} <= detected, rows
    else:
        assert detected == set(rows), rows
    assert sum(r["isolation_wrong"] for r in rows.values()) == 0
    assert sum(c.pre_onset_detections for c in res.cases) == 0
    assert res.fault_free and all(d.detection_events == 0 for d in res.fault_free)
    isolated = sum(c.isolated_in_time for c in res.cases)
    goals = scenario_goals(res)
    assert [g["scenario"] for g in goals] == ["cornering"] and goals[0]["isolated_in_time"] == isolated
    if table == "romo":
        assert rows["f1"]["isolation_exact"] == 1, rows["f1"]
    else:  # the kinematic table exonerates by reaction sizes after their 3 s window: exact, but not within 1 s
        assert sum(c.outcome == "exact" for c in res.cases) >= 3
    d = to_dict(res)
    back = json.loads(json.dumps(d))  # JSON-serialisable (tuples come back as lists)
    assert len(back["cases"]) == n and back["summary"] == d["summary"] and back["fault_free"]["drives"] >= 1
    md = markdown(res)
    assert "| f4 |" in md and "**NOT met** (under 30 minutes driven)." in md and "| cornering |" in md
    assert "quick mode" not in md  # the report says why the goal is not met, not how the run was started
    assert dataclasses.asdict(res.cases[0])["fault"] == "f1"
    # a study with other ECU settings says so in both reports (fdi-quality --ecu)
    assert "ECU settings other than the defaults" not in md
    study = dataclasses.replace(res, config=dataclasses.replace(res.config, ecu=(("noise_allowance", 2),)))
    assert "ECU settings other than the defaults: noise_allowance = 2." in markdown(study)
    assert json.loads(json.dumps(to_dict(study)))["config"]["ecu"] == [["noise_allowance", 2]]


def test_cli_errors_and_help(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    with pytest.raises(SystemExit):
        main(["--help"])
    assert "example" in capsys.readouterr().out
    bad = tmp_path / "bad.toml"
    bad.write_text("[requirement]\nf1 = 0\n", encoding="utf-8")
    assert main(["--quick", "--sizes", str(bad)]) == 1
    assert "positive number" in capsys.readouterr().err
