"""Which (equation, unknown) pairs a computation sequence may solve, and the solution.

An equation is solved for an unknown only when (a) the model does not list the unknown in the equation's
`not_solvable_for`, and (b) the residual lhs - rhs is linear in the unknown: d(res)/dx does not contain x.
(b) rejects every unknown that sits inside a non-invertible or multi-branch term (tyre law with sqrt and
Max/Abs, tanh/sign of a brake torque, products of the unknown with itself), so no branch is ever chosen
silently. The coefficient d(res)/dx may contain signals: the solution then divides by it, which
`causality` records and clears from the final residual (multiplying by the denominator).

An algebraic loop (k equations that share k unknowns, none of them with a single unknown left) is solved
as one block (`solve_block`) when the equations are jointly linear in the k unknowns, none of them is
marked `not_solvable_for` an unknown of the loop, and the determinant of the coefficient matrix (found
constant by probing where it is, e.g. cos^2 + sin^2 of a steering rotation -> 1) is not identically zero:
each unknown is then adj(J) (-b) / det(J) by Cramer's rule. A determinant that holds signals is a division
by a signal, as the coefficient of a single equation. Anything else (a tyre law in the loop, a singular
system, more than MAX_LOOP equations) is rejected with the reason, and `causality` tries another residual
equation.
"""

from __future__ import annotations

import random
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import sympy

from fdi_analysis.model import Equation, Model
from fdi_analysis.residuals.reasons import Reason, Rejection


@dataclass(frozen=True)
class Solution:
    expr: sympy.Expr  # the unknown, in the equation's other symbols (faults 0, parameters numeric)
    coefficient: sympy.Expr  # d(res)/dx; a non-constant one is a division by a signal


MAX_LOOP = 6  # largest algebraic loop solved as one block (equations); larger ones are rejected


@dataclass(frozen=True)
class BlockSolution:
    """An algebraic loop solved jointly: each unknown of `unknowns` as `solutions[k]` (with coefficient =
    the determinant of the loop's coefficient matrix, shared by all of them)."""

    equations: tuple[str, ...]
    unknowns: tuple[str, ...]
    solutions: tuple[Solution, ...]


def rate_symbol(fault: sympy.Symbol) -> sympy.Symbol:
    """The symbol of d/dt of a kept fault (`Solver(keep_faults=True)`)."""
    return sympy.Symbol(f"{fault}__rate", real=True)


