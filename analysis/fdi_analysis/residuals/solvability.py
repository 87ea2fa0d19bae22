"""Which (equation, unknown) pairs a computation sequence may solve, and the solution.

An equation is solved for an unknown only when (a) the model does not list the unknown in the equation's
`not_solvable_for`, and (b) the residual lhs - rhs is linear in the unknown: d(res)/dx does not contain x.
(b) rejects every unknown that sits inside a non-invertible or multi-branch term (tyre law with sqrt and
Max/Abs, tanh/sign of a brake torque, products of the unknown with itself), so no branch is ever chosen
silently. The coefficient d(res)/dx may contain signals: the solution then divides by it, which
`causality` records and clears from the final residual (multiplying by the denominator).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy

from fdi_analysis.model import Equation, Model


@dataclass(frozen=True)
class Solution:
    expr: sympy.Expr  # the unknown, in the equation's other symbols (faults 0, parameters numeric)
    coefficient: sympy.Expr  # d(res)/dx; a non-constant one is a division by a signal


class Solver:
    """Cached solutions of the equations of one model (parameters substituted, faults set to zero)."""

    def __init__(self, model: Model) -> None:
        self.model = model
        self.params = {sympy.Symbol(k): sympy.Float(v) for k, v in model.parameter_values().items()}
        self.fault_zero = {sympy.Symbol(f.name): sympy.Integer(0) for f in model.faults}
        self._residuals: dict[str, sympy.Expr] = {}
        self._cache: dict[tuple[str, str], Solution | str] = {}

    def residual(self, eq: Equation) -> sympy.Expr:
        """lhs - rhs of an algebraic equation with parameters and faults substituted."""
        if eq.id not in self._residuals:
            res = eq.residual.xreplace(self.params).xreplace(self.fault_zero)
            self._residuals[eq.id] = sympy.expand_mul(res) if res.is_polynomial() else res
        return self._residuals[eq.id]

    def solve(self, eq: Equation, var: str) -> Solution | str:
        """The solution, or the reason why `eq` is not solved for `var`."""
        key = (eq.id, var)
        if key not in self._cache:
            self._cache[key] = self._solve(eq, var)
        return self._cache[key]

    def solvable(self, eq: Equation, var: str) -> bool:
        return isinstance(self.solve(eq, var), Solution)

    def rational_in(self, eq: Equation, var: str) -> bool:
        """True when the equation is a rational function of `var` (a quotient in var can be cleared)."""
        key = (eq.id, "rational:" + var)
        if key not in self._cache:
            ok = eq.differential is not None or (
                eq.lhs is not None and self.residual(eq).is_rational_function(sympy.Symbol(var)))
            self._cache[key] = Solution(sympy.Integer(0), sympy.Integer(1)) if ok else "not rational"
        return isinstance(self._cache[key], Solution)

    def _solve(self, eq: Equation, var: str) -> Solution | str:
        if eq.differential is not None:
            return f"{eq.id} is a differential constraint"
        if eq.derivatives:
            return f"{eq.id} holds inline derivatives der(...), which the generator does not handle"
        if var in eq.not_solvable_for:
            return f"{eq.id} is marked not_solvable_for {var}"
        if eq.lhs is None:
            return f"{eq.id} has no expression"
        x = sympy.Symbol(var)
        res = self.residual(eq)
        coef = sympy.diff(res, x)
        if coef.has(x):
            return f"{eq.id} is not linear in {var} (non-invertible or multi-branch term)"
        if coef == 0:
            return f"{var} does not appear in {eq.id}"
        if coef.free_symbols and not coef.is_polynomial(*coef.free_symbols):
            return (f"{eq.id} solved for {var} divides by {sympy.sstr(coef)[:60]}, not a polynomial in signals "
                    "(its zeros cannot be cleared)")
        rest = res.subs(x, 0)
        return Solution(expr=-rest / coef, coefficient=coef)
