"""The residual generators of a selection as MISRA-style C of a vehicle target (``fdi_<vehicle>_generators.h/.c``).

Per generator a static step function that runs its filter bank (fdi_svf instances held in the caller's fdi_gen_t)
and evaluates the residual (common subexpressions shared), on request also its fault sensitivities d r / d f_j
(`Generator.sensitivities`) from the same common subexpressions, an operating-domain function when it has one,
and a descriptor (fw/include/fdi_gen.h) in the array ``fdi_<vehicle>_generators[]`` that the table's tests point
to. What goes into the file is computed first (`generators_file`: the C lines of every body from sympy), then
rendered from the named templates below. Deterministic output.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from string import Template

import sympy

from fdi_analysis.export.c_expr import c_float, to_c
from fdi_analysis.export.c_names import VehicleNames
from fdi_analysis.export.c_text import comment_text
from fdi_analysis.residuals.generator import DOMAIN_SIGNAL, XHAT, Generator
from fdi_analysis.residuals.signals import Node, node_of

MAX_FILTERS = 16  # FDI_GEN_MAX_FILTERS of fw/include/fdi_gen.h
MAX_GENERATORS = 32  # FDI_TABLE_MAX_TESTS of fw/include/fdi_table.h


class EmitError(ValueError):
    """A generator that does not fit the firmware's limits."""


# ------------------------------------------------------------------------------------------ templates
HEADER_FMT = Template("""\
${banner}
/*
 * ${base}.h - residual generators of vehicle ${vehicle}, synthesised from the selected MSO sets
 * (fdi_analysis.residuals): one descriptor (fdi_gen.h) per generator, ${base}[k] for test k of the table.
${listing}
 */
#ifndef ${guard}
#define ${guard}

#include "fdi_gen.h"

/* ${n_sens} sensitivities in all: a diagnoser computing them needs FDI_DIAG_MAX_SENS >= ${n_sens} */
#define ${count_macro} ${count}U

extern const fdi_gen_desc_t ${base}[${count_macro}];

#endif /* ${guard} */
""")

LISTING_FMT = Template(" *   ${base}[${slot}]  ${name}: ${causality}")

SOURCE_FMT = Template("""\
${banner}
#include "${base}.h"

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "fdi_float.h"
#include "fdi_gen_impl.h"
#include "fdi_static_assert.h"
#include "fdi_svf.h"
#include "${signals}.h"

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(${max_filters}U <= FDI_GEN_MAX_FILTERS, fdi_sa_${vehicle}_generator_filters);

${functions}

/* name, step, domain, signals read, sensitivities (bit j = fault j, ascending), filters, observer states */
const fdi_gen_desc_t ${base}[${count_macro}] = {
${descriptors}
};
""")

FUNCTION_FMT = Template("""\
/* ${name}: ${equations}
 * ${causality}
 */
static fdi_status_t ${function}(fdi_gen_t *g, const fdi_gen_param_t *par, const fdi_frame_t *in, bool reset, float *r,
${pad}float *sens)
{
${statements}
    return st;
}""")

OUTPUT_FMT = Template("    fdi_svf_out_t o${k} = {0.0f, 0.0f};")
FILTER_FMT = Template("    st = fdi_gen_status_worst(st, fdi_gen_filter_step(g, par, ${k}U, ${input}, reset, &o${k}));")

PLAIN_BODY_FMT = Template("""\
    {
${lines}
    }""")
FINISH = "st = fdi_gen_finish(st, value, reset, r);"
STORE = "st = fdi_gen_status_worst(st, fdi_gen_obs_store(g, xh, f + (l * value)));"

OBSERVER_BODY_FMT = Template("""\
    {
${shared}float xh = 0.0f;
        if (reset)
        {
${reset}
        }
        else
        {
            const float xp = g->obs.xh;
${predict}
            xh = fdi_gen_obs_predict(g, par, f + (l * e), a + (l * c));
        }
        {
${at_new}
        }
    }""")

RESET_SENSOR_FMT = Template("""\
            const float x0 = ${x0}; /* ${state} from its sensor outside the MSO set */
            xh = fdi_float_is_finite(x0) ? x0 : 0.0f;""")
RESET_CONST_FMT = Template("            xh = ${x0};")

SENS_FMT = Template("""\
#if FDI_GEN_SENSITIVITIES
${indent}if (sens != NULL) /* d r / d f: ${faults} */
${indent}{
${lines}
${indent}    st = fdi_gen_sens_finish(st, sens, ${count}U);
${indent}}
#else
${indent}(void)sens;
#endif""")
NO_SENS_FMT = Template("${indent}(void)sens; /* no sensitivity */")

