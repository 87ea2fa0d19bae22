"""Integral causality through an observer: one state x of an MSO set that the plain sequence could only
integrate open loop (dx = d/dt x with no measurement of x in the set).

The estimate xh is treated as a known signal; the rest of the MSO is computed by the ordinary sequence, the
differential constraint gives the state update dx = F(xh, u) and the equation left over is the residual
e(xh, u) (u = the filtered measured signals). Observer and residual:

    xh' = G(xh, u) = F(xh, u) + L(xh, u) * e(xh, u),      r = e(xh, u)

With a = dF/dx and c = de/dx (sympy, through the sequence) the error pole of the linearisation is a + L c.
The gain places it at -lambda where the residual sees the state and where the model's own dynamics are
slower than that, and leaves the (faster) own dynamics alone otherwise:

    L = -max(lambda + a, 0) * c / (c^2 + eps)       (constant when a and c are constants; eps = 0 then)

eps = (OBSERVER_EPS * c_ref)^2 with c_ref the RMS of c on a fault-free reference drive, so the gain fades
out instead of dividing by zero where the residual equation does not see the state.

Discretisation for the step dt (the style of fdi_obs.h: exponential of the error pole, averaged input),
stable for every pole J < 0 however fast (a wheel's own slip dynamics reach a ~ -400 1/s, J dt ~ -4, where
forward Euler would diverge): with G(x, u) ~ J x + b(u) over one step,

    L1 = L(xh[k-1], u[k]),  G1 = F(xh[k-1], u[k]) + L1 e(xh[k-1], u[k]),  J = a + L1 c at (xh[k-1], u[k]),
    phi = expm1(J dt) / J   (dt when |J dt| < 1e-6)
    xh[k] = xh[k-1] + phi * (Gp + G1) / 2,   r[k] = e(xh[k], u[k])
    Gp for the next step = F(xh[k], u[k]) + L1 r[k]   (the gain of this step's prediction)

which is exact for a linear G with the input b averaged over the step. The gain and its Jacobian are
evaluated once per step, at the prediction: evaluating them again at xh[k] would change Gp only by
(L(xh[k]) - L1) r[k], a product of two small terms, at the cost of the Jacobian's second evaluation in every
step (the README's performance section has the measured difference). The on-line sensitivities d r / d f
are computed at xh[k-1] too, with that gain and Jacobian (`evaluate.sensitivity_estimate`).

At a restart (no prediction; L1 = L(xh[k], u[k])) xh = the state from its measurement outside the MSO set when
the model has one (`initial_estimate`; a fault there only moves the initial error, which decays with the error
pole inside the diagnoser's warm-up), else 0. That sensor is not among the generator's inputs (the test's
signals stay those of its MSO set, so the diagnoser does not check it): a non-finite value gives 0.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np
import sympy

from fdi_analysis.model import Model
from fdi_analysis.residuals.evaluate import VECTOR_MODULES, FilterDesign, in_domain, initial_values, node_signals
from fdi_analysis.residuals.generator import OBSERVER_EPS, OBSERVER_POLE_FACTOR, XHAT, Generator
from fdi_analysis.residuals.reasons import NotRealizableError, Reason, Rejection
from fdi_analysis.residuals.signals import nodes_in, raw
from fdi_analysis.residuals.solvability import Solution, Solver

DESIGN_CUTOFF_HZ = 1.0  # the table's filter design (FilterDesign, fdi_table_design_t)


def pole(cutoff_hz: float = DESIGN_CUTOFF_HZ) -> float:
    return OBSERVER_POLE_FACTOR * 2.0 * math.pi * cutoff_hz


def align_with_state(update: sympy.Expr, residual: sympy.Expr) -> tuple[sympy.Expr, sympy.Expr, int]:
    """Lift the nodes of the state update and of the residual to one common filter level (all inputs of the
    observer delayed alike, as the signals of a plain residual)."""
    nodes = nodes_in(update) | nodes_in(residual)
    level = max((n.level for n in nodes), default=0)
    sub = {n.symbol: n.at_level(level).symbol for n in nodes}
    return update.xreplace(sub), residual.xreplace(sub), level


def initial_estimate(model: Model, solver: Solver, state: str) -> sympy.Expr:
    """x from the model's measurement equations alone (raw samples), e.g. omega3 = omega3_m, vx = vx_m -
    d_y * psidot_m; 0 when the measurements do not determine x."""
    known_sub = {sympy.Symbol(k.name): raw(k.name) for k in model.knowns}
    value: dict[sympy.Symbol, sympy.Expr] = {}
    eqs = [e for e in model.equations if e.knowns and e.differential is None]
    progress = True
    while progress and sympy.Symbol(state) not in value:
        progress = False
        for e in eqs:
            todo = [u for u in e.unknowns if sympy.Symbol(u) not in value]
            if len(todo) != 1:
                continue
            sol = solver.solve(e, todo[0])
            if isinstance(sol, Solution) and not sol.coefficient.free_symbols:
                value[sympy.Symbol(todo[0])] = sol.expr.xreplace(known_sub).xreplace(value)
                progress = True
    return value.get(sympy.Symbol(state), sympy.Integer(0))


def d_dstate(expr: sympy.Expr) -> sympy.Expr:
    """d expr / d XHAT (every symbol of a generator expression is real: Abs -> sign, Max -> Heaviside)."""
    return sympy.diff(expr, XHAT)


def gain_expr(a: sympy.Expr, c: sympy.Expr, lam: float, eps: float) -> sympy.Expr:
    k = sympy.Float(lam) + a
    k = sympy.Float(max(float(k), 0.0)) if not k.free_symbols else sympy.Max(k, sympy.Integer(0))
    if not c.free_symbols:
        return sympy.Float(float(-k / c)) if not k.free_symbols else -k / c
    return -k * c / (c**2 + sympy.Float(eps))


@dataclass(frozen=True)
class ObserverReference:
    """Where the run-time gain of an observer generator takes its regularisation eps = (OBSERVER_EPS c_ref)^2
    from, c_ref being the RMS of the output sensitivity c = de/dx on a fault-free reference drive: the drive's
    measured signals (`signals`, c_ref is computed on them), or the c_ref values already computed, by the
    generator's equation set (space separated; the thresholds file's [observer] table)."""

    signals: Mapping[str, np.ndarray] | None = None
    c_ref: Mapping[str, float] = field(default_factory=dict)

    def sensitivity(self, g: Generator) -> float | None:
        """c_ref of generator `g`, or None when this reference has neither its value nor signals."""
        key = " ".join(g.equations)
        if key in self.c_ref:
            return float(self.c_ref[key])
        return reference_sensitivity(g, self.signals) if self.signals is not None else None


def round_sensitivity(c_ref: float) -> float:
    """c_ref to 3 significant digits: a design number that is the same on every machine (a drive's last bits
    depend on the CPU's floating-point path) and that the thresholds file holds exactly."""
    return float(f"{c_ref:.3g}")


def reference_sensitivity(g: Generator, signals: Mapping[str, np.ndarray]) -> float:
    """RMS of c = de/dx on fault-free reference signals, inside the operating domain and after the first
    quarter (at most 3 s), with x taken from its initial estimate (the measurement, fault-free here), rounded
    (`round_sensitivity`)."""
    assert g.observer is not None
    values = node_signals(g, signals, FilterDesign())
    syms = [n.symbol for n in g.nodes]
    xs = initial_values(g, signals)
    fn = sympy.lambdify([XHAT, *syms], g.observer.c, modules=VECTOR_MODULES)
    cv = np.asarray(fn(xs, *[values[n] for n in g.nodes]), dtype=float) * np.ones(len(xs))
    ok = in_domain(g, signals)
    ok[:min(300, len(ok) // 4)] = False
    if not ok.any():
        return 0.0
    return round_sensitivity(float(np.sqrt(np.mean(cv[ok] ** 2))))


def design_observer(g: Generator, reference: ObserverReference | None,
                    cutoff_hz: float = DESIGN_CUTOFF_HZ) -> Generator:
    """Fill in the pole, eps and the gain of a synthesised observer generator. A constant output sensitivity
    c needs no reference; otherwise `reference` gives c_ref (NotRealizableError NO_REFERENCE without it,
    NOT_OBSERVABLE when c vanishes on the reference drive)."""
    assert g.observer is not None
    o = g.observer
    lam = pole(cutoff_hz)
    eps = 0.0
    if o.c.free_symbols:
        c_ref = reference.sensitivity(g) if reference is not None else None
        if c_ref is None:
            raise NotRealizableError(Rejection(
                Reason.NO_REFERENCE, f"the observer gain of {g.name} ({o.state}) needs a reference drive: its "
                "output sensitivity varies (fdi-tune calibrate writes it to the thresholds file's [observer] table)",
                g.residual_equation, o.state))
        if not c_ref > 0.0:
            raise NotRealizableError(Rejection(
                Reason.NOT_OBSERVABLE, f"{o.state} not observable from the residual equation {g.residual_equation} "
                f"on the reference drive (d r / d {o.state} = 0 there)", g.residual_equation, o.state))
        eps = (OBSERVER_EPS * c_ref) ** 2
    return replace(g, observer=replace(o, gain=gain_expr(o.a, o.c, lam, eps), pole=lam, eps=eps))