class Solver:
    """Cached solutions of the equations of one model (parameters substituted, faults set to zero, or kept as
    symbols with `keep_faults`: the sequence then computes what the unknowns are under given fault sizes)."""

    def __init__(self, model: Model, keep_faults: bool = False) -> None:
        self.model = model
        self.params = {sympy.Symbol(k): sympy.Float(v) for k, v in model.parameter_values().items()}
        # kept faults are real symbols, as the signals (`Node.symbol`): real derivatives, no re/im terms
        self.fault_symbols = frozenset(sympy.Symbol(f.name, real=True) for f in model.faults)
        self.fault_zero: dict[sympy.Symbol, sympy.Expr] = {
            sympy.Symbol(f.name): (sympy.Symbol(f.name, real=True) if keep_faults else sympy.Integer(0))
            for f in model.faults}
        # with kept faults, d/dt of a fault is the symbol of its rate (zero for a step; a drift's rate), so that a
        # residual that sees a fault only through a derivative has a rate gain (`sensitivity.rate_gains`)
        self.fault_rates: dict[sympy.Symbol, sympy.Symbol] = (
            {s: rate_symbol(s) for s in self.fault_symbols} if keep_faults else {})
        self._residuals: dict[str, sympy.Expr] = {}
        self._cache: dict[tuple[str, str], Solution | Rejection] = {}
        self._rational: dict[tuple[str, str], bool] = {}
        self._blocks: dict[tuple[str, str], BlockSolution | Rejection] = {}
        self._loop_unknowns: dict[str, frozenset[str]] = {}

    def residual(self, eq: Equation) -> sympy.Expr:
        """lhs - rhs of an algebraic equation with parameters and faults substituted."""
        if eq.id not in self._residuals:
            res = eq.residual.xreplace(self.params).xreplace(self.fault_zero)
            self._residuals[eq.id] = sympy.expand_mul(res) if res.is_polynomial() else res
        return self._residuals[eq.id]

    def solve(self, eq: Equation, var: str) -> Solution | Rejection:
        """The solution, or the reason why `eq` is not solved for `var`."""
        key = (eq.id, var)
        if key not in self._cache:
            self._cache[key] = self._solve(eq, var)
        return self._cache[key]

    def solvable(self, eq: Equation, var: str) -> bool:
        return isinstance(self.solve(eq, var), Solution)

    def rational_in(self, eq: Equation, var: str) -> bool:
        """True when the equation is a rational function of `var` (a quotient in var can be cleared)."""
        key = (eq.id, var)
        if key not in self._rational:
            self._rational[key] = eq.differential is not None or (
                eq.lhs is not None and bool(self.residual(eq).is_rational_function(sympy.Symbol(var))))
        return self._rational[key]

    def linear_in(self, eq: Equation, var: str) -> bool:
        """True when `eq` may take part in an algebraic loop over `var`: usable, not marked
        not_solvable_for it, and linear in it."""
        return var in self.loop_unknowns(eq)

    def loop_unknowns(self, eq: Equation) -> frozenset[str]:
        """The unknowns `eq` may be solved for inside an algebraic loop (`linear_in`), cached per equation."""
        if eq.id not in self._loop_unknowns:
            ok: set[str] = set()
            if self._unusable(eq) is None:
                res = self.residual(eq)
                for u in eq.unknowns:
                    x = sympy.Symbol(u)
                    if u not in eq.not_solvable_for and not sympy.diff(res, x).has(x):
                        ok.add(u)
            self._loop_unknowns[eq.id] = frozenset(ok)
        return self._loop_unknowns[eq.id]

    def solve_block(self, eqs: Sequence[Equation], unknowns: Sequence[str]) -> BlockSolution | Rejection:
        """The joint solution of the algebraic loop `eqs` (k equations) for `unknowns` (k unknowns), or the
        reason why it is not solved (cached per loop)."""
        key = ("+".join(sorted(e.id for e in eqs)), "+".join(sorted(unknowns)))
        if key not in self._blocks:
            self._blocks[key] = self._solve_block(sorted(eqs, key=lambda e: e.id), sorted(unknowns))
        return self._blocks[key]

    def _solve_block(self, eqs: list[Equation], unknowns: list[str]) -> BlockSolution | Rejection:
        names = ", ".join(e.id for e in eqs)

        def loop(text: str, equation: str = "", variable: str = "") -> Rejection:
            return Rejection(Reason.ALGEBRAIC_LOOP, f"algebraic loop {names}{text}", equation or eqs[0].id, variable)

        if len(eqs) != len(unknowns):
            return loop(f" is not square ({len(eqs)} equations, {len(unknowns)} unknowns)")
        for e in eqs:
            why = self._unusable(e)
            if why is not None:
                return why
            marked = [u for u in unknowns if u in e.not_solvable_for and u in e.unknowns]
            if marked:
                return loop(f": {e.id} is marked not_solvable_for {marked[0]}", e.id, marked[0])
            nonlinear = [u for u in unknowns if u in e.unknowns and not self.linear_in(e, u)]
            if nonlinear:
                return loop(f": {e.id} is not linear in {nonlinear[0]} (non-invertible or multi-branch term)", e.id,
                            nonlinear[0])
        if len(eqs) > MAX_LOOP:
            return loop(f" has {len(eqs)} equations (more than {MAX_LOOP} are not solved)")
        xs = [sympy.Symbol(u) for u in unknowns]
        res = [self.residual(e) for e in eqs]
        jac = sympy.Matrix([[sympy.diff(r, x) for x in xs] for r in res])
        for i, e in enumerate(eqs):  # jointly linear: no coefficient holds an unknown of the loop
            for j, x in enumerate(xs):
                held = sorted(str(v) for v in jac[i, j].free_symbols & set(xs))
                if held:
                    return loop(f": {e.id} is not linear in {', '.join(unknowns)} jointly (its coefficient of {x} "
                                f"holds {', '.join(held)})", e.id, str(x))
        det = _determinant(jac)
        if det is None:
            return loop(f" divides by its determinant, which varies with "
                        f"{', '.join(sorted(map(str, jac.free_symbols))[:4])} through non-polynomial terms (its zeros "
                        "cannot be cleared)")
        if det == 0:
            return loop(f" is singular in {', '.join(unknowns)} (determinant identically 0)")
        if det.free_symbols and not det.is_polynomial(*det.free_symbols):
            return loop(f" divides by its determinant, not a polynomial in "
                        f"{', '.join(sorted(map(str, det.free_symbols))[:4])} (its zeros cannot be cleared)")
        rest = sympy.Matrix([r.xreplace({x: 0 for x in xs}) for r in res])
        num = jac.adjugate() * (-rest)
        sols = tuple(Solution(expr=sympy.expand(num[k]) / det, coefficient=det) for k in range(len(xs)))
        return BlockSolution(tuple(e.id for e in eqs), tuple(unknowns), sols)

    @staticmethod
    def _unusable(eq: Equation) -> Rejection | None:
        """Why an equation cannot be solved for anything (None when it can be tried)."""
        why = ""
        if eq.differential is not None:
            why = f"{eq.id} is a differential constraint"
        elif eq.derivatives:
            why = f"{eq.id} holds inline derivatives der(...), which the generator does not handle"
        elif eq.lhs is None:
            why = f"{eq.id} has no expression"
        return Rejection(Reason.UNUSABLE_EQUATION, why, eq.id) if why else None

    def _solve(self, eq: Equation, var: str) -> Solution | Rejection:
        why = self._unusable(eq)
        if why is not None:
            return why

        def no(text: str) -> Rejection:
            return Rejection(Reason.NOT_SOLVABLE, text, eq.id, var)

        if var in eq.not_solvable_for:
            return no(f"{eq.id} is marked not_solvable_for {var}")
        x = sympy.Symbol(var)
        res = self.residual(eq)
        coef = sympy.diff(res, x)
        if coef.has(x):
            return no(f"{eq.id} is not linear in {var} (non-invertible or multi-branch term)")
        if coef == 0:
            return no(f"{var} does not appear in {eq.id}")
        if coef.free_symbols and not coef.is_polynomial(*coef.free_symbols):
            return no(f"{eq.id} solved for {var} divides by {sympy.sstr(coef)[:60]}, not a polynomial in signals "
                      "(its zeros cannot be cleared)")
        rest = res.subs(x, 0)
        return Solution(expr=-rest / coef, coefficient=coef)