DOMAIN_FMT = Template("""\
/* ${name}: ${note} */
static bool ${function}_in_domain(const fdi_frame_t *in)
{
    return ${condition};
}""")

DESCRIPTOR_FMT = Template("""\
    {"${name}", ${function}, ${domain}, ${inputs},
     FDI_GEN_SENS_MASK(0x${sens_mask}U), ${n_filters}U, ${n_obs}U}, /* ${sens_note} */""")


# ------------------------------------------------------------------------------------------ data model
@dataclass(frozen=True)
class GeneratorCode:
    """Everything the C of one generator needs, computed."""

    slot: int
    name: str
    function: str
    equations: str
    causality: str
    filter_inputs: tuple[str, ...]  # C expression fed to filter k
    body: str  # the residual (and sensitivity) block, C text
    domain_condition: str  # "" when always in the domain
    domain_note: str
    inputs: str  # C mask expression of the signals read
    sens_faults: tuple[str, ...]
    sens_mask: int
    n_obs: int


@dataclass(frozen=True)
class GeneratorsFile:
    banner: str
    names: VehicleNames
    generators: tuple[GeneratorCode, ...]

    @property
    def max_filters(self) -> int:
        return max(len(g.filter_inputs) for g in self.generators)


# ------------------------------------------------------------------------------------------ computing
def kind_name(slot: int, names: VehicleNames) -> str:
    """The C descriptor of generator `slot`: &fdi_<vehicle>_generators[slot]."""
    return f"&{names.generators}[{slot}]"


def inputs(g: Generator) -> list[str]:
    """Measured signals the C generator reads: the residual's plus the operating-domain signal."""
    extra = [DOMAIN_SIGNAL] if g.min_speed > 0.0 and DOMAIN_SIGNAL not in g.knowns else []
    return [*g.knowns, *extra]


def _raw_c(names: VehicleNames, signal: str) -> str:
    return f"in->value[{names.sig_index(signal)}]"


def _node_c(g: Generator, names: VehicleNames, n: Node) -> str:
    if n.level == 0:
        return _raw_c(names, n.signal)
    src = n.source()
    assert src is not None
    k = g.filters.index(src)
    return f"o{k}.{'y' if n.order == src.order else 'dy'}"


_XPREV = sympy.Symbol("xprev")  # the previous estimate in the prediction's expressions


def _namer(g: Generator, names: VehicleNames, tmp: set[str]) -> Callable[[sympy.Symbol], str]:
    def name(s: sympy.Symbol) -> str:
        if s == XHAT:
            return "xh"
        if s == _XPREV:
            return "xp"
        return str(s) if str(s) in tmp else _node_c(g, names, node_of(s))

    return name


@dataclass(frozen=True)
class _Temp:
    symbol: sympy.Symbol
    expr: sympy.Expr  # over nodes, XHAT and earlier temporaries


def _reusing(exprs: Sequence[sympy.Expr], temps: Sequence[_Temp]) -> list[sympy.Expr]:
    """`exprs` with every subexpression that equals an available temporary's expression replaced by the
    temporary (bottom up, exact subtrees: expensive calls such as cos, sqrt, fmax of the residual are shared)."""
    known = {t.expr: t.symbol for t in temps}
    memo: dict[sympy.Basic, sympy.Basic] = {}

    def rw(e: sympy.Basic) -> sympy.Basic:
        if e in memo:
            return memo[e]
        if e.is_Atom:
            out: sympy.Basic = e
        else:
            out = e.func(*[rw(a) for a in e.args])
            out = known.get(out, out)
        memo[e] = out
        return out

    return [sympy.sympify(rw(e)) for e in exprs]


def _lines(*blocks: str) -> str:
    """The non-empty blocks of lines, one after the other."""
    return "\n".join(b for b in blocks if b)


