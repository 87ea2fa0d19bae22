"""sympy expression -> MISRA-style C99 float expression (every binary operation parenthesised, float
literals with an f suffix, integer powers as products and half-integer powers as products with one square root,
single-precision math functions; Max/Min, the derivatives of Max and Abs, tanh, sin and cos through the helpers
of fw/include/fdi_gen_impl.h, no library call)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import sympy

from fdi_analysis.errors import FdiError

MAX_PRODUCT = 8  # integer powers up to this exponent become products (beyond: powf)
_FUNCS = {sympy.sin: "fdi_gen_sin", sympy.cos: "fdi_gen_cos", sympy.tanh: "fdi_gen_tanh", sympy.Abs: "fabsf",
          sympy.exp: "expf", sympy.tan: "tanf", sympy.atan: "atanf"}


class CExprError(FdiError, ValueError):
    """An expression with a construct the C emitter does not support."""


def c_float(x: float) -> str:
    """The C `float` literal of x: the shortest decimal text that reads back as the same float32 value (what
    the compiler makes of any longer text), so the generated C does not depend on the last bits of a double
    computed on this machine. CExprError when x is not finite as a float32."""
    f = np.float32(x)
    if not np.isfinite(f):
        raise CExprError(f"{x!r} is not a finite C float")
    if f == 0.0 or 1e-4 <= abs(f) < 1e7:
        text = np.format_float_positional(f, unique=True, trim="0")
    else:
        text = np.format_float_scientific(f, unique=True, trim="0")
    return text + "f"


def to_c(e: sympy.Basic, name: Callable[[sympy.Symbol], str]) -> str:
    """C text of `e`; `name` maps each symbol to its C identifier or expression."""
    if isinstance(e, sympy.Symbol):
        return str(name(e))
    if e.is_Number:
        return c_float(float(e))
    if isinstance(e, sympy.Add):
        args = sorted(e.args, key=sympy.default_sort_key)
        return "(" + " + ".join(to_c(a, name) for a in args) + ")"
    if isinstance(e, sympy.Mul):
        args = sorted(e.args, key=sympy.default_sort_key)
        if args[0] == -1:
            return "(-" + to_c(sympy.Mul(*args[1:]), name) + ")"
        return "(" + " * ".join(to_c(a, name) for a in args) + ")"
    if isinstance(e, sympy.Pow):
        base, ex = e.args
        b = to_c(base, name)
        twice = 2 * ex
        if twice.is_Integer and 1 <= abs(int(twice)) <= 2 * MAX_PRODUCT:
            n, half = divmod(abs(int(twice)), 2)  # |ex| = n + half / 2
            factors = [b] * n + ([f"sqrtf({b})"] if half else [])
            prod = factors[0] if len(factors) == 1 else "(" + " * ".join(factors) + ")"
            return prod if twice > 0 else f"(1.0f / {prod})" if prod.startswith("(") else f"(1.0f / ({prod}))"
        return f"powf({b}, {to_c(ex, name)})"
    if isinstance(e, (sympy.Max, sympy.Min)):
        fn = "fdi_gen_max" if isinstance(e, sympy.Max) else "fdi_gen_min"
        args = [to_c(a, name) for a in sorted(e.args, key=sympy.default_sort_key)]
        out: str = args[-1]
        for a in reversed(args[:-1]):
            out = f"{fn}({a}, {out})"
        return out
    if isinstance(e, sympy.Heaviside):  # derivative of Max: 1 for x > 0, else 0 (the value at 0 is immaterial)
        return f"fdi_gen_heaviside({to_c(e.args[0], name)})"
    if isinstance(e, sympy.sign):
        return f"fdi_gen_sign({to_c(e.args[0], name)})"
    for f, cname in _FUNCS.items():
        if isinstance(e, f):
            return f"{cname}({to_c(e.args[0], name)})"
    raise CExprError(f"no C translation for {type(e).__name__}: {sympy.sstr(e)[:80]}")
