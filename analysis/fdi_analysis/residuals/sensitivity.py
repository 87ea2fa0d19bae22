"""Fault sensitivity of a residual generator: d r / d f_j for every fault of its signature, analytically.

The faults are symbols of the model's equations. Run the generator's computation sequence once more with the
faults kept as symbols (`Solver(keep_faults=True)`): every unknown then becomes what it really is under fault
sizes f, and the residual equation evaluated on it, H(u, f), is zero on consistent data with the true f. The
generator evaluates H(u, 0), so to first order (Eriksson, Frisk, Krysander's fault-to-noise reasoning, for a
step fault held over the operating point)

    r = H(u, 0) ~ -dH/df_j (u, 0) f_j                      sensitivity  s_j = -dH/df_j at f = 0

with the residual cleared of divisions exactly as the generator clears it (same divisors, same powers), and
d/dt of a fault taken as 0 (a step of constant size), so a fault that reaches the residual only through a
filtered derivative has s_j = 0: the residual sees it only while it changes.

Such a fault still has a rate gain: with d/dt f_j kept as the symbol of its rate rho_j, a drift f_j = rho_j t
gives, once the filters have settled on the ramp (every node of a signal lags alike, and the static terms of f_j
cancel as they do for a step), the steady residual

    r ~ g_j rho_j                                          rate gain  g_j = -dH/d(rho_j) at f = 0, rho = 0

`rate_gains` lists the constant ones (a number at every operating point, e.g. |g| = 1 for a vx offset in
a_x = d vx / dt - psidot vy) of the generators without an observer. The residual of any shape of such a fault is g
times the derivative of the filtered fault, so the diagnoser adds up (|r| - noise) / |g| over the alarmed steps: how
far the fault must have moved (fdi_diag.h). A gain that varies with the operating point, or an observer's (its
estimate follows part of the ramp), is not listed: no bound, as before.

An observer generator (state estimate xh, update xh' = F + L e, residual r = e) absorbs part of a fault: with
a = dF/dx, c = de/dx, J = a + L c (the error pole) and F_f, e_f the faults' direct effect on the update and
on the residual, the error settles where x~' = J x~ - (F_f + L e_f) f = 0, which gives

    s_j = (c F_f - a e_f) / J                               (J floored at -J_FLOOR: a slower pole means the
                                                             steady state is never reached on the vehicle)

All expressions are over the generator's node symbols (and XHAT), so the C generator computes them from the
same common subexpressions as the residual, and `evaluate` computes them along any drive. `fault_to_noise`
turns them into the fault-to-noise ratio |s_j| size_j / sigma of a test at each operating point.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import sympy

from fdi_analysis.model import Model
from fdi_analysis.residuals.causality import (
    Plan,
    cleared,
    division_degrees,
    residual_value,
    sequence_values,
)
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.signals import nodes_in
from fdi_analysis.residuals.solvability import Solver, rate_symbol

J_FLOOR = 0.1  # [1/s]: the observer's error pole taken as at most -J_FLOOR (time constant 10 s)


def _at_level(expr: sympy.Expr, level: int) -> sympy.Expr | None:
    """`expr` with every node lifted to `level` (as the generator lifts its own), or None when a node lies
    above it (the sensitivity would need a filter the generator does not have)."""
    nodes = nodes_in(expr)
    if any(n.level > level for n in nodes):
        return None
    return expr.xreplace({n.symbol: n.at_level(level).symbol for n in nodes})


def _zero(faults: tuple[sympy.Symbol, ...]) -> dict[sympy.Symbol, sympy.Expr]:
    """No fault: every size and every rate zero."""
    return {**dict.fromkeys(faults, sympy.Integer(0)), **dict.fromkeys(map(rate_symbol, faults), sympy.Integer(0))}


def _plan_of(g: Generator) -> Plan:
    return Plan(g.residual_equation, g.steps, g.level, 0, 0, g.observer.state if g.observer is not None else "")


@dataclass(frozen=True)
class FaultyResidual:
    """The generator's residual computed with the faults kept (`H(u, f)`, cleared of divisions as the generator
    clears its own, nodes at the generator's level) and, for an observer generator, its state update F(u, f)."""

    faults: tuple[sympy.Symbol, ...]
    residual: sympy.Expr
    update: sympy.Expr | None