def _sens_block(g: Generator, names: VehicleNames, faults: Sequence[str], temps: Sequence[_Temp],
                indent: str) -> str:
    """The sensitivity block: d r / d f of `g.sensitivities`, in ascending fault order, from the residual's
    temporaries `temps` and common subexpressions of their own."""
    if not g.sensitivities:
        return NO_SENS_FMT.substitute(indent=indent)
    ordered = sorted(g.sensitivities, key=lambda fs: faults.index(fs[0]))
    exprs = _reusing([e for _, e in ordered], temps)
    subs, red = sympy.cse(exprs, symbols=sympy.numbered_symbols("s"), order="canonical")
    name = _namer(g, names, {str(t.symbol) for t in temps} | {str(s) for s, _ in subs})
    lines = [f"{indent}    const float {s} = {to_c(e, name)};" for s, e in subs]
    lines += [f"{indent}    sens[{k}] = {to_c(e, name)}; /* {f} */" for k, ((f, _), e) in enumerate(zip(ordered, red,
                                                                                                          strict=True))]
    return SENS_FMT.substitute(indent=indent, faults=" ".join(f for f, _ in ordered), lines="\n".join(lines),
                               count=len(ordered))


def _plain_body(g: Generator, names: VehicleNames, faults: Sequence[str]) -> str:
    subs, red = sympy.cse([g.expr], symbols=sympy.numbered_symbols("t"), order="canonical")
    name = _namer(g, names, {str(s) for s, _ in subs})
    lines = [f"        const float {s} = {to_c(e, name)};" for s, e in subs]
    lines += [f"        const float value = {to_c(red[0], name)};", f"        {FINISH}"]
    temps = [_Temp(s, e) for s, e in subs]
    return PLAIN_BODY_FMT.substitute(lines=_lines("\n".join(lines), _sens_block(g, names, faults, temps, "        ")))


def _observer_cse(g: Generator, names: VehicleNames, predict: list[tuple[str, sympy.Expr]],
                  at_new: list[tuple[str, sympy.Expr]]) -> tuple[list[str], list[str], list[str], list[_Temp]]:
    """One common-subexpression pass over the prediction (at the previous estimate xp) and the outputs at the
    new estimate xh, so that what depends on neither (the filtered signals' terms) is computed once per step:
    (shared lines, prediction lines, lines at the new estimate, the temporaries in scope at the new estimate)."""
    exprs = [e.xreplace({XHAT: _XPREV}) for _, e in predict] + [e for _, e in at_new]
    subs, red = sympy.cse(exprs, symbols=sympy.numbered_symbols("t"), order="canonical")
    name = _namer(g, names, {str(s) for s, _ in subs})
    uses: dict[sympy.Symbol, set[sympy.Symbol]] = {}
    shared: list[str] = []
    before: list[str] = []
    after: list[str] = []
    in_scope: list[_Temp] = []
    for s, e in subs:
        deps = {v for v in e.free_symbols if v in (_XPREV, XHAT)}
        for v in e.free_symbols:
            deps |= uses.get(v, set())
        uses[s] = deps
        line = f"const float {s} = {to_c(e, name)};"
        if XHAT in uses[s]:
            after.append(line)
            in_scope.append(_Temp(s, e))
        elif _XPREV in uses[s]:
            before.append(line)
        else:
            shared.append(line)
            in_scope.append(_Temp(s, e))
    outs = [n for n, _ in predict] + [n for n, _ in at_new]
    lines = [f"const float {n} = {to_c(e, name)};" for n, e in zip(outs, red, strict=True)]
    return shared, before + lines[: len(predict)], after + lines[len(predict):], in_scope


def _observer_body(g: Generator, names: VehicleNames, faults: Sequence[str]) -> str:
    """The observer step of fdi_analysis.residuals.observer: predict xh from the previous estimate (state
    update plus output injection, exponential of the error pole, input averaged), then the residual, the next
    step's input and the sensitivities at the new estimate."""
    o = g.observer
    assert o is not None

    def raw_name(s: sympy.Symbol) -> str:
        return _node_c(g, names, node_of(s))

    if o.initial.free_symbols:
        # the state's sensor is outside the MSO set (not in the input mask, not checked by the diagnoser):
        # used only when finite, else 0 (an error of the reset value decays with the error pole)
        reset = RESET_SENSOR_FMT.substitute(x0=to_c(o.initial, raw_name), state=o.state)
    else:
        reset = RESET_CONST_FMT.substitute(x0=c_float(float(o.initial)))
    shared, predict, at_new, temps = _observer_cse(
        g, names, [("f", o.update), ("l", o.gain), ("a", o.a), ("c", o.c), ("e", g.expr)],
        [("f", o.update), ("l", o.gain), ("value", g.expr)])
    at_new_lines = "\n".join(f"            {x}" for x in [*at_new, STORE, FINISH])
    return OBSERVER_BODY_FMT.substitute(
        shared="".join(f"        {x}\n" for x in shared) + "        ", reset=reset,
        predict="\n".join(f"            {x}" for x in predict),
        at_new=_lines(at_new_lines, _sens_block(g, names, faults, temps, "            ")))


