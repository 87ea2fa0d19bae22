"""ARR3/ARR4 of the paper: derivation from the model, the filter, and the Fig. 6 isolation property."""

from __future__ import annotations

import numpy as np
import pytest
import sympy

from fdi_analysis.model_loader import load_model
from fdi_host.paper.arr import SVFDerivative
from fdi_host.paper.fig6 import QUIET_BANDS, REACT_BANDS, SETTLE_S, Fig6Result, run_fig6
from fdi_host.sim.plant import DEFAULT_MODEL


def test_arrs_follow_from_model_equations() -> None:
    """Build the measurements from K1, K2, S1..S5 of the model file (at its nominal accelerometer tilt) and check
    r3 = f4*w^3 and r4 = f5*w^3 (constant faults), and that r3 does not see f5 nor r4 f4."""
    m = load_model(DEFAULT_MODEL)
    t = sympy.Symbol("t")
    vx, vy, w = (sympy.Function(n)(t) for n in ("vx", "vy", "psidot"))
    f = {k: sympy.Symbol(k) for k in ("f1", "f2", "f3", "f4", "f5")}
    # the parameters symbolic, but the accelerometer's tilt at the model's value: none, as in the paper (on a vehicle
    # that pitches and rolls the ARRs see it: the on-line estimators' work, docs/robust_diagnosis.md)
    tilt = ("c_ax", "c_ay")
    params = {sympy.Symbol(k): sympy.nsimplify(m.parameters[k].value) if k in tilt else sympy.Symbol(k)
              for k in m.parameters}
    assert all(params[sympy.Symbol(k)] == 0 for k in tilt)
    state = {sympy.Symbol("vx"): vx, sympy.Symbol("vy"): vy, sympy.Symbol("psidot"): w,
             sympy.Symbol("dvx"): vx.diff(t), sympy.Symbol("dvy"): vy.diff(t)} | params
    env = dict(state)
    for eid in ("K1", "K2"):
        e = m.equation(eid)
        env[e.lhs] = e.rhs.xreplace(env)  # ax, ay
    meas = {}
    for eid in ("S1", "S2", "S4", "S5"):
        e = m.equation(eid)
        meas[str(e.lhs)] = e.rhs.xreplace(env | {sympy.Symbol(k): v for k, v in f.items()})
    d_x, d_y = sympy.Symbol("d_x"), sympy.Symbol("d_y")
    wm = w  # yaw-rate sensor fault-free here (f3 is in both ARRs)
    vxr = meas["vx_m"] + d_y * wm
    p = vxr.diff(t) - meas["ax_m"]
    r3 = wm * p.diff(t) - p * wm.diff(t) - (meas["ay_m"] - vxr * wm) * wm**2
    vyr = meas["vy_m"] - d_x * wm
    q = vyr.diff(t) - meas["ay_m"]
    r4 = wm * q.diff(t) - q * wm.diff(t) + (meas["ax_m"] + vyr * wm) * wm**2
    assert sympy.simplify(sympy.expand(r3 - f["f4"] * w**3 + f["f2"] * w**2 - f["f1"] * w.diff(t))) == 0
    assert sympy.simplify(sympy.expand(r4 - f["f5"] * w**3 - f["f1"] * w**2 - f["f2"] * w.diff(t))) == 0
    assert not r3.has(f["f5"]) and not r4.has(f["f4"])


def test_svf_derivatives_of_a_ramp_and_a_parabola() -> None:
    dt = 0.01
    t = np.arange(0, 20, dt)
    filt = SVFDerivative(1.0)
    y, dy, ddy = filt.apply(3.0 * t, dt)
    late = t > 8
    np.testing.assert_allclose(dy[late], 3.0, atol=1e-6)
    np.testing.assert_allclose(ddy[late], 0.0, atol=1e-6)
    y, dy, ddy = filt.apply(0.5 * t**2, dt)
    np.testing.assert_allclose(ddy[late], 1.0, atol=1e-6)
    np.testing.assert_allclose(np.gradient(y, dt)[late], dy[late], rtol=1e-3)


@pytest.fixture(scope="module")
def fig6() -> Fig6Result:
    return run_fig6("fig6", cutoff_hz=1.0)


def test_fig6_isolation(fig6: Fig6Result) -> None:
    assert set(fig6.windows) == {"f4", "f5", "f6"}
    assert fig6.ratio("f4", "r3") >= REACT_BANDS and fig6.ratio("f4", "r4") <= QUIET_BANDS
    assert fig6.ratio("f5", "r4") >= REACT_BANDS and fig6.ratio("f5", "r3") <= QUIET_BANDS
    assert fig6.ratio("f6", "r3") <= QUIET_BANDS and fig6.ratio("f6", "r4") <= QUIET_BANDS


def test_fig6_faulty_drive_is_quiet_outside_the_fault_windows(fig6: Fig6Result) -> None:
    """A second noise realisation stays inside the band derived from the first one when no fault acts."""
    t = fig6.faulty.t
    quiet = t >= SETTLE_S
    for a, b in fig6.windows.values():
        quiet &= ~((t >= a) & (t < b))
    for key in ("r3", "r4"):
        assert np.abs(getattr(fig6.faulty, key)[quiet]).max() <= QUIET_BANDS * fig6.band[key]


def test_fig6_band_is_not_trivial(fig6: Fig6Result) -> None:
    """The band is set by the drive and the noise, not zero: without faults the residuals move."""
    assert fig6.band["r3"] > 1e-3 and fig6.band["r4"] > 1e-3
