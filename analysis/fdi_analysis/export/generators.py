"""Emit the residual generators of a selection as one MISRA-style C file for fw/ (fw/generated/).

Per generator a static function that runs its filter bank (fdi_svf instances held in the caller's fdi_gen_t)
and evaluates the residual (common subexpressions shared); fdi_gen_generated_step() and
fdi_gen_generated_inputs() (declared in fdi_gen.h) dispatch by generator slot with a switch, so the
diagnoser runs a generated generator as table kind FDI_GEN_GENERATED_1 + slot. Deterministic output.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import sympy

from fdi_analysis.export.c_expr import c_float, to_c
from fdi_analysis.residuals.generator import DOMAIN_SIGNAL, XHAT, Generator
from fdi_analysis.residuals.signals import Node, node_of

MAX_FILTERS = 16  # FDI_GEN_MAX_FILTERS of fw/include/fdi_gen.h
MAX_GENERATED = 16  # FDI_GEN_GENERATED_1 .. FDI_GEN_GENERATED_16 of fw/include/fdi_table.h


class EmitError(ValueError):
    """A generator that does not fit the firmware's limits."""


def kind_name(slot: int) -> str:
    return f"FDI_GEN_GENERATED_{slot + 1}"


def _signal_macro(known: str) -> str:
    return "FDI_SIGM_" + known.upper()


def inputs(g: Generator) -> list[str]:
    """Measured signals the C generator reads: the residual's plus the operating-domain signal."""
    extra = [DOMAIN_SIGNAL] if g.min_speed > 0.0 and DOMAIN_SIGNAL not in g.knowns else []
    return [*g.knowns, *extra]


def _node_c(g: Generator, n: Node) -> str:
    if n.level == 0:
        return f"in->{n.signal}"
    src = n.source()
    assert src is not None
    k = g.filters.index(src)
    return f"o{k}.{'y' if n.order == src.order else 'dy'}"


def _function(g: Generator, slot: int) -> str:
    if len(g.filters) > MAX_FILTERS:
        raise EmitError(f"{g.name}: {len(g.filters)} filters, the firmware holds {MAX_FILTERS}")
    lines = [f"/* {g.name}: {' '.join(g.equations)}", f" * {g.causality()}", " */",
             f"static fdi_status_t gen_{slot + 1}(fdi_gen_t *g, const fdi_gen_param_t *par, "
             "const fdi_inputs_t *in, bool reset, float *r)", "{"]
    for k in range(len(g.filters)):
        lines.append(f"    fdi_svf_out_t o{k} = {{0.0f, 0.0f}};")
    lines.append("    fdi_status_t st = FDI_OK;")
    for k, f in enumerate(g.filters):
        step = f"fdi_gen_filter_step(g, par, {k}U, {_node_c(g, f)}, reset, &o{k})"
        lines.append(f"    st = fdi_gen_status_worst(st, {step});")
    if g.observer is None:
        lines.append("    {")
        lines += _block(g, [("value", g.expr)], "        ")
        lines.append("        st = fdi_gen_finish(st, value, reset, r);")
        lines.append("    }")
    else:
        lines += _observer_block(g)
    lines.append("    return st;")
    lines.append("}")
    return "\n".join(lines)


def _names(g: Generator, tmp: set[str]) -> Callable[[sympy.Symbol], str]:
    def name(s: sympy.Symbol) -> str:
        if s == XHAT:
            return "xh"
        if s == _XPREV:
            return "xp"
        return str(s) if str(s) in tmp else _node_c(g, node_of(s))

    return name


def _block(g: Generator, outputs: list[tuple[str, sympy.Expr]], indent: str) -> list[str]:
    """`const float <name> = <expr>;` for each output, common subexpressions shared (XHAT is `xh`)."""
    subs, red = sympy.cse([e for _, e in outputs], symbols=sympy.numbered_symbols("t"), order="canonical")
    name = _names(g, {str(s) for s, _ in subs})
    lines = [f"{indent}const float {s} = {to_c(e, name)};" for s, e in subs]
    lines += [f"{indent}const float {n} = {to_c(e, name)};" for (n, _), e in zip(outputs, red, strict=True)]
    return lines


_XPREV = sympy.Symbol("xprev")  # the previous estimate in the prediction's expressions


def _observer_cse(g: Generator, predict: list[tuple[str, sympy.Expr]], at_new: list[tuple[str, sympy.Expr]]
                  ) -> tuple[list[str], list[str], list[str]]:
    """One common-subexpression pass over the prediction (at the previous estimate xp) and the outputs at the
    new estimate xh, so that what depends on neither (the filtered signals' terms) is computed once per step:
    (shared lines, prediction lines, lines at the new estimate)."""
    exprs = [e.xreplace({XHAT: _XPREV}) for _, e in predict] + [e for _, e in at_new]
    subs, red = sympy.cse(exprs, symbols=sympy.numbered_symbols("t"), order="canonical")
    name = _names(g, {str(s) for s, _ in subs})
    uses: dict[sympy.Symbol, set[sympy.Symbol]] = {}
    shared: list[str] = []
    before: list[str] = []
    after: list[str] = []
    for s, e in subs:
        deps = {v for v in e.free_symbols if v in (_XPREV, XHAT)}
        for v in e.free_symbols:
            deps |= uses.get(v, set())
        uses[s] = deps
        line = f"const float {s} = {to_c(e, name)};"
        (after if XHAT in uses[s] else before if _XPREV in uses[s] else shared).append(line)
    outs = [n for n, _ in predict] + [n for n, _ in at_new]
    lines = [f"const float {n} = {to_c(e, name)};" for n, e in zip(outs, red, strict=True)]
    return shared, before + lines[: len(predict)], after + lines[len(predict):]