def faulty_residual(model: Model, g: Generator, solver: Solver | None = None,
                    rates: bool = False) -> FaultyResidual | None:
    """H(u, f) of `g` (None when a node lies above the generator's filter level); with `rates` also over the
    faults' rates (`rate_symbol`; else they are 0: steps of constant size). `solver` must keep the faults
    (Solver(model, keep_faults=True))."""
    solver = solver or Solver(model, keep_faults=True)
    p = _plan_of(g)
    faults = tuple(sympy.Symbol(f, real=True) for f in g.faults)
    zero = _zero(faults)
    seq = sequence_values(model, solver, p)
    expr = residual_value(model, solver, p, seq)
    # A divisor that is a number at f = 0 (a kept symbol in a coefficient: the perturbation of a parameter, e.g.
    # FL = .../(R0 + dR)) is no division by a signal in the generator, which divides by the number: keep it
    # a division here too, or the residual would come out scaled by it (and its derivative with it).
    inverses = {k: v for k, v in seq.inverses.items() if v.xreplace(zero).free_symbols}
    numbers = {k: 1 / v for k, v in seq.inverses.items() if k not in inverses}
    expr = expr.xreplace(numbers)
    if inverses:
        nominal = {k: v.xreplace(zero) for k, v in inverses.items()}
        expr = cleared(expr, inverses, division_degrees(p, expr.xreplace(zero), nominal))
    steps = {} if rates else dict.fromkeys(map(rate_symbol, faults), sympy.Integer(0))
    lifted = _at_level(expr.xreplace(steps), g.level)
    update = None
    if g.observer is not None:
        pair = model.equation(g.observer.equation).differential
        assert pair is not None
        update = _at_level(seq.value[sympy.Symbol(pair[0])].xreplace(numbers).xreplace(steps), g.level)
        if update is None:
            return None
    return FaultyResidual(faults, lifted, update) if lifted is not None else None


def _slope(e: sympy.Expr, f: sympy.Symbol, zero: dict[sympy.Symbol, sympy.Expr], step: float | None) -> sympy.Expr:
    """d e / d f at f = 0, or with a finite `step` the secant (e(step) - e(0)) / step (the other faults at 0)."""
    if step is None:
        return sympy.diff(e, f).xreplace(zero)
    rest = {k: v for k, v in zero.items() if k != f}
    return (e.xreplace({**rest, f: sympy.Float(step)}) - e.xreplace(zero)) / sympy.Float(step)


def fault_sensitivities(model: Model, g: Generator, solver: Solver | None = None,
                        secant: dict[str, float] | None = None) -> tuple[tuple[str, sympy.Expr], ...]:
    """(fault, d r / d f) for the faults of the signature of `g` whose steady-state sensitivity is not
    identically zero, in the signature's order (see the module doc); for the faults of `secant` the secant to the
    size given there instead of the derivative at 0 (the exact change of r over that step, per unit: what a
    quantity far from linear over its range needs)."""
    h = faulty_residual(model, g, solver)
    if h is None:
        return ()
    zero = _zero(h.faults)
    steps = secant or {}
    out: list[tuple[str, sympy.Expr]] = []
    if h.update is None:
        for f in h.faults:
            s = -_slope(h.residual, f, zero, steps.get(str(f)))
            if s != 0:
                out.append((str(f), s))
        return tuple(out)
    o = g.observer
    assert o is not None
    pole = sympy.Min(o.a + o.gain * o.c, sympy.Float(-J_FLOOR))
    for f in h.faults:
        e_f = _slope(h.residual, f, zero, steps.get(str(f)))
        f_f = _slope(h.update, f, zero, steps.get(str(f)))
        if e_f == 0 and f_f == 0:
            continue
        out.append((str(f), (o.c * f_f - o.a * e_f) / pole))
    return tuple(out)


def rate_gains(model: Model, g: Generator, solver: Solver | None = None) -> tuple[tuple[str, float], ...]:
    """(fault, g_j) for the faults of the signature of `g` without a steady-state sensitivity whose rate gain
    is a nonzero constant, in the signature's order (see the module doc); () for an observer generator."""
    if g.observer is not None:
        return ()
    h = faulty_residual(model, g, solver, rates=True)
    if h is None:
        return ()
    zero = _zero(h.faults)
    out: list[tuple[str, float]] = []
    for f in h.faults:
        if sympy.diff(h.residual, f).xreplace(zero) != 0:
            continue  # a steady-state sensitivity: the size is bounded directly
        gain = sympy.simplify(-sympy.diff(h.residual, rate_symbol(f)).xreplace(zero))
        if gain != 0 and not gain.free_symbols:
            out.append((str(f), float(gain)))
    return tuple(out)


def with_sensitivities(model: Model, g: Generator, solver: Solver | None = None) -> Generator:
    """`g` with its `sensitivities` and `rate_gains` filled in (`fault_sensitivities`, `rate_gains`)."""
    solver = solver or Solver(model, keep_faults=True)
    return replace(g, sensitivities=fault_sensitivities(model, g, solver), rate_gains=rate_gains(model, g, solver))
