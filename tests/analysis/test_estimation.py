"""What an on-line estimator of a test follows (fdi_analysis.residuals.estimation): each estimated quantity's
declaration (deviation from the model's value: prior mean and variance of a uniform range, the step variance from the
declared drift, the bounds, the largest move per step), offsets lumped from quantities of constant sensitivity, and
the errors for what a test cannot estimate."""

from __future__ import annotations

import math

import pytest
import sympy

from fdi_analysis.residuals.estimation import LEARN_S, RAMP_LAG, EstimationError, estimated
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.uncertainty_sensitivity import Uncertainty

DT = 0.01
AX = sympy.Symbol("ax_m", real=True)

QUANTITIES = {
    "m": Uncertainty("m", "parameter", 1046.0, (1046.0, 1307.5), "kg"),
    "b_ax": Uncertainty("b_ax", "slow", 0.0, (-0.15, 0.15), "m/s^2", 0.005),
    "g_x": Uncertainty("g_x", "input", 0.0, (-0.78, 0.78), "m/s^2", 0.1),
    "mu_max": Uncertainty("mu_max", "input", 1.0, (0.15, 1.0), "1"),
    "c_ax": Uncertainty("c_ax", "parameter", 0.03, (0.0, 0.06), "1"),
}


def _generator(uncertainty: tuple[tuple[str, sympy.Expr], ...]) -> Generator:
    g = Generator.__new__(Generator)
    object.__setattr__(g, "name", "T1")
    object.__setattr__(g, "uncertainty", uncertainty)
    return g


def test_a_vehicle_constant_a_drift_and_a_rate_limited_move() -> None:
    g = _generator((("m", 2.0 * AX), ("b_ax", sympy.Float(-1.0)), ("g_x", sympy.Float(-1.0)),
                    ("c_ax", AX), ("mu_max", AX**2)))
    m, b = estimated(g, [["m"], ["b_ax"]], QUANTITIES, DT)
    assert m.names == ("m",) and m.regressor == 2.0 * AX
    assert (m.lo, m.hi) == (0.0, 261.5) and m.mean == pytest.approx(130.75)
    assert m.var == pytest.approx(261.5**2 / 12)
    assert m.q == pytest.approx(m.var * DT / 3600.0)  # a vehicle's constant forgets over an hour
    assert m.step == pytest.approx(261.5 / LEARN_S * DT)
    assert b.q == pytest.approx((0.005 * DT / RAMP_LAG) ** 2)
    assert b.step == pytest.approx(max(0.005, 0.3 / LEARN_S) * DT)
    assert b.width == pytest.approx(0.15)


def test_constants_lump_into_one_offset() -> None:
    g = _generator((("b_ax", sympy.Float(-0.97)), ("g_x", sympy.Float(-0.97)), ("c_ax", AX)))
    (off,) = estimated(g, [["b_ax", "g_x"]], QUANTITIES, DT)
    assert off.regressor == 1 and off.label == "b_ax + g_x"
    assert off.hi == pytest.approx(0.97 * (0.15 + 0.78)) and off.lo == pytest.approx(-off.hi)
    one = estimated(g, [["b_ax"]], QUANTITIES, DT)[0]
    other = estimated(g, [["g_x"]], QUANTITIES, DT)[0]
    assert off.var == pytest.approx(0.97**2 * (one.var + other.var))
    assert off.q == pytest.approx(0.97**2 * (one.q + other.q))
    assert off.step == pytest.approx(0.97 * (one.step + other.step))
    assert math.isclose(off.mean, 0.0, abs_tol=1e-12)


def test_what_a_test_cannot_estimate_is_an_error() -> None:
    g = _generator((("b_ax", sympy.Float(-1.0)), ("c_ax", AX), ("mu_max", AX**2)))
    with pytest.raises(EstimationError, match="no sensitivity to 'm'"):
        estimated(g, [["m"]], QUANTITIES, DT)
    with pytest.raises(EstimationError, match="mu_max is an input without a declared drift"):
        estimated(g, [["mu_max"]], QUANTITIES, DT)
    with pytest.raises(EstimationError, match="c_ax is not a constant"):
        estimated(g, [["b_ax", "c_ax"]], QUANTITIES, DT)
    with pytest.raises(EstimationError, match="estimated twice"):
        estimated(g, [["b_ax"], ["b_ax"]], QUANTITIES, DT)
    with pytest.raises(EstimationError, match="empty"):
        estimated(g, [[]], QUANTITIES, DT)
    assert estimated(g, [], QUANTITIES, DT) == ()
