"""Terms of a residual filtered as a whole: the part without derivatives, computed from the raw signals.

A generator evaluates its residual over filtered signals, all at one filter level (`signals.align`). That is exact
for the terms linear in one signal (a filter is linear: F(c y) = c F(y)), but a nonlinear term of filtered signals is
not the filtered term: F(vx) F(psidot) differs from F(vx psidot) wherever both change, by about the product of
their rates times the filter's delay squared. In fault-free driving that error is model error the residual shows as
noise; in a spin (yaw rate and speed changing fast together) it makes a kinematic test that is blind to the fault
alarm (measured on the ROMO kinematic test MSO2: 0.07 m/s^2, its gate, from the product alone; 0.001 with the
product filtered as one signal).

So the terms of the residual that hold no derivative, are smooth (products, integer powers, tanh/sin/cos/exp: no
division, root, absolute value or switch, which raw noise near their singular point would bias) and are not linear
in a single signal are summed into one
derived signal, computed from the raw samples and filtered like a measured signal (`Composite`): the residual then
holds the exactly filtered sum. Terms with a derivative keep their filtered signals (a nonlinear term of a
derivative cannot be filtered from raw samples), and an observer generator keeps its form (its state estimate is
reconstructed from filtered signals, so its terms must stay on them).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy

from fdi_analysis.residuals.signals import Node, nodes_in

COMPOSITE_SUFFIX = "_terms"  # signal name of a generator's derived signal: <generator name>_terms
SMOOTH_FUNCTIONS = (sympy.tanh, sympy.sin, sympy.cos, sympy.exp)


@dataclass(frozen=True)
class Composite:
    """A derived signal: `expr` over raw samples (level-0 node symbols), filtered like a measured signal."""

    signal: str
    expr: sympy.Expr

    @property
    def sources(self) -> tuple[str, ...]:
        return tuple(sorted({n.signal for n in nodes_in(self.expr)}))


def composite_signal(generator: str) -> str:
    return f"{generator}{COMPOSITE_SUFFIX}"


def _smooth(term: sympy.Expr) -> bool:
    """No division, root, absolute value or switch: the term is smooth in its signals at the noise scale, so
    computing it from raw (noisy) samples does not amplify the noise or bias its mean."""
    for sub in sympy.preorder_traversal(term):
        if isinstance(sub, sympy.Pow) and not (sub.exp.is_Integer and sub.exp >= 0):
            return False
        if isinstance(sub, sympy.Function) and not isinstance(sub, SMOOTH_FUNCTIONS):
            return False
    return True


def _filtered_whole(term: sympy.Expr) -> bool:
    """A term to filter as a whole: signals without derivatives, smooth, not linear in a single signal."""
    nodes = nodes_in(term)
    if not nodes or any(n.order > 0 for n in nodes) or term.free_symbols - {n.symbol for n in nodes}:
        return False
    if not _smooth(term):
        return False
    if len(nodes) == 1:
        (n,) = nodes
        return bool(sympy.diff(term, n.symbol).free_symbols)
    return True


def whole_terms(expr: sympy.Expr, level: int, generator: str) -> tuple[sympy.Expr, Composite | None]:
    """`expr` (every node at `level`, no observer state) with its derivative-free nonlinear terms replaced by the
    filtered derived signal (level `level`) of generator `generator`, and that signal; (expr, None) when there is
    no such term or no filter (level 0)."""
    if level == 0:
        return expr, None
    whole: list[sympy.Expr] = []
    rest: list[sympy.Expr] = []
    for t in sympy.Add.make_args(expr):
        (whole if _filtered_whole(t) else rest).append(t)
    if not whole:
        return expr, None
    raw = sympy.Add(*whole)
    raw = raw.xreplace({n.symbol: Node(n.signal, 0, 0).symbol for n in nodes_in(raw)})
    signal = composite_signal(generator)
    return sympy.Add(*rest) + Node(signal, level, 0).symbol, Composite(signal, raw)
