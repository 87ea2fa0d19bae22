"""Causality for a state whose derivative the sequence would take twice: integral causality through an
observer when the residual equation sees the state uniformly (d r / d x a nonzero constant), else the second
derivative is kept and the generator says why (ROMO's MSO3/MSO4, the paper's ARR3/ARR4, whose observer
alternative sees vy resp. vx only through the yaw rate).

Hand-made double integrator: position sensor y, accelerometer acc.
    E1: dx = d/dt x   E2: dv = d/dt v   E3: dx = v   E4: dv = a   S1: y = x + fy   S2: acc = a + fa
The derivative sequence takes v = d/dt y and dv = d/dt v: a second derivative of y (two filter levels).
With v estimated by an observer: v^' = acc + L e, e = +-(d/dt y - v^), c = de/dv^ = -+1, a = 0, L = -lambda c / c^2,
so for an accelerometer bias fa the estimate error settles at fa / lambda and the residual at |fa| / lambda."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fdi_analysis.model import Model
from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.causality import plan, synthesize, twice_differentiated
from fdi_analysis.residuals.evaluate import residual
from fdi_analysis.residuals.reasons import NotRealizableError, Reason
from fdi_analysis.residuals.solvability import Solver
from fdi_host.tuning.drives import observer_reference

DOUBLE_INTEGRATOR = """
[model]
name = "double_integrator"
[[unknown]]
foreach = { n = ["x", "dx", "v", "dv", "a"] }
name = "{n}"
[[known]]
foreach = { n = ["y", "acc"] }
name = "{n}"
[[fault]]
foreach = { n = ["fy", "fa"] }
name = "{n}"
[[equation]]
id = "E1"
differential = ["dx", "x"]
[[equation]]
id = "E2"
differential = ["dv", "v"]
[[equation]]
id = "E3"
expr = "dx = v"
[[equation]]
id = "E4"
expr = "dv = a"
[[equation]]
id = "S1"
expr = "y = x + fy"
[[equation]]
id = "S2"
expr = "acc = a + fa"
"""
ALL = ["E1", "E2", "E3", "E4", "S1", "S2"]
DT = 0.01
ARR3 = ["K1", "K2", "D1", "D2", "S1", "S2", "S3", "S4"]
ARR4 = ["K1", "K2", "D1", "D2", "S1", "S2", "S3", "S5"]


@pytest.fixture
def integrator(tmp_path: Path) -> Model:
    (tmp_path / "di.toml").write_text(DOUBLE_INTEGRATOR)
    return load_model(tmp_path / "di.toml")


def oscillation(n: int, fa: float = 0.0, t_fault: float = 1e9) -> dict[str, np.ndarray]:
    t = np.arange(n) * DT
    w = 0.5
    return {"y": np.sin(w * t), "acc": -w * w * np.sin(w * t) + np.where(t >= t_fault, fa, 0.0)}


def test_observer_replaces_a_second_derivative_it_sees_uniformly(integrator: Model) -> None:
    p = plan(integrator, Solver(integrator), ALL)
    assert p.level == 2 and twice_differentiated(integrator, p) == ["v"]
    g = synthesize(integrator, ALL, "DI")
    assert g.observer is not None and g.observer.state == "v" and g.observer.equation == "E2"
    assert g.residual_equation == "E3" and g.level == 1 and not g.note
    assert not g.observer.c.free_symbols and abs(float(g.observer.c)) == 1.0
    d = synthesize(integrator, ALL, "DI", causality="derivative")
    assert d.observer is None and d.level == 2  # v = d/dt y, then dv - d/dt v as the residual (E2)


def test_double_integrator_residuals(integrator: Model) -> None:
    """Fault-free both stay small after the warm-up; an accelerometer bias moves the observer residual to
    |fa| / lambda (hand derivation above) and the second-derivative residual to |fa|."""
    g = synthesize(integrator, ALL, "DI")
    d = synthesize(integrator, ALL, "DI", causality="derivative")
    assert g.observer is not None
    lam = g.observer.pole
    n, fa = 3000, 0.2
    for gen, steady in ((g, fa / lam), (d, fa)):
        r0 = residual(gen, oscillation(n))[500:]
        rf = residual(gen, oscillation(n, fa=fa, t_fault=15.0))
        assert np.max(np.abs(r0)) < 0.05 * steady
        assert abs(float(np.mean(rf[2500:]))) == pytest.approx(steady, rel=0.05)


def test_romo_arr3_arr4_keep_the_second_derivative_and_say_why(repo: Path) -> None:
    """The observer alternative of MSO3 (vy from K2 integrated, residual K1) sees vy only through psidot: the
    default keeps ARR3's second derivative; causality="integral" takes the observer."""
    m = load_model(repo / "analysis/models/romo_grouped.toml")
    for eqs, state, out_eq in ((ARR3, "vy", "K1"), (ARR4, "vx", "K2")):
        g = synthesize(m, eqs, "T")
        assert g.observer is None and g.level == 2
        assert g.note.startswith(f"an observer for {state} (residual {out_eq}) instead of the second derivative")
        assert "psidot_m" in g.note
        with pytest.raises(NotRealizableError) as exc:  # its gain is designed on a reference drive
            synthesize(m, eqs, "T", causality="integral")
        assert exc.value.kind is Reason.NO_REFERENCE
        i = synthesize(m, eqs, "T", reference=observer_reference(), causality="integral")
        assert i.observer is not None and i.observer.state == state and i.residual_equation == out_eq
        assert i.level == 1 and "psidot_m" in str(i.observer.c)
