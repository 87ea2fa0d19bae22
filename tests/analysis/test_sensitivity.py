"""Fault sensitivity of the residual generators (fdi_analysis.residuals.sensitivity): the analytic d r / d f
against a hand derivation (tank observer), against central differences of the residual computed with the faults
kept (what the screening uses), and against the residual's actual response to step faults in simulated drives;
the rate gain of a fault seen only through a derivative against the residual of a drifting sensor."""

from __future__ import annotations

import numpy as np
import pytest
from test_residual_observer import MSO, TANK, K, tank_signals

from fdi_analysis.model import Model
from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.causality import synthesize
from fdi_analysis.residuals.evaluate import (
    FilterDesign,
    node_signals,
    observer_run,
    residual,
    sensitivity_estimate,
    sensitivity_series,
)
from fdi_analysis.residuals.generator import OBSERVER_EPS, XHAT, Generator
from fdi_analysis.residuals.observer import ObserverReference, pole
from fdi_analysis.residuals.sensitivity import with_sensitivities
from fdi_analysis.residuals.solvability import Solver
from fdi_host.tuning.drives import drive, observer_reference
from fdi_host.tuning.screening import _sensitivity_fn

# ROMO tests: the wheel-2 spin equation against its tyre law (no observer), and a body force balance with the
# rear-left wheel speed estimated by an observer
MSO7 = ["W2.FL", "W2.dyn", "W2.D", "S1", "S2", "S3", "S4", "S5", "S.omega2"]
MSO351 = ["B2", "K2", "D2", "W1.FL", "W2.FL", "W3.FL", "W4.FL", "W1.FS", "W2.FS", "W3.FS", "W4.FS", "W1.Fy", "W2.Fy",
          "W3.Fy", "W4.Fy", "W3.dyn", "W3.D", "S1", "S3", "S4", "S5", "S.omega1", "S.omega2", "S.omega4"]


@pytest.fixture(scope="module")
def romo(repo) -> Model:  # type: ignore[no-untyped-def]
    return load_model(repo / "analysis/models/romo_grouped.toml")


@pytest.fixture(scope="module")
def cornering() -> dict[str, np.ndarray]:
    return drive("cornering", duration=14.0)[1]


def _generator(model: Model, eqs: list[str], name: str) -> Generator:
    g = synthesize(model, eqs, name, reference=observer_reference())
    return with_sensitivities(model, g)