def _determinant(jac: sympy.Matrix, probes: int = 8, seed: int = 7) -> sympy.Expr | None:
    """det(jac) of a loop's coefficient matrix: 0 when it vanishes at `probes` random points (relative to
    the rows' norms), a number when it takes one value there (cos(d)^2 + sin(d)^2 -> 1 without a
    trigonometric simplification, which can take minutes), the symbolic determinant when every entry is a
    polynomial in its symbols, else None (a determinant that varies through non-polynomial terms, e.g. of a
    tyre law, whose zeros cannot be cleared). Deterministic: the probes come from a fixed seed."""
    syms = sorted(jac.free_symbols, key=str)
    rng = random.Random(seed)
    values: list[float] = []
    scales: list[float] = []
    for _ in range(probes if syms else 1):
        point = {x: sympy.Float(rng.gauss(0.0, 2.0)) for x in syms}
        try:
            num = np.array([[complex(v.xreplace(point).evalf()) for v in row] for row in jac.tolist()])
        except (TypeError, ValueError, ZeroDivisionError):
            continue
        if np.all(np.isfinite(num)) and np.max(np.abs(num.imag)) == 0.0:
            values.append(float(np.linalg.det(num.real)))
            scales.append(float(np.prod(np.linalg.norm(num.real, axis=1))))  # Hadamard's bound of |det|
    if values and len(values) == (probes if syms else 1):
        if all(abs(v) <= 1e-10 * sc for v, sc in zip(values, scales, strict=True)):
            return sympy.Integer(0)
        v0 = values[0]
        if all(abs(v - v0) <= 1e-9 * abs(v0) for v in values):
            near = round(v0)
            # 12 significant digits: the same number whatever the machine's LAPACK path
            return sympy.Integer(near) if abs(v0 - near) <= 1e-9 * abs(v0) else sympy.Float(float(f"{v0:.12g}"))
    if not all(v.is_polynomial(*syms) for v in jac):
        return None
    return sympy.expand(jac.det(method="berkowitz"))
