"""Calibration on a fleet (fdi_host.tuning.fleet_calibration) on synthetic series whose truth is known: what a test
estimates (the constants lumped, the largest shares first, a regressor the chosen ones already span left out, inputs
without a drift never), and its sigma with and without the estimator (an offset the estimator takes does not widen
sigma; without it sigma must cover it); the Python filter replica against the C estimator through the diagnoser."""

from __future__ import annotations

import numpy as np
import sympy

from fdi_analysis.residuals.estimation import estimated
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.uncertainty_sensitivity import Uncertainty
from fdi_host.tuning.estimator import innovations
from fdi_host.tuning.fleet_calibration import Series, calibrate_sigma, choose_estimation

AX = sympy.Symbol("ax_m", real=True)
Q = {
    "b": Uncertainty("b", "slow", 0.0, (-0.2, 0.2), "m/s^2", 0.005),
    "g": Uncertainty("g", "input", 0.0, (-0.8, 0.8), "m/s^2", 0.1),
    "c": Uncertainty("c", "parameter", 0.03, (0.0, 0.06), "1"),
    "c2": Uncertainty("c2", "parameter", 0.0, (-0.05, 0.05), "1"),
    "mu": Uncertainty("mu", "input", 1.0, (0.15, 1.0), "1"),
}


def _generator() -> Generator:
    g = Generator.__new__(Generator)
    object.__setattr__(g, "name", "T")
    object.__setattr__(g, "uncertainty", (("b", sympy.Float(-1.0)), ("g", sympy.Float(-1.0)), ("c", AX),
                                          ("c2", 1.01 * AX), ("mu", AX**2)))
    return g


def _series(rng: np.random.Generator, offset: float, tilt: float, n: int = 3000) -> Series:
    t = np.arange(n) * 0.01
    ax = 3.0 * np.sin(0.7 * t) + 0.5 * np.sin(2.3 * t)
    r = offset + tilt * ax + 0.02 * rng.standard_normal(n)
    starts = np.zeros(n, dtype=bool)
    starts[0] = True
    return Series(r, starts, {"b": -np.ones(n), "g": -np.ones(n), "c": ax, "c2": 1.01 * ax, "mu": ax**2})


def test_the_choice_lumps_constants_ranks_and_leaves_out_what_is_spanned() -> None:
    rng = np.random.default_rng(1)
    groups = choose_estimation(_generator(), [_series(rng, 0.3, 0.02) for _ in range(3)], Q)
    # b and g enter as the same constant: one offset (its share 0.2 + 0.8 the largest); c and c2 are the same
    # regressor but for 1 %: c2 has the larger share (its half-width 0.05 against c's 0.03), c is left out; mu is an
    # input without a drift: never estimated
    assert groups == (("b", "g"), ("c2",))


def test_the_estimator_takes_an_offset_that_a_fixed_gate_must_cover() -> None:
    rng = np.random.default_rng(2)
    drives = [_series(rng, off, tilt) for off, tilt in ((0.5, 0.04), (-0.6, 0.01), (0.1, 0.05))]
    g = _generator()
    widths = {n: u.half_width for n, u in Q.items()}
    est = estimated(g, [("b", "g"), ("c",)], Q, 0.01)
    with_est = calibrate_sigma(drives, est, widths, 5.0)
    fixed = calibrate_sigma(drives, (), {n: 0.0 for n in Q}, 5.0)  # nothing estimated, no spread
    assert fixed.sigma > 0.6 / 5.0  # the gate alone must hold the largest offset
    assert with_est.sigma < fixed.sigma / 3.0
    assert with_est.sigma >= 0.02  # never below the noise it leaves
    nu, a = innovations(np.column_stack([np.ones(3000), drives[0].sens["c"]]), drives[0].r, est, with_est.sigma**2)
    assert abs(float(np.mean(nu[1500:]))) < 0.01  # the offset taken
    assert float(np.median(a[1500:])) < float(a[0]) / 5.0  # the spread narrowed from the prior's


def test_the_replica_is_the_c_estimator() -> None:
    """The calibration's filter (numba, double) against the library's fdi_est (float, called through the extension)
    on the same residual and regressors, with steps cut by the step limit at the start: the innovations and spreads
    agree to float rounding."""
    import ctypes

    from fdi_host.ecu.bindings import _lib

    dll = _lib().dll
    rng = np.random.default_rng(3)
    s = _series(rng, 0.4, 0.03)
    est = estimated(_generator(), [("b", "g"), ("c",)], Q, 0.01)
    h = np.column_stack([np.ones(len(s.r)), s.sens["c"]])
    sigma, d = 0.02, 10.0
    nu_py, a_py = innovations(h, s.r, est, sigma**2, d)

    class Param(ctypes.Structure):
        _fields_ = [(k, ctypes.c_float) for k in ("mean", "var", "q", "lo", "hi", "step")]

    params = (Param * len(est))(*[Param(e.mean, e.var, e.q, e.lo, e.hi, e.step) for e in est])
    state = ctypes.create_string_buffer(256)
    assert dll.fdi_est_init(state, params, ctypes.c_uint32(len(est))) == 0
    nu_c, a_c = np.empty(len(s.r)), np.empty(len(s.r))
    nu, a = ctypes.c_float(), ctypes.c_float()
    for k in range(len(s.r)):
        hk = (ctypes.c_float * 2)(*h[k])
        assert dll.fdi_est_update(state, params, ctypes.c_uint32(len(est)), hk, ctypes.c_float(s.r[k]),
                                  ctypes.c_float(sigma**2 * d), ctypes.c_float(d), ctypes.c_bool(False),
                                  ctypes.byref(nu), ctypes.byref(a)) == 0
        nu_c[k], a_c[k] = nu.value, a.value
    assert float(np.max(np.abs(nu_c - nu_py))) < 1e-3 * sigma + 1e-5
    assert float(np.max(np.abs(a_c - a_py) / np.maximum(a_py, 1e-6))) < 1e-3
    assert float(np.max(np.abs(nu_py[1:] - s.r[1:]))) > 0.1  # the filter did act
