"""The on-line offset estimator (fdi_diag.h "On-line offset estimation", fdi_est.h) on the C diagnoser of the ROMO
table, on a truth-plant vehicle the model does not describe: a 5 % grade (the unknown input g_x). The longitudinal
inertial test MSO1 (a_x against d vx / dt) sees it as an offset g sin(theta) ~ 0.49 m/s^2 that its fixed gate alarms
on (tests/host/test_adaptive_threshold.py). With MSO1's offset estimated, the test keeps its fixed gate, stays quiet,
and an accelerometer offset f1 at its required size (0.5 m/s^2, host_tools/scenarios/fault_sizes.toml) is detected
within 0.5 s: the estimate freezes from the first alarm on, so the fault is not absorbed. The adaptive threshold
would have to widen MSO1's gate by its whole spread (0.93 m/s^2) and could not see f1 at that size.

The drive is the slalom, at nearly constant speed. In the straight drive's acceleration phases the truth plant's
body pitches and its accelerometer sees part of gravity in proportion to a_x (MSO1 ~ 0.031 a_x on the nominal
vehicle), which the model does not declare and an offset estimator cannot follow (README "Robust diagnosis")."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np
import pytest
from numpy.typing import NDArray

from fdi_host.can.dbc import RomoDatabase
from fdi_host.can.traffic import build_frames
from fdi_host.ecu.bindings import Ecu, EcuResult
from fdi_host.ecu.offline import replay
from fdi_host.sim.faults import FaultSpec
from fdi_host.sim.scenario import load_scenario
from fdi_host.sim.truth_sim import faulty_truth_drive, simulate_truth
from fdi_host.sim.vehicle_envelope import NOMINAL
from fdi_host.sim.vehicle_sim import faulty_drive, simulate

GRADE = 0.05
SEED = 9102  # a noise seed of no fleet (fleet_plan: calibration and evaluation seeds lie elsewhere)
F1_REQUIRED = 0.5  # m/s^2, fault_sizes.toml


def _mso1(results: Sequence[EcuResult], what: str) -> NDArray[Any]:
    k = [n.split(":")[0] for n in results[0].test_names].index("MSO1")
    return np.array([getattr(r, what)[k] for r in results])


def test_the_estimator_takes_the_grade_and_still_sees_an_accelerometer_offset_at_its_required_size() -> None:
    vehicle = dataclasses.replace(NOMINAL, name="grade 5 %", grade=GRADE)
    base = simulate_truth(load_scenario("slalom"), [], vehicle=vehicle, seed=SEED)
    db = RomoDatabase()
    est = {"estimate": "MSO1", "estimate_tau": 10.0}
    quiet = replay("romo", build_frames(base, db), **est)
    status = _mso1(quiet, "test_status")
    assert (status != "not_evaluable").mean() > 0.6
    assert not (status == "alarm").any()
    # the estimate: the grade's share of gravity (plus the vehicle's accelerometer bias, 0 on the nominal vehicle)
    offset = _mso1(quiet, "offsets")[status != "not_evaluable"]
    assert abs(float(np.median(np.abs(offset))) - 9.81 * np.sin(np.arctan(GRADE))) < 0.1
    # its residual, with the estimate removed: centred, at the fixed gate (no spread added)
    assert abs(float(np.median(_mso1(quiet, "residuals")[status != "not_evaluable"]))) < 0.05
    assert not _mso1(quiet, "spreads").any()
    # f1 at its required size: detected within 0.5 s, the estimate frozen from the first alarm on
    onset = 10.0
    faulty = replay("romo", build_frames(faulty_truth_drive(base, FaultSpec("f1", onset, F1_REQUIRED)), db), **est)
    t = np.array([x.t_us for x in faulty]) * 1e-6
    st = _mso1(faulty, "test_status")
    alarmed = np.flatnonzero((t > onset) & (st == "alarm"))
    assert alarmed.size and t[alarmed[0]] - onset < 0.5
    off = _mso1(faulty, "offsets")
    before = off[np.flatnonzero(t <= onset)[-1]]
    open_episode = np.array([x.accused_mask != 0 for x in faulty])
    held = open_episode & (np.arange(len(t)) >= alarmed[0])
    assert held.sum() > 50
    assert np.all(off[held] == off[alarmed[0]])
    assert abs(float(off[alarmed[0]] - before)) < 0.02 * F1_REQUIRED


def test_the_estimator_costs_no_detection_delay_on_the_model_plant() -> None:
    """The suite's model-plant case (fdi_host.quality.suite: the ECU starts 5 s before the onset, at 55 % of the
    drive): f1 at its required size is detected within the suite's 300 ms with MSO1 and MSO2 estimated, no later than
    at the fixed gates. The estimator's start-up (1 s after the filters' warm-up) ends before the onset, so the
    step meets the slow gain dt / tau, not the start-up's 1 / n (which absorbed a fifth of it and delayed the alarm
    past 1 s when the start-up lasted as long as the warm-up)."""
    scenario = load_scenario("straight")
    onset = 0.55 * scenario.duration
    drive = faulty_drive(simulate(scenario, [], seed=SEED), FaultSpec("f1", onset, F1_REQUIRED))
    frames = [f for f in build_frames(drive, RomoDatabase()) if f.timestamp >= onset - 5.0]
    delays = {}
    for label, est in (("fixed", {}), ("estimated", {"estimate": "MSO1,MSO2"})):
        res = replay("romo", frames, **est)
        t = np.array([x.t_us for x in res]) * 1e-6
        detected = np.flatnonzero((t > onset) & np.array([x.detected for x in res]))
        assert detected.size, label
        delays[label] = t[detected[0]] - onset
        if est:
            status = _mso1(res, "test_status")
            assert status[np.flatnonzero(t <= onset)[-1]] != "not_evaluable"  # the start-up is over at the onset
    assert delays["estimated"] <= 0.3
    assert delays["estimated"] <= delays["fixed"] + 0.03


def test_estimate_settings_are_checked() -> None:
    with pytest.raises(ValueError, match="not a test of the table"):
        Ecu("romo", estimate="MSO999999")
    with pytest.raises(ValueError, match="beyond the table"):
        Ecu("romo", estimate=1 << 31)
    with pytest.raises(ValueError, match=r"outside 0\.\.65535"):
        Ecu("romo", estimate="MSO1", estimate_startup=-1)
    with pytest.raises(RuntimeError):
        Ecu("romo", estimate="MSO1", estimate_tau=1.0, estimate_startup=500)  # longer than tau: init refuses
    assert Ecu("romo").config.diag.estimate_startup == 100  # 1 s at the 10 ms step
    mask = Ecu("romo", estimate="MSO1").config.diag.estimate
    assert mask and mask == Ecu("romo", estimate=[1]).config.diag.estimate


def test_what_the_estimator_cannot_take_the_body_pitch_under_acceleration() -> None:
    """A limitation, measured so that it cannot drift unseen: on the nominal truth vehicle on a flat road, the
    straight drive's acceleration phases pitch the body, and MSO1's residual follows the measured a_x with a gain
    of about 0.03 (the sine of the pitch angle per m/s^2), which the model does not declare. An offset
    estimator follows constants, not a_x, so in these phases the estimated test still sees it at full size."""
    base = simulate_truth(load_scenario("straight"), [], vehicle=NOMINAL, seed=SEED)
    out = replay("romo", build_frames(base, RomoDatabase()))
    status = _mso1(out, "test_status")
    t = np.array([x.t_us for x in out]) * 1e-6
    ax = np.interp(t, base.t, base.clean["ax_m"])
    ok = status != "not_evaluable"
    r = _mso1(out, "residuals")[ok]
    gain, offset = np.polyfit(ax[ok], r, 1)
    assert np.ptp(ax[ok]) > 2.0  # m/s^2: the drive accelerates and brakes
    assert 0.02 < gain < 0.045
    assert abs(offset) < 0.05
