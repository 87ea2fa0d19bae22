"""Parsing of model equations into sympy, with a closed namespace.

An equation is written ``lhs = rhs`` (or a bare expression meaning ``expr = 0``). Only declared names and
the functions in `FUNCTIONS` may appear; anything else is an error that names the symbol. ``der(x)`` is
the time derivative of the unknown ``x`` written inline (a "mixed" equation); structurally it is an
incidence of ``x``.
"""

from __future__ import annotations

import re
from collections.abc import Mapping

import sympy
from sympy.parsing.sympy_parser import parse_expr, standard_transformations

from fdi_analysis.errors import FdiError


class der(sympy.Function):  # type: ignore[misc]  # noqa: N801 - the model language spells it der(x)
    """Time derivative of an unknown, written inline in an equation: ``der(x)`` = dx/dt."""

    nargs = 1


FUNCTIONS: dict[str, object] = {
    "sin": sympy.sin,
    "cos": sympy.cos,
    "tan": sympy.tan,
    "asin": sympy.asin,
    "acos": sympy.acos,
    "atan": sympy.atan,
    "atan2": sympy.atan2,
    "sinh": sympy.sinh,
    "cosh": sympy.cosh,
    "tanh": sympy.tanh,
    "exp": sympy.exp,
    "log": sympy.log,
    "sqrt": sympy.sqrt,
    "abs": sympy.Abs,
    "Abs": sympy.Abs,
    "sign": sympy.sign,
    "max": sympy.Max,
    "Max": sympy.Max,
    "min": sympy.Min,
    "Min": sympy.Min,
    "der": der,
    "pi": sympy.pi,
}

# Names parse_expr's transformations may emit; nothing else from sympy is visible to a model.
_PARSER_GLOBALS: dict[str, object] = {
    "Integer": sympy.Integer,
    "Float": sympy.Float,
    "Rational": sympy.Rational,
    "Symbol": sympy.Symbol,
    "Function": sympy.Function,
}

_EQ_SPLIT = re.compile(r"(?<![<>=!])=(?!=)")


class ExpressionError(FdiError, ValueError):
    """An expression that cannot be parsed; `symbol` names the offending name when there is one."""

    def __init__(self, message: str, symbol: str | None = None) -> None:
        super().__init__(message)
        self.symbol = symbol


def parse_equation(text: str, symbols: Mapping[str, sympy.Symbol]) -> tuple[sympy.Expr, sympy.Expr]:
    """Parse ``lhs = rhs`` into two sympy expressions over the declared `symbols`."""
    parts = _EQ_SPLIT.split(text)
    if len(parts) > 2:
        raise ExpressionError(f"more than one '=' in {text!r}")
    if len(parts) == 1:
        lhs_txt, rhs_txt = parts[0], "0"
    else:
        lhs_txt, rhs_txt = parts
    if not lhs_txt.strip() or not rhs_txt.strip():
        raise ExpressionError(f"empty side of '=' in {text!r}")
    return parse_side(lhs_txt, symbols), parse_side(rhs_txt, symbols)


def parse_side(text: str, symbols: Mapping[str, sympy.Symbol]) -> sympy.Expr:
    local: dict[str, object] = dict(FUNCTIONS)
    local.update(symbols)
    try:
        expr = parse_expr(
            text,
            local_dict=local,
            global_dict=dict(_PARSER_GLOBALS),
            transformations=standard_transformations,
            evaluate=True,
        )
    except (SyntaxError, TypeError, ValueError, AttributeError, NameError) as exc:
        raise ExpressionError(f"cannot parse {text.strip()!r}: {exc}") from exc
    if not isinstance(expr, sympy.Expr):
        raise ExpressionError(f"{text.strip()!r} is not an arithmetic expression")
    for s in sorted(expr.free_symbols, key=str):
        if str(s) not in symbols:
            raise ExpressionError(f"undeclared symbol {str(s)!r} in {text.strip()!r}", symbol=str(s))
    for f in expr.atoms(sympy.Function):
        if isinstance(f, sympy.core.function.AppliedUndef) and not isinstance(f, der):
            name = type(f).__name__
            raise ExpressionError(f"unknown function {name!r} in {text.strip()!r}", symbol=name)
    for d in expr.atoms(der):
        (arg,) = d.args
        if not isinstance(arg, sympy.Symbol):
            raise ExpressionError(f"der() takes a single variable, got der({arg}) in {text.strip()!r}")
    return expr


def derivative_symbols(expr: sympy.Expr) -> set[str]:
    """Names of the variables that appear as der(x) in `expr`."""
    return {str(d.args[0]) for d in expr.atoms(der)}