def test_tank_observer_sensitivity_is_the_hand_derivation(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """Inflow fault fu of the tank (dh = u - q + fu): the observer absorbs it with its error pole, r settles at
    s * fu with s = (c F_f - a e_f) / (a + L c) = -(c^2 + eps) / (lambda c) at the true level; a measured-inflow
    offset +d is the model's fu = -d, and the simulated residual settles there."""
    (tmp_path / "t.toml").write_text(TANK)
    m = load_model(tmp_path / "t.toml")
    sig = tank_signals(1500, 0.5)
    g = with_sensitivities(m, synthesize(m, MSO, "T", reference=ObserverReference(signals=sig)))
    assert [f for f, _ in g.sensitivities] == ["fu", "fy"]
    s = sensitivity_series(g, sig)
    h = (0.5 / K) ** 2
    assert g.observer is not None and g.observer.c.free_symbols == {XHAT}
    c = float(g.observer.c.subs(XHAT, h))
    assert abs(c) == pytest.approx(K / (2 * np.sqrt(h)))
    lam = pole()
    eps = g.observer.eps
    assert eps == pytest.approx((OBSERVER_EPS * abs(c)) ** 2, rel=0.05)
    expect = -(c**2 + eps) / (lam * c)
    assert float(np.median(s["fu"][500:])) == pytest.approx(expect, rel=1e-3)
    offset = 0.01
    faulty = tank_signals(3000, 0.5, fu=offset, t_fault=5.0)
    r = residual(g, faulty)
    assert float(np.mean(r[-300:])) == pytest.approx(expect * -offset, rel=0.05)


@pytest.mark.parametrize("eqs,name", [(MSO7, "MSO7"), (MSO351, "MSO351")])
def test_analytic_sensitivity_equals_finite_differences(romo: Model, cornering: dict[str, np.ndarray],
                                                       eqs: list[str], name: str) -> None:
    """At every operating point the analytic d r / d f equals a one-sided difference of the residual computed
    with the faults kept: the forward one, or the backward one where the operating point sits on a kink of
    the tyre law (the slip normaliser Max(|v|, R |omega|) switches branch at rolling), whose derivative is
    one-sided (Heaviside)."""
    g = _generator(romo, eqs, name)
    assert {f for f, _ in g.sensitivities} <= set(g.faults) and len(g.sensitivities) >= 5
    analytic = sensitivity_series(g, cornering)
    values = node_signals(g, cornering, FilterDesign())
    xs = (sensitivity_estimate(observer_run(g, cornering, values, FilterDesign())[1]) if g.observer is not None
          else np.zeros(len(values[g.nodes[0]])))
    fd = _sensitivity_fn(romo, g, Solver(romo, keep_faults=True))
    assert fd is not None
    args = [values[n] for n in g.nodes]
    step = 1e-6
    forward = fd(xs, args, dict.fromkeys(g.faults, step), one_sided=1)
    backward = fd(xs, args, dict.fromkeys(g.faults, step), one_sided=-1)
    settled = slice(500, None)
    for f, a in analytic.items():
        tol = 1e-4 * (float(np.max(np.abs(a[settled]))) + 1e-12)
        ok = (np.abs(forward[f][settled] - a[settled]) <= tol) | (np.abs(backward[f][settled] - a[settled]) <= tol)
        assert ok.all(), f"{f}: {np.count_nonzero(~ok)} of {ok.size} operating points differ"


@pytest.mark.parametrize("fault,size", [("f23", 3.0), ("f23", -3.0), ("f4", 0.6), ("f11", 150.0), ("f19", 600.0)])
def test_sensitivity_predicts_the_step_fault_response(romo: Model, fault: str, size: float) -> None:
    """MSO7 in steady cornering, step faults of the required size (once the filters have settled): the
    residual's shift is the secant of the residual computed with the faults kept over the fault's size (what the
    screening's fault-to-noise ratio uses) within 5 %; the analytic derivative * size is exact (within 2 %)
    where the fault enters linearly (motor torque, tyre force) and overpredicts where it enters the tyre law's
    slip (wheel-speed and velocity sensor offsets of these sizes: the on-board exoneration margin covers it)."""
    g = _generator(romo, MSO7, "MSO7")
    t, clean = drive("cornering", duration=14.0, seed=5)
    t, faulty = drive("cornering", faults=[(fault, 8.0, size)], duration=14.0, seed=5)
    shift = residual(g, faulty) - residual(g, clean)
    assert float(np.max(np.abs(shift[t < 7.9]))) == 0.0  # nothing before the fault
    window = (t > 10.0) & (t < 13.9)
    values = node_signals(g, clean, FilterDesign())
    fd = _sensitivity_fn(romo, g, Solver(romo, keep_faults=True))
    assert fd is not None
    steps = dict.fromkeys(g.faults, 1e-3) | {fault: abs(size)}
    secant = fd(np.zeros(len(t)), [values[n] for n in g.nodes], steps, one_sided=1 if size > 0 else -1)[fault]
    measured_over_secant = float(np.median(shift[window] / (secant[window] * size)))
    assert measured_over_secant == pytest.approx(1.0, abs=0.05)
    derivative = sensitivity_series(g, clean)[fault]
    measured_over_derivative = float(np.median(shift[window] / (derivative[window] * size)))
    if fault in ("f11", "f19"):
        assert measured_over_derivative == pytest.approx(1.0, abs=0.02)
    else:
        assert 0.55 < measured_over_derivative < 0.8


# A body force balance of the practical selection with the wheel-2 speed estimated by an observer (MSO2058)
MSO2058 = ["B1", "B2", "B3", "D.psidot", "K1", "K2", "D1", "D2", "W1.FL", "W2.FL", "W3.FL", "W1.FS", "W2.FS",
           "W3.FS", "W1.Fx", "W2.Fx", "W3.Fx", "W1.Fy", "W2.Fy", "W3.Fy", "W2.dyn", "W2.D", "S3", "S4", "S5",
           "S.omega1", "S.omega3"]


@pytest.mark.parametrize("fault,size,low,high", [("f19", 600.0, 0.9, 1.1), ("f3", 0.05, 0.9, 1.1),
                                                 ("f7", 0.06, 0.7, 1.0), ("f24", 3.0, 0.5, 1.0)])
def test_observer_sensitivity_predicts_the_step_fault_response(romo: Model, fault: str, size: float, low: float,
                                                               high: float) -> None:
    """The observer generator's steady-state sensitivity (c F_f - a e_f) / (a + L c) against its residual's
    settled response to a step fault of the required size in steady cornering: within 10 % where the fault
    enters linearly (tyre force, yaw-rate offset); where it enters the tyre law's slip (steering offset,
    wheel-speed offset) the derivative overpredicts, never underpredicts (what the on-board exoneration's
    margin of 2 has to cover: a quiet test then reacts less than predicted, never more)."""
    g = _generator(romo, MSO2058, "MSO2058")
    assert g.observer is not None
    t, clean = drive("cornering", duration=14.0, seed=5)
    t, faulty = drive("cornering", faults=[(fault, 8.0, size)], duration=14.0, seed=5)
    shift = residual(g, faulty) - residual(g, clean)
    window = (t > 10.0) & (t < 13.9)
    predicted = sensitivity_series(g, clean)[fault] * size
    assert low < float(np.median(shift[window] / predicted[window])) <= high


def test_observer_absorbs_the_torque_of_its_own_wheel(romo: Model) -> None:
    """A motor torque fault of the observed wheel (f11 on wheel 2) is absorbed by the wheel-speed estimate: the
    predicted and the measured response both stay below a tenth of the test's sigma (228 N)."""
    g = _generator(romo, MSO2058, "MSO2058")
    t, clean = drive("cornering", duration=14.0, seed=5)
    t, faulty = drive("cornering", faults=[("f11", 8.0, 150.0)], duration=14.0, seed=5)
    window = (t > 10.0) & (t < 13.9)
    shift = (residual(g, faulty) - residual(g, clean))[window]
    predicted = (sensitivity_series(g, clean)["f11"] * 150.0)[window]
    assert float(np.max(np.abs(np.median(shift)))) < 22.8 and float(np.max(np.abs(np.median(predicted)))) < 22.8


# The longitudinal kinematics of the ROMO table (its test MSO1): a_x = d vx / dt - psidot vy, vx from the sensor
MSO1_KIN = ["K1", "D1", "S1", "S3", "S4", "S5"]


@pytest.mark.parametrize("rate", [0.3, -0.5])
def test_rate_gain_predicts_the_residual_of_a_drift(romo: Model, rate: float) -> None:
    """A vx sensor offset (f4) reaches the kinematic residual only through d vx / dt: no steady-state sensitivity,
    the rate gain -1 instead. A drift of the sensor at `rate` m/s^2 (added to vx_m from 8 s on) shifts the
    settled residual by gain * rate (within 2 %, and nothing before the drift); a step of the same sensor leaves
    no steady shift (why the size of a drift cannot be bounded from this residual, only its rate)."""
    g = _generator(romo, MSO1_KIN, "MSO1")
    assert dict(g.rate_gains) == {"f4": -1.0}
    assert "f4" not in dict(g.sensitivities) and "f5" in dict(g.sensitivities)
    t, clean = drive("cornering", duration=14.0, seed=5)
    drifting = dict(clean) | {"vx_m": clean["vx_m"] + rate * np.clip(t - 8.0, 0.0, None)}
    shift = residual(g, drifting) - residual(g, clean)
    assert float(np.max(np.abs(shift[t < 7.99]))) == 0.0
    window = (t > 10.0) & (t < 13.9)
    assert float(np.median(shift[window])) == pytest.approx(-1.0 * rate, rel=0.02)
    stepped = dict(clean) | {"vx_m": clean["vx_m"] + 0.6 * (t >= 8.0)}
    step_shift = residual(g, stepped) - residual(g, clean)
    assert float(np.max(np.abs(step_shift[window]))) < 0.01 * 0.6


def test_observer_and_static_faults_have_no_rate_gain(romo: Model) -> None:
    """Rate gains are listed only for faults without a steady-state sensitivity, and never for an observer
    generator (its estimate follows part of a drift: no constant gain)."""
    g = _generator(romo, MSO2058, "MSO2058")
    assert g.observer is not None and g.rate_gains == ()
    kin = _generator(romo, MSO1_KIN, "MSO1")
    assert not set(dict(kin.rate_gains)) & set(dict(kin.sensitivities))
