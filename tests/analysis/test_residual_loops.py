"""Algebraic loops in the computation sequence: solved jointly by Cramer's rule where the equations are linear
in the loop's unknowns (a determinant that holds signals is cleared from the residual like any division by a
signal), rejected with the reason otherwise, and another residual equation tried.

Hand-made models:
- a velocity sensor mounted on the wheel carrier of wheel 1 measures the body velocity rotated by the
  steering angle (vx_m, vy_m in wheel coordinates): neither R1 nor R2 alone gives vx or vy without dividing by
  cos/sin(delta1_m); together they are a rotation with determinant cos^2 + sin^2 = 1;
- two sensors of a + b and s a - b (s measured) and one of a b: the loop's determinant -(1 + s) is a division
  by a signal;
- the same with a singular loop (a + b and s (a + b))."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import sympy
from residual_harness import SIGNALS, build_harness, run_harness

from fdi_analysis.export.c_names import VehicleNames
from fdi_analysis.export.generators import generators_file, render
from fdi_analysis.export.signals import render as render_signals
from fdi_analysis.export.signals import signals_file
from fdi_analysis.model import Model
from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.causality import closure, plan, synthesize
from fdi_analysis.residuals.evaluate import residual
from fdi_analysis.residuals.realizability import why_not_realizable
from fdi_analysis.residuals.reasons import NotRealizableError, Reason, Rejection
from fdi_analysis.residuals.signals import raw
from fdi_analysis.residuals.solvability import BlockSolution, Solver, _determinant

ROTATED = """
[model]
name = "rotated_velocity_sensor"
[[unknown]]
foreach = { n = ["vx", "vy", "psidot", "dvx", "ax"] }
name = "{n}"
[[known]]
foreach = { n = ["ax_m", "psidot_m", "vx_m", "vy_m", "delta1_m"] }
name = "{n}"
[[fault]]
foreach = { n = ["f1", "f3", "f4", "f5"] }
name = "{n}"
[[equation]]
id = "K1"
expr = "ax = dvx - vy*psidot"
[[equation]]
id = "D1"
differential = ["dvx", "vx"]
[[equation]]
id = "S1"
expr = "ax_m = ax + f1"
[[equation]]
id = "S3"
expr = "psidot_m = psidot + f3"
[[equation]]
id = "R1"
expr = "vx_m = cos(delta1_m)*vx + sin(delta1_m)*vy + f4"
[[equation]]
id = "R2"
expr = "vy_m = -sin(delta1_m)*vx + cos(delta1_m)*vy + f5"
"""

PRODUCT = """
[model]
name = "product"
[[unknown]]
foreach = { n = ["a", "b"] }
name = "{n}"
[[known]]
foreach = { n = ["u", "y", "s", "w"] }
name = "{n}"
[[fault]]
foreach = { n = ["fu", "fy", "fw"] }
name = "{n}"
[[equation]]
id = "E1"
expr = "u = a + b + fu"
[[equation]]
id = "E2"
expr = "y = SECOND + fy"
[[equation]]
id = "E3"
expr = "w = a*b + fw"
"""
DT = 0.01


def _model(tmp_path: Path, name: str, text: str) -> Model:
    (tmp_path / name).write_text(text)
    return load_model(tmp_path / name)


@pytest.fixture
def rotated(tmp_path: Path) -> Model:
    return _model(tmp_path, "rotated.toml", ROTATED)


def rotated_drive(n: int, f1: float = 0.0, f4: float = 0.0, t_fault: float = 1e9) -> dict[str, np.ndarray]:
    """Consistent signals of a slow manoeuvre (ax = d/dt vx - vy psidot), the velocity seen in wheel-1
    coordinates; faults f1 (ax_m) and f4 (vx_m) from t_fault."""
    t = np.arange(n) * DT
    vx = 10.0 + 2.0 * np.sin(0.4 * t)
    vy = 0.5 * np.sin(0.3 * t + 0.4)
    psidot = 0.3 * np.sin(0.25 * t) + 0.1
    delta = 0.2 * np.sin(0.35 * t)
    ax = 0.8 * np.cos(0.4 * t) - vy * psidot
    on = t >= t_fault
    sig = {k: np.zeros(n) for k in SIGNALS}
    sig["ax_m"] = ax + np.where(on, f1, 0.0)
    sig["psidot_m"] = psidot
    sig["vx_m"] = np.cos(delta) * vx + np.sin(delta) * vy + np.where(on, f4, 0.0)
    sig["vy_m"] = -np.sin(delta) * vx + np.cos(delta) * vy
    sig["delta1_m"] = delta
    return sig


def test_rotation_loop_is_solved_jointly(rotated: Model) -> None:
    solver = Solver(rotated)
    for e in ("R1", "R2"):  # alone each divides by cos or sin of the steering angle: not a polynomial
        assert not solver.solvable(rotated.equation(e), "vx") or not solver.solvable(rotated.equation(e), "vy")
    blk = solver.solve_block([rotated.equation("R1"), rotated.equation("R2")], ["vx", "vy"])
    assert isinstance(blk, BlockSolution)
    d, vxm, vym = (sympy.Symbol(s) for s in ("delta1_m", "vx_m", "vy_m"))
    assert all(s.coefficient == 1 for s in blk.solutions)  # cos^2 + sin^2 found to be 1
    assert sympy.simplify(blk.solutions[0].expr - (sympy.cos(d) * vxm - sympy.sin(d) * vym)) == 0
    assert sympy.simplify(blk.solutions[1].expr - (sympy.sin(d) * vxm + sympy.cos(d) * vym)) == 0
    g = synthesize(rotated, [e.id for e in rotated.equations], "ROT")
    assert g.residual_equation == "K1" and g.level == 1 and not g.scaled_by
    assert [(s.var, s.equation, s.kind) for s in g.steps if s.kind == "loop"] == [("vx", "R1+R2", "loop"),
                                                                               ("vy", "R1+R2", "loop")]
    assert "algebraic loop R1+R2 solved jointly for vx, vy" in g.causality()
    assert g.faults == ("f1", "f3", "f4", "f5")


def test_rotation_loop_residual_on_signals_and_in_c(rotated: Model, repo: Path, tmp_path: Path) -> None:
    """Fault-free the residual stays near 0 (filter lag only); an ax_m offset moves it by the offset; the
    emitted C (fw gates' flags) computes the same residual as the Python evaluation."""
    g = synthesize(rotated, [e.id for e in rotated.equations], "ROT")
    n = 2000
    r0 = residual(g, rotated_drive(n))[300:]
    rf = residual(g, rotated_drive(n, f1=0.2, t_fault=10.0))
    assert np.max(np.abs(r0)) < 0.02
    assert float(np.mean(rf[1300:])) == pytest.approx(0.2, rel=0.05)
    names = VehicleNames("rot")
    faults = [f.name for f in rotated.faults]
    for base, (header, source) in ((names.generators, render(generators_file([g], names, faults, "/* test */",
                                                                                    [k.name for k in rotated.knowns]))),
                                   (names.signals, render_signals(signals_file(rotated, names, "/* test */")))):
        (tmp_path / f"{base}.h").write_text(header)
        (tmp_path / f"{base}.c").write_text(source)
    sig = rotated_drive(n, f4=0.5, t_fault=8.0)
    h = build_harness(repo, tmp_path, [f"&{names.generators}[0]"],
                      sources=[tmp_path / f"{names.generators}.c", tmp_path / f"{names.signals}.c"],
                      include_dirs=[tmp_path], headers=[f"{names.generators}.h"],
                      signals=[k.name for k in rotated.knowns])
    c = run_harness(h, sig).residuals[:, 0]
    py = residual(g, sig)
    scale = float(np.max(np.abs(py)))
    assert scale > 0.01 and float(np.max(np.abs(c - py))) < 1e-3 * scale


def test_determinant_with_a_signal_is_cleared_from_the_residual(tmp_path: Path) -> None:
    """a = (u + y) / (1 + s), b = (s u - y) / (1 + s): the residual w - a b is multiplied by (1 + s)^2 and is
    exactly 0 on consistent samples (no filters: nothing is differentiated)."""
    m = _model(tmp_path, "p.toml", PRODUCT.replace("SECOND", "s*a - b"))
    p = plan(m, Solver(m), ["E1", "E2", "E3"])
    assert p.residual == "E3" and {s.kind for s in p.steps} == {"loop"} and p.divisions == 2
    # with E1 or E2 as the residual equation the loop holds a*b: not linear in a and b jointly
    for r in ("E1", "E2"):
        why = closure(m, Solver(m), ["E1", "E2", "E3"], r)
        assert isinstance(why, Rejection) and why.kind is Reason.ALGEBRAIC_LOOP and "not linear" in why.text
    g = synthesize(m, ["E1", "E2", "E3"], "P")
    u, y, s, w = (raw(k) for k in ("u", "y", "s", "w"))
    assert sympy.expand(g.expr ** 2 - (w * (1 + s) ** 2 - (u + y) * (s * u - y)) ** 2) == 0
    rng = np.random.default_rng(3)
    a, b, sv = rng.normal(size=50), rng.normal(size=50), rng.uniform(0.5, 2.0, size=50)
    sig = {"u": a + b, "y": sv * a - b, "s": sv, "w": a * b}
    assert np.max(np.abs(residual(g, sig)[1:])) < 1e-12
    sig["w"] = a * b + 0.1
    assert np.min(np.abs(residual(g, sig)[1:])) > 0.0


def test_singular_loop_is_rejected_with_the_reason(tmp_path: Path) -> None:
    m = _model(tmp_path, "s.toml", PRODUCT.replace("SECOND", "s*(a + b)"))
    solver = Solver(m)
    why = solver.solve_block([m.equation("E1"), m.equation("E2")], ["a", "b"])
    assert isinstance(why, Rejection) and why.kind is Reason.ALGEBRAIC_LOOP
    assert "singular" in why.text and "E1, E2" in why.text
    with pytest.raises(NotRealizableError, match="algebraic loop"):
        synthesize(m, ["E1", "E2", "E3"], "S")


def test_marked_pair_is_never_solved_inside_a_loop(tmp_path: Path) -> None:
    text = PRODUCT.replace("SECOND", "s*a - b").replace('expr = "u = a + b + fu"',
                                                       'expr = "u = a + b + fu"\nnot_solvable_for = ["a"]')
    m = _model(tmp_path, "n.toml", text)
    why = Solver(m).solve_block([m.equation("E1"), m.equation("E2")], ["a", "b"])
    assert isinstance(why, Rejection) and why.kind is Reason.ALGEBRAIC_LOOP
    assert (why.equation, why.variable) == ("E1", "a") and "E1 is marked not_solvable_for a" in why.text
    with pytest.raises(NotRealizableError):
        synthesize(m, ["E1", "E2", "E3"], "N")


def test_tyre_law_loops_of_romo_are_rejected_with_the_equation_and_variable(repo: Path) -> None:
    """The ROMO loops through a tyre law (the slip normaliser, not linear in the velocities) stay rejected,
    naming the equation and the variable."""
    m = load_model(repo / "analysis/models/romo_grouped.toml")
    eqs = ["W1.FL", "W2.FL", "W1.dyn", "W2.dyn", "W1.D", "W2.D", "S1", "S2", "S4", "S5", "S.omega1", "S.omega2"]
    why = why_not_realizable(m, Solver(m), eqs)
    assert why is not None and why.kind is Reason.ALGEBRAIC_LOOP
    assert why.equation in ("W1.FL", "W2.FL") and why.equation in why.text and why.variable in why.text
    assert "not_solvable_for" in why.text or "not linear" in why.text


def test_determinant_probe_is_relative_to_the_coefficients() -> None:
    """A small but regular determinant is not taken for 0 (zero is judged against Hadamard's bound of the
    rows), a singular one is 0 whatever the scale, a constant one is exact, a polynomial one symbolic."""
    a, b = sympy.symbols("a b")
    assert _determinant(sympy.Matrix([[1e-6, 0], [0, 1e-6]])) == pytest.approx(1e-12)
    assert _determinant(sympy.Matrix([[1e6 * a, 2e6 * a], [1, 2]])) == 0
    assert _determinant(sympy.Matrix([[sympy.cos(a), sympy.sin(a)], [-sympy.sin(a), sympy.cos(a)]])) == 1
    assert sympy.expand(_determinant(sympy.Matrix([[a, 1], [1, b]])) - (a * b - 1)) == 0
    assert _determinant(sympy.Matrix([[sympy.sqrt(a**2 + 1), 1], [1, b]])) is None  # varies, not polynomial
