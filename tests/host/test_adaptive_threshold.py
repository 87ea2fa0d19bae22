"""The adaptive threshold (fdi_diag.h "Adaptive thresholds", fdi_eval.h) on the C diagnoser of the ROMO table, alone
(no on-line estimation: estimate 0), on a truth-plant vehicle the model does not describe: a 5 % grade (inside the
declared +-8 %, the unknown input g_x). The longitudinal inertial test MSO1 (a_x against d vx / dt) sees the grade as
g sin(theta) ~ 0.49 m/s^2: at its fixed gate it alarms through the drive; with the adaptive threshold over the whole
declared envelope (its spread: the grade's and the x-bias's share as one offset, the tilt's and the yaw-rate bias's,
computed by the generated step at every step) it stays quiet, and an accelerometer offset beyond that spread is still
detected by it. The residuals are the same either way: only the evaluation changes. (What the whole envelope costs,
and what the estimators win back: tests/host/test_offset_estimation.py.)"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fdi_host.can.dbc import CanDatabase
from fdi_host.can.traffic import build_frames
from fdi_host.ecu.bindings import EcuResult
from fdi_host.ecu.offline import replay
from fdi_host.sim.faults import FaultSpec
from fdi_host.sim.scenario import load_scenario
from fdi_host.sim.truth_sim import faulty_truth_drive, simulate_truth
from fdi_host.sim.vehicle_envelope import NOMINAL

GRADE = 0.05
SEED = 9101  # a noise seed of no fleet (fleet_plan: calibration and evaluation seeds lie elsewhere)


def _mso1(results: Sequence[EcuResult], what: str) -> NDArray[Any]:
    """Test MSO1's field `what` (an EcuResult tuple per test) at every step."""
    k = [n.split(":")[0] for n in results[0].test_names].index("MSO1")
    return np.array([getattr(r, what)[k] for r in results])


def test_a_grade_alarms_at_the_fixed_gate_and_not_with_the_adaptive_threshold() -> None:
    vehicle = dataclasses.replace(NOMINAL, name="grade 5 %", grade=GRADE)
    base = simulate_truth(load_scenario("straight"), [], vehicle=vehicle, seed=SEED)
    db = CanDatabase()
    frames = build_frames(base, db)
    fixed = replay("romo", frames, adaptive=False, estimate=0)  # the fixed gates
    adaptive = replay("romo", frames, adaptive=True, estimate=0)
    status_fixed, status_adaptive = _mso1(fixed, "test_status"), _mso1(adaptive, "test_status")
    evaluable = status_adaptive != "not_evaluable"
    assert evaluable.mean() > 0.8
    assert np.array_equal(_mso1(fixed, "residuals"), _mso1(adaptive, "residuals"))
    # the grade: the fixed gate alarms most of the drive, the adaptive threshold never
    assert (status_fixed == "alarm").mean() > 0.5
    assert not (status_adaptive == "alarm").any()
    # its spread: at least the constant share (b_ax 0.15 + g_x 0.7824 m/s^2, times the residual's 1 / (1 + c_ax)),
    # none at the fixed gate
    spread = _mso1(adaptive, "spreads")[evaluable]
    assert float(spread.min()) >= 0.9324 / 1.03 - 1e-4 and float(spread.max()) < 1.4
    assert not _mso1(fixed, "spreads").any()
    # the residual sits at the grade's share of gravity: what the spread allows for, with room
    r = _mso1(adaptive, "residuals")[evaluable]
    assert abs(float(np.median(np.abs(r))) - 9.81 * np.sin(np.arctan(GRADE))) < 0.1
    # an accelerometer offset beyond the spread: still detected by the inertial test
    onset = 10.0
    spec = FaultSpec("f1", onset, 2.0)
    faulty = replay("romo", build_frames(faulty_truth_drive(base, spec), db), adaptive=True, estimate=0)
    t = np.array([x.t_us for x in faulty]) * 1e-6
    after = (t > onset) & (t < onset + 0.5)
    assert (_mso1(faulty, "test_status")[after] == "alarm").any()