def _observer_block(g: Generator) -> list[str]:
    """The observer step of fdi_analysis.residuals.observer: predict xh from the previous estimate (state
    update plus output injection, exponential of the error pole, input averaged), then the residual and
    the next step's input at the new estimate."""
    o = g.observer
    assert o is not None

    def raw_name(s: sympy.Symbol) -> str:
        return _node_c(g, node_of(s))

    if o.initial.free_symbols:
        # the state's sensor is outside the MSO set (not in the input mask, not checked by the diagnoser):
        # used only when finite, else 0 (an error of the reset value decays with the error pole)
        x0 = to_c(o.initial, raw_name)
        reset = [f"            const float x0 = {x0}; /* {o.state} from its sensor outside the MSO set */",
                 "            xh = fdi_float_is_finite(x0) ? x0 : 0.0f;"]
    else:
        reset = [f"            xh = {c_float(float(o.initial))};"]
    shared, predict, at_new = _observer_cse(
        g, [("f", o.update), ("l", o.gain), ("a", o.a), ("c", o.c), ("e", g.expr)],
        [("f", o.update), ("l", o.gain), ("value", g.expr)])
    lines = ["    {", *[f"        {x}" for x in shared], "        float xh = 0.0f;", "        if (reset)", "        {",
             *reset, "        }", "        else", "        {", "            const float xp = g->obs.xh;"]
    lines += [f"            {x}" for x in predict]
    lines += ["            xh = fdi_gen_obs_predict(g, par, f + (l * e), a + (l * c));", "        }", "        {"]
    lines += [f"            {x}" for x in at_new]
    lines += ["            st = fdi_gen_status_worst(st, fdi_gen_obs_store(g, xh, f + (l * value)));",
              "            st = fdi_gen_finish(st, value, reset, r);", "        }", "    }"]
    return lines


def render(generators: Sequence[Generator], name: str, command: str) -> tuple[str, str]:
    """Header and source text of the generator file `name` (e.g. "fdi_romo_generators")."""
    if not 0 < len(generators) <= MAX_GENERATED:
        raise EmitError(f"{len(generators)} generators; the firmware holds 1..{MAX_GENERATED}")
    banner = f"/* Generated by `{command}`. Do not edit: regenerate instead. */"
    guard = name.upper() + "_H"
    listing = "\n".join(f" *   {kind_name(k)}  {g.name}: {g.causality()}" for k, g in enumerate(generators))
    header = f"""{banner}
/*
 * {name}: residual generators synthesised from the selected MSO sets (fdi_analysis.residuals).
 * Run through fdi_gen (kind FDI_GEN_GENERATED_<n>): fdi_gen_generated_step(), fdi_gen_generated_inputs().
{listing}
 */
#ifndef {guard}
#define {guard}

/* {len(generators)} generators, slots 0..{len(generators) - 1}; the functions are declared in fdi_gen.h. */

#endif /* {guard} */
"""
    funcs = "\n\n".join(_function(g, k) for k, g in enumerate(generators))
    step_cases = "\n".join(
        f"    case {k}U:\n        st = gen_{k + 1}(self, par, in, reset, r);\n        break;"
        for k in range(len(generators)))
    input_cases = "\n".join(
        f"    case {k}U:\n        m = {' | '.join(_signal_macro(s) for s in inputs(g))};\n        break;"
        for k, g in enumerate(generators))
    domain_cases = "\n".join(
        f"    case {k}U: /* {g.name}: {g.domain()} */\n"
        f"        ok = fabsf(in->{DOMAIN_SIGNAL}) >= {c_float(g.min_speed)};\n        break;"
        for k, g in enumerate(generators) if g.min_speed > 0.0)
    if domain_cases:
        domain_body = f"""    bool ok;
    switch (slot)
    {{
{domain_cases}
    default:
        ok = true;
        break;
    }}
    return ok;"""
    else:
        domain_body = "    (void)slot;\n    (void)in;\n    return true;"
    domain_fn = f"""bool fdi_gen_generated_in_domain(uint32_t slot, const fdi_inputs_t *in)
{{
{domain_body}
}}
"""
    source = f"""{banner}
#include "{name}.h"

#include <math.h>
#include <stdbool.h>
#include <stdint.h>

#include "fdi_float.h"
#include "fdi_gen.h"
#include "fdi_gen_internal.h"
#include "fdi_signals.h"
#include "fdi_svf.h"

{funcs}

fdi_status_t fdi_gen_generated_step(uint32_t slot, fdi_gen_t *self, const fdi_gen_param_t *par,
                                    const fdi_inputs_t *in, bool reset, float *r)
{{
    fdi_status_t st;
    switch (slot)
    {{
{step_cases}
    default:
        st = FDI_BAD_ARG;
        break;
    }}
    return st;
}}

uint32_t fdi_gen_generated_inputs(uint32_t slot)
{{
    uint32_t m;
    switch (slot)
    {{
{input_cases}
    default:
        m = 0U;
        break;
    }}
    return m;
}}

{domain_fn}"""
    return header, source
