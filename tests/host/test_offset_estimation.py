"""The on-line estimators (fdi_diag.h "On-line estimation", fdi_est.h) on the C diagnoser of the ROMO table, on a
truth-plant vehicle the model does not describe: a 5 % grade (the unknown input g_x) and the body's pitch, which tilts
the accelerometer in proportion to the acceleration (c_ax). The longitudinal inertial test MSO1 (a_x against
d vx / dt) estimates the lumped offset of the grade and the accelerometer's bias and the tilt (the thresholds file's
[estimation], chosen on the calibration fleet). Measured here: the estimates converge to what the truth plant holds,
the test then keeps its tight threshold and stays quiet; an accelerometer offset f1 at its required size
(0.5 m/s^2, host_tools/scenarios/fault_sizes.toml) is detected within 0.5 s, and from its first alarm the estimates
stay frozen bit for bit while the episode is open, so the fault is not absorbed."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import pytest
from numpy.typing import NDArray

from fdi_host.can.dbc import CanDatabase
from fdi_host.can.traffic import build_frames
from fdi_host.ecu.bindings import Ecu, EcuResult, table_info
from fdi_host.ecu.offline import replay
from fdi_host.sim.faults import FaultSpec
from fdi_host.sim.scenario import load_scenario
from fdi_host.sim.truth_sim import faulty_truth_drive, simulate_truth
from fdi_host.sim.vehicle_envelope import NOMINAL
from fdi_host.sim.vehicle_sim import faulty_drive, simulate

GRADE = 0.05
SEED = 9102  # a noise seed of no fleet (fleet_plan: calibration and evaluation seeds lie elsewhere)
F1_REQUIRED = 0.5  # m/s^2, fault_sizes.toml
ONSET = 11.0  # s: 55 % of the slalom, as the fleet suite injects


def _mso1(results: Sequence[EcuResult], what: str) -> NDArray[Any]:
    k = [n.split(":")[0] for n in results[0].test_names].index("MSO1")
    return np.array([getattr(r, what)[k] for r in results])


def test_the_estimates_follow_the_grade_and_the_tilt_and_a_fault_is_not_absorbed() -> None:
    vehicle = dataclasses.replace(NOMINAL, name="grade 5 %", grade=GRADE)
    base = simulate_truth(load_scenario("slalom"), [], vehicle=vehicle, seed=SEED, snapshots=[ONSET])
    db = CanDatabase()
    quiet = replay("romo", build_frames(base, db))  # the default configuration: estimation and adaptive thresholds
    status = _mso1(quiet, "test_status")
    t = np.array([x.t_us for x in quiet]) * 1e-6
    assert (status != "not_evaluable").mean() > 0.6
    assert not (status == "alarm").any()
    est = _mso1(quiet, "estimates")
    assert est.shape[1] >= 2  # the lumped offset (b_ax + g_x) and the tilt (c_ax)
    late = t > 8.0
    # the offset: g sin(grade) (the model's accelerometer is level, c_ax = 0), the nominal vehicle's bias 0
    offset = 9.81 * math.sin(math.atan(GRADE))
    assert abs(float(np.median(est[late, 0])) - offset) < 0.05
    # the tilt: the nominal vehicle pitches by g sin(pitch) ~ 0.031 a_x (tests/analysis/test_uncertainty.py) against
    # the model's none
    assert abs(float(np.median(est[late, 1])) - 0.031) < 0.01
    # what the estimates leave: no trace of the grade, and the pitch's share of the residual's slope against a_x
    # removed (0.045 raw, 0.026 left in the slalom: the rest is the filters' lag behind its fast a_x, not a tilt)
    ev = late & (status != "not_evaluable")
    r = _mso1(quiet, "residuals")[ev]
    raw = r + _mso1(quiet, "offsets")[ev]
    ax = np.interp(t, base.t, base.clean["ax_m"])[ev]
    gain, centre = np.polyfit(ax, r, 1)
    raw_gain, raw_centre = np.polyfit(ax, raw, 1)
    assert abs(raw_centre - offset) < 0.05 and abs(centre) < 0.02
    assert abs(gain) <= abs(raw_gain) - 0.5 * 0.031
    # f1 at its required size: detected within 0.5 s, the estimates frozen from the first alarm on
    faulty = replay("romo", build_frames(faulty_truth_drive(base, FaultSpec("f1", ONSET, F1_REQUIRED)), db))
    tf = np.array([x.t_us for x in faulty]) * 1e-6
    st = _mso1(faulty, "test_status")
    alarmed = np.flatnonzero((tf > ONSET) & (st == "alarm"))
    assert alarmed.size and tf[alarmed[0]] - ONSET < 0.5
    e = _mso1(faulty, "estimates")
    before = e[np.flatnonzero(tf <= ONSET)[-1]]
    held = np.array([x.accused_mask != 0 for x in faulty]) & (np.arange(len(tf)) >= alarmed[0])
    assert held.sum() > 50
    assert np.all(e[held] == e[alarmed[0]])
    # before its test alarmed the estimate took a little of the fault (measured 0.028 of 0.5: the filter's gain times
    # the few steps to the alarm); the rest reaches the evaluator and stays there
    assert abs(float(e[alarmed[0], 0] - before[0])) < 0.1 * F1_REQUIRED


def test_the_estimators_cost_no_detection_on_the_model_plant() -> None:
    """The suite's model-plant case: f1 at its required size, 55 % into the straight drive, replayed from the drive's
    start (fdi_host.quality.suite): detected within the suite's 300 ms with the default configuration."""
    scenario = load_scenario("straight")
    onset = 0.55 * scenario.duration
    drive = faulty_drive(simulate(scenario, [], seed=SEED), FaultSpec("f1", onset, F1_REQUIRED))
    res = replay("romo", build_frames(drive, CanDatabase()))
    t = np.array([x.t_us for x in res]) * 1e-6
    detected = np.flatnonzero((t > onset) & np.array([x.detected for x in res]))
    assert not any(x.detected for x in res[: np.flatnonzero(t <= onset)[-1]])
    assert detected.size and t[detected[0]] - onset <= 0.3


def test_estimate_settings_are_checked() -> None:
    info = table_info("romo")
    assert Ecu("romo").config.diag.estimate == sum(1 << i for i, n in enumerate(info.n_est) if n > 0)
    assert Ecu("romo").config.diag.adaptive
    assert Ecu("romo", estimate="all").config.diag.estimate == Ecu("romo").config.diag.estimate
    with pytest.raises(ValueError, match="not a test of the table"):
        Ecu("romo", estimate="MSO999999")
    with pytest.raises(ValueError, match="beyond the table"):
        Ecu("romo", estimate=1 << 31)
    with pytest.raises(RuntimeError):
        Ecu("romo", estimate_kappa=-1.0)  # init refuses
    with pytest.raises(RuntimeError):
        Ecu("romo", estimate_decorrelation=0.5)
    with pytest.raises(RuntimeError):
        Ecu("romo", reentry_steps=0)
    without = [i for i, n in enumerate(info.n_est) if n == 0]
    if without:  # a test whose generator declares nothing to estimate cannot be asked to
        with pytest.raises(RuntimeError):
            Ecu("romo", estimate=1 << without[0])
