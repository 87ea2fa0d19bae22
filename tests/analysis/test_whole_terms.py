"""Residual terms filtered as a whole (fdi_analysis.residuals.whole_terms): which terms become the derived signal,
and that the generator built so holds the exactly filtered relation where the product of filtered signals does
not (a fast manoeuvre on the ROMO kinematic test K2: ay = d/dt vy + vx psidot with the sensors' lever arms)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import sympy

from fdi_analysis.model import Model
from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.causality import synthesize
from fdi_analysis.residuals.evaluate import FilterDesign, residual
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.signals import Node, nodes_in
from fdi_analysis.residuals.whole_terms import composite_signal, whole_terms
from fdi_host.tuning.drives import observer_reference

KINEMATIC_Y = ["K2", "D2", "S2", "S3", "S4", "S5"]  # ay = dvy + vx psidot and the IMU / velocity sensors


@pytest.fixture(scope="module")
def romo(repo) -> Model:  # type: ignore[no-untyped-def]
    return load_model(repo / "analysis/models/romo_grouped.toml")


def _node(name: str, level: int = 1, order: int = 0) -> sympy.Symbol:
    return Node(name, level, order).symbol


def test_only_smooth_derivative_free_nonlinear_terms_are_taken() -> None:
    a, b, c = _node("a"), _node("b"), _node("c")
    da = _node("a", 1, 1)
    expr = 2 * a + da + b * c + sympy.tanh(b) * a + b * da + sympy.sqrt(sympy.Abs(c)) + c / b
    out, comp = whole_terms(expr, 1, "T")
    assert comp is not None and comp.signal == composite_signal("T")
    raw = {n.signal: Node(n.signal, 0, 0).symbol for n in nodes_in(expr)}
    # the product and the smooth function's product, from raw samples; the linear term, the derivative terms, the
    # root of an absolute value and the division stay on the filtered signals
    assert sympy.simplify(comp.expr - (raw["b"] * raw["c"] + sympy.tanh(raw["b"]) * raw["a"])) == 0
    assert comp.sources == ("a", "b", "c")
    rest = out - _node(comp.signal)
    assert sympy.simplify(rest - (2 * a + da + b * da + sympy.sqrt(sympy.Abs(c)) + c / b)) == 0
    # nothing to take: unchanged; no filter (level 0): unchanged
    assert whole_terms(2 * a + da, 1, "T") == (2 * a + da, None)
    flat = Node("a", 0, 0).symbol * Node("b", 0, 0).symbol
    assert whole_terms(flat, 0, "T") == (flat, None)


def _spin(n: int, dt: float) -> dict[str, np.ndarray]:
    """Consistent K2 signals of a fast manoeuvre (speed falling, yaw rate and side slip building up), no noise:
    vy, psidot and vx as smooth functions of time, ay from the relation, the sensors with their lever arms."""
    t = np.arange(n) * dt
    s = np.clip((t - 1.0) / 2.0, 0.0, 1.0)
    smooth = s * s * (3.0 - 2.0 * s)
    vx = 20.0 - 15.0 * smooth
    psidot = -1.8 * smooth
    vy = 7.5 * smooth
    dvy = np.gradient(vy, dt)
    ay = dvy + vx * psidot
    d_x, d_y = 1.0, 0.3  # the model's lever arms (romo_quasistatic.toml S4, S5)
    return {"ay_m": ay, "psidot_m": psidot, "vx_m": vx - d_y * psidot, "vy_m": vy + d_x * psidot}


def _signal_filtered(g: Generator) -> Generator:
    """The same generator with its derived signal expanded back into products of filtered signals."""
    assert g.composite is not None
    lifted = g.composite.expr.xreplace({n.symbol: Node(n.signal, g.level, 0).symbol
                                        for n in nodes_in(g.composite.expr)})
    own = g.composite.signal
    return replace(g, expr=g.expr.xreplace({Node(own, g.level, 0).symbol: lifted}), composite=None,
                   filters=tuple(f for f in g.filters if f.signal != own),
                   nodes=tuple(n for n in g.nodes if n.signal != own))


def test_the_kinematic_test_holds_the_filtered_relation_in_a_spin(romo: Model) -> None:
    g = synthesize(romo, KINEMATIC_Y, "MSO2", reference=observer_reference())
    assert g.observer is None and g.composite is not None
    assert set(g.composite.sources) == {"psidot_m", "vx_m"}  # the product vx psidot, not ay or a derivative
    design = FilterDesign(dt=0.001)
    sig = _spin(6000, design.dt)
    whole = np.abs(residual(g, sig, design))
    products = np.abs(residual(_signal_filtered(g), sig, design))
    # with the product of filtered signals the relation breaks by the filter lag (here ~0.1 m/s^2, a gate of the
    # ROMO table); filtered whole, only the discrete derivative's error is left
    assert products.max() > 0.05
    assert whole.max() < products.max() / 20.0