def generator_code(g: Generator, slot: int, names: VehicleNames, faults: Sequence[str]) -> GeneratorCode:
    if len(g.filters) > MAX_FILTERS:
        raise EmitError(f"{g.name}: {len(g.filters)} filters, the firmware holds {MAX_FILTERS}")
    unknown = [f for f, _ in g.sensitivities if f not in faults]
    if unknown:
        raise EmitError(f"{g.name}: sensitivities to {unknown}, not faults of the model")
    body = _observer_body(g, names, faults) if g.observer is not None else _plain_body(g, names, faults)
    domain = (f"fabsf({_raw_c(names, DOMAIN_SIGNAL)}) >= {c_float(g.min_speed)}" if g.min_speed > 0.0 else "")
    sens_faults = tuple(sorted((f for f, _ in g.sensitivities), key=faults.index))
    return GeneratorCode(
        slot=slot, name=g.name, function=f"{names.vehicle}_gen_{slot + 1}", equations=" ".join(g.equations),
        causality=g.causality(),
        filter_inputs=tuple(_node_c(g, names, f) for f in g.filters), body=body, domain_condition=domain,
        domain_note=g.domain(), inputs=names.mask_expr(inputs(g)), sens_faults=sens_faults,
        sens_mask=sum(1 << faults.index(f) for f in sens_faults), n_obs=0 if g.observer is None else 1)


def generators_file(generators: Sequence[Generator], names: VehicleNames, faults: Sequence[str],
                    banner: str) -> GeneratorsFile:
    """What goes into the generator files: the C of every generator of `generators` (slot = position), for the
    model's fault list `faults` (bit j of a sensitivity mask = faults[j])."""
    if not 0 < len(generators) <= MAX_GENERATORS:
        raise EmitError(f"{len(generators)} generators; the firmware holds 1..{MAX_GENERATORS}")
    return GeneratorsFile(banner, names,
                          tuple(generator_code(g, k, names, faults) for k, g in enumerate(generators)))


# ------------------------------------------------------------------------------------------ rendering
def _function_text(c: GeneratorCode) -> str:
    head = f"static fdi_status_t {c.function}("
    statements = _lines("\n".join(OUTPUT_FMT.substitute(k=k) for k in range(len(c.filter_inputs))),
                        "    fdi_status_t st = FDI_OK;",
                        "\n".join(FILTER_FMT.substitute(k=k, input=x) for k, x in enumerate(c.filter_inputs)),
                        c.body)
    text = FUNCTION_FMT.substitute(name=c.name, equations=c.equations, causality=comment_text(c.causality),
                                   function=c.function, pad=" " * len(head), statements=statements)
    if c.domain_condition:
        text += "\n\n" + DOMAIN_FMT.substitute(name=c.name, note=comment_text(c.domain_note), function=c.function,
                                              condition=c.domain_condition)
    return text


def render(f: GeneratorsFile) -> tuple[str, str]:
    """Header and source text of the generator files."""
    n = f.names
    listing = "\n".join(LISTING_FMT.substitute(base=n.generators, slot=c.slot, name=c.name,
                                               causality=comment_text(c.causality)) for c in f.generators)
    header = HEADER_FMT.substitute(banner=f.banner, base=n.generators, vehicle=n.vehicle, listing=listing,
                                   guard=n.generators.upper() + "_H", count_macro=n.n_generators,
                                   count=len(f.generators), n_sens=sum(len(c.sens_faults) for c in f.generators))
    descriptors = "\n".join(DESCRIPTOR_FMT.substitute(
        name=c.name, function=c.function, domain=f"{c.function}_in_domain" if c.domain_condition else "NULL",
        inputs=c.inputs, sens_mask=f"{c.sens_mask:08X}", n_filters=len(c.filter_inputs), n_obs=c.n_obs,
        sens_note=("sensitivities " + " ".join(c.sens_faults)) if c.sens_faults else "no sensitivities")
        for c in f.generators)
    source = SOURCE_FMT.substitute(banner=f.banner, base=n.generators, signals=n.signals, vehicle=n.vehicle,
                                   max_filters=f.max_filters, functions="\n\n".join(_function_text(c)
                                                                                  for c in f.generators),
                                   count_macro=n.n_generators, descriptors=descriptors)
    return header, source
