"""The residual generators of a selection as MISRA-style C of a vehicle target (``fdi_<vehicle>_generators.h/.c``).

The generators of a table are the slots of one generator set (fw/include/fdi_gen.h): a filter bank that filters
every distinct filtered signal of all generators once per step (``<vehicle>_bank``), and one step function that
computes every running slot's residual in one pass: one common-subexpression pass over ALL residual and observer
expressions of the table, so the terms several generators share (sin/cos of a steering angle, tyre-law terms) are
evaluated once per step, gated by the slots that need them; then per slot its own terms, its observer update and,
on request, its fault sensitivities d r / d f_j (`Generator.sensitivities`) from the same shared terms. Integer
and half-integer powers become products and square roots, Max/Min and the derivatives of Abs and Max inline
helpers (fdi_gen_impl.h); float-only math. A generator's derivative-free nonlinear terms filtered as a whole
(`residuals.whole_terms`) become derived signals of the set: a derive function computes them from the raw frame
signals into free places of the frame, the bank filters them (``<vehicle>_derived``). The descriptors (one per
slot, ``fdi_<vehicle>_generators[]``, the table's tests point to them) and the set (``fdi_<vehicle>_gen_set``)
close the file. What goes into the file is computed first (`generators_file`), then rendered from the named
templates below. Deterministic output.
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from string import Template

import sympy
from sympy.core.parameters import evaluate

from fdi_analysis.errors import FdiError
from fdi_analysis.export.c_expr import c_float, to_c
from fdi_analysis.export.c_names import VehicleNames
from fdi_analysis.export.c_order import defined_before_use
from fdi_analysis.export.c_text import comment_text
from fdi_analysis.export.capacity import DEFAULT as DEFAULT_CAPACITY
from fdi_analysis.export.capacity import Capacity
from fdi_analysis.residuals.estimation import Estimated
from fdi_analysis.residuals.generator import ACCEL_SIGNALS, DOMAIN_SIGNAL, XHAT, Generator
from fdi_analysis.residuals.signals import Node, node_of, readable

# Fixed limits of the formats (the overridable capacities, checked with a `Capacity`, are export.capacity's)
MAX_BANK = 255  # FDI_GEN_MAX_BANK of fw/include/fdi_gen.h
MAX_GENERATORS = 32  # FDI_GEN_MAX_SLOTS of fw/include/fdi_gen.h (and FDI_TABLE_MAX_TESTS)
MAX_SENS = 32  # sensitivities of one generator: its sens_mask is a uint32_t of faults (FDI_TABLE_MAX_FAULTS)
MAX_FRAME = 32  # FDI_FRAME_MAX_SIGNALS of fw/include/fdi_frame.h
MAX_ESTIMATED = DEFAULT_CAPACITY.est_max_params  # FDI_EST_MAX_PARAMS's default (export.capacity)


class EmitError(FdiError, ValueError):
    """A generator that does not fit the firmware's limits."""


# ------------------------------------------------------------------------------------------ templates
HEADER_FMT = Template("""\
${banner}
/*
 * ${base}.h - residual generators of vehicle ${vehicle}, synthesised from the selected MSO sets
 * (fdi_analysis.residuals): the generator set ${set} (fdi_gen.h: a filter bank of ${n_bank} filters, every
 * filtered signal once, and one step for all slots) and one descriptor per slot, ${base}[k] for test k of the table.
${listing}
 */
#ifndef ${guard}
#define ${guard}

#include "fdi_gen.h"

/* ${n_sens} sensitivities in all (at most ${max_sens} per generator): a diagnoser listing them needs
   FDI_DIAG_MAX_SENS >= ${n_sens} */
#define ${count_macro} ${count}U

extern const fdi_gen_set_t ${set};
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
#include "${signals}.h"

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(${count_macro} <= FDI_GEN_MAX_SLOTS, fdi_sa_${vehicle}_generator_slots);

${derived}${bank}
${domains}${rates}${estimates}
static void ${vehicle}_gen_step(fdi_gen_io_t *io);

/* name, step (NULL: the set's), domain, signals read, sensitivities (bit j = fault j, ascending), filters, observer
   states, set, slot, rate gains (bit j = fault j; the gains ascending by fault), estimable quantities, range */
const fdi_gen_desc_t ${base}[${count_macro}] = {
${descriptors}
};

const fdi_gen_set_t ${set} = {"${vehicle}", ${vehicle}_gen_step, ${bank_ref}, ${n_bank}U, ${count_macro},
                              ${derive_ref}, ${derived_ref}, ${n_derived}U};

/* Every slot of io->run in one pass (fdi_gen.h): the terms shared by several slots once, then each slot. */
static void ${vehicle}_gen_step(fdi_gen_io_t *io)
{
${prelude}
${body}
}
""")

DERIVED_FMT = Template("""\
/* Derived signals (fdi_gen.h): the terms of a residual without derivatives, computed from the raw signals and
   filtered as one signal (exactly the filtered terms; products of filtered signals would differ in fast motion).
   Their places in the frame follow the vehicle's signals. */
${defines}

static void ${vehicle}_gen_derive(fdi_frame_t *in)
{
${lines}
}

static const fdi_gen_derived_t ${vehicle}_derived[${n_derived}] = {
${entries}
};

""")
DERIVED_DEFINE_FMT = Template("#define ${macro} ${index}U /* ${generator}: ${what} */")
DERIVED_LINE_FMT = Template("    in->value[${macro}] = ${value};")
DERIVED_ENTRY_FMT = Template("    {${macro}, ${sources}},")

BANK_FMT = Template("""\
/* The filter bank: every filtered signal of the generators once (b[k].x1 = y, b[k].x2 = dy; fdi_gen.h). */
static const fdi_gen_bank_filter_t ${vehicle}_bank[${n_bank}] = {
${lines}
};
""")
BANK_LINE_FMT = Template("    {${signal}, ${source}, ${order}U}, /* b[${k}]: ${what} */")

DOMAIN_FMT = Template("""\
/* ${name}: ${note} */
static bool ${function}_in_domain(const fdi_frame_t *in)
{
    return ${condition};
}
""")

DESCRIPTOR_FMT = Template("""\
    {"${name}", NULL, ${domain}, ${inputs},
     FDI_GEN_SENS_MASK(0x${sens_mask}U), 0U, ${n_obs}U, &${set}, ${slot}U,
     FDI_GEN_SENS_MASK(0x${rate_mask}U), ${rate_ref}, ${n_est}U, ${est_ref}, ${range}}, /* ${sens_note} */""")

RANGE_FMT = Template("""\
/* ${name}: the tyres near their linear range, |(ax_m, ay_m)| <= ${limit} m/s^2 (fdi_gen_desc_t.in_range) */
static bool ${function}_in_range(const fdi_frame_t *in)
{
    return ${condition};
}
""")

ESTIMATES_FMT = Template("""\
/* The quantities the diagnoser may estimate on line per test (fdi_est.h): deviations from the model's values, their
   prior mean and variance (uniform over the declared range), the variance they may gain per step (from the declared
   drift; a vehicle's constant forgets over an hour), their bounds and the most they move in one step; a group of
   quantities entering with constant
   sensitivities is one offset (fdi_analysis.residuals.estimation). {mean, var, q, lo, hi, step} */
${arrays}
""")
ESTIMATE_ARRAY_FMT = Template("""\
static const fdi_est_param_t ${vehicle}_est_${slot}[${n}] = {
${lines}
};""")
ESTIMATE_LINE_FMT = Template("    {${mean}, ${var}, ${q}, ${lo}, ${hi}, ${step}}, /* ${label} */")

RATES_FMT = Template("""\
/* Rate gains d r / d (d f / dt) of the faults that reach a residual only through a derivative, where the gain is
   constant (fdi_analysis.residuals.sensitivity.rate_gains): the steady residual of a drift of rate rho is gain * rho.
   ${notes} */
static const float ${vehicle}_rate_gain[${count}] = {${gains}};
""")

GATED_FMT = Template("""\
    if ((run & 0x${mask}U) != 0U)
    {
${lines}
    }""")

SLOT_FMT = Template("""\
    if ((run & 0x${bit}U) != 0U) /* ${name}: ${equations} */
    {
${lines}
    }""")

PLAIN_FMT = Template("""\
${own}        const float value = ${value};
        io->r[io->at[${slot}]] = value;
        if (!fdi_float_is_finite(value))
        {
            io->failed |= 0x${bit}U;
        }
${spread}${sens}""")

OBSERVER_FMT = Template("""\
        fdi_obs_t *const o = &io->obs[io->at[${slot}]];
${own}        float xp = o->xh;
        if ((io->restart & 0x${bit}U) != 0U)
        {
${restart}
        }
        {
${predict}
            float xh = xp; /* at a restart: the reset value */
            if ((io->restart & 0x${bit}U) == 0U)
            {
                xh = fdi_gen_obs_predict(o, io->par, f + (l * e), a + (l * c));
            }
            /* the observer input kept for the next step takes this prediction's gain l (at xp, not again at xh) */
${at_new}
            io->r[io->at[${slot}]] = value;
            /* a non-finite value makes the stored input non-finite too (l * value is NaN or +-Inf for any l), and
               fdi_gen_obs_store() refuses it: one check covers both */
            if (fdi_gen_obs_store(o, xh, fx + (l * value)) != FDI_OK)
            {
                io->failed |= 0x${bit}U;
            }
${spread}${sens}
        }""")

RESET_SENSOR_FMT = Template("""\
            const float x0 = ${x0}; /* ${state} from its sensor outside the MSO set */
            xp = fdi_float_is_finite(x0) ? x0 : 0.0f;""")
RESET_CONST_FMT = Template("            xp = ${x0};")

SPREAD_FMT = Template("""\
${indent}if (io->spread != NULL) /* worst-case spread: sum |d r / d theta| * dtheta over ${quantities}${estimated} */
${indent}{
${lines}
${indent}    io->spread[io->at[${slot}]] = spread;
${indent}    if (!fdi_float_is_finite(${check}))
${indent}    {
${indent}        io->failed |= 0x${bit}U;
${indent}    }
${indent}}""")

SENS_FMT = Template("""\
#if FDI_GEN_SENSITIVITIES
${indent}if ((io->sens_mask & 0x${bit}U) != 0U) /* d r / d f: ${faults} */
${indent}{
${indent}    float *const sv = &io->sens[io->sens_at[${slot}]];
${lines}
${indent}}
#endif""")


# ------------------------------------------------------------------------------------------ data model
@dataclass(frozen=True)
class BankFilter:
    k: int
    signal: str  # frame signal at the root
    source: int | None  # None: the raw signal; else the bank index of the filter it is fed from
    order: int  # fed with that filter's y (0) or dy (1)
    what: str


@dataclass(frozen=True)
class SlotCode:
    """Everything the C of one slot needs, computed."""

    slot: int
    name: str
    equations: str
    causality: str
    body: str  # its block inside the set's step, C text
    domain_condition: str  # "" when always in the domain
    domain_note: str
    range_condition: str  # "" when always in range (fdi_gen_desc_t.in_range: the tyre laws near their linear range)
    range_limit: float  # its acceleration limit [m/s^2] (Generator.max_accel), 0 without a range
    inputs: str  # C mask expression of the signals read
    sens_faults: tuple[str, ...]
    sens_mask: int
    n_obs: int
    rate_gains: tuple[tuple[str, float], ...]  # (fault, gain), ascending by fault
    rate_mask: int
    spread: tuple[tuple[str, float], ...] = ()  # (uncertain quantity, its half-width) the spread weighs, model order
    estimated: tuple[Estimated, ...] = ()  # the quantities the diagnoser may estimate (their regressors, io->reg)


@dataclass(frozen=True)
class DerivedSignal:
    index: int  # its place in the frame (after the vehicle's signals)
    signal: str
    generator: str
    value: str  # C expression over the raw frame signals
    sources: tuple[str, ...]
    what: str


@dataclass(frozen=True)
class GeneratorsFile:
    banner: str
    names: VehicleNames
    bank: tuple[BankFilter, ...]
    derived: tuple[DerivedSignal, ...]
    shared: str  # the shared terms, C text
    slots: tuple[SlotCode, ...]


# ------------------------------------------------------------------------------------------ computing
def kind_name(slot: int, names: VehicleNames) -> str:
    """The C descriptor of generator `slot`: &fdi_<vehicle>_generators[slot]."""
    return f"&{names.generators}[{slot}]"


def inputs(g: Generator) -> list[str]:
    """Measured signals the C generator reads: the residual's plus the operating-domain signals."""
    domain = ([DOMAIN_SIGNAL] if g.min_speed > 0.0 else []) + (list(ACCEL_SIGNALS) if g.max_accel > 0.0 else [])
    return [*g.knowns, *(k for k in domain if k not in g.knowns)]


def _xp(k: int) -> sympy.Symbol:
    return sympy.Symbol(f"xprev_{k}", real=True)  # slot k's previous estimate (prediction)


def _xh(k: int) -> sympy.Symbol:
    return sympy.Symbol(f"xhat_{k}", real=True)  # slot k's new estimate


def bank_nodes(generators: Sequence[Generator], signals: Sequence[str]) -> list[Node]:
    """Every filter (by input node) of the generators once, inputs before the filters fed by them, in frame order."""
    order = list(signals) + sorted({n.signal for g in generators for n in g.filters} - set(signals))
    return sorted({n for g in generators for n in g.filters}, key=lambda n: (n.level, order.index(n.signal), n.order))


def bank_of(nodes: Sequence[Node]) -> tuple[BankFilter, ...]:
    """The bank's filters: each fed with its raw signal or from the filter of its input's source node."""
    index = {n: k for k, n in enumerate(nodes)}
    out = []
    for k, n in enumerate(nodes):
        src = n.source()
        if src is None:
            out.append(BankFilter(k, n.signal, None, 0, f"{n.signal}"))
        else:
            out.append(BankFilter(k, n.signal, index[src], 0 if n.order == src.order else 1, n.text()))
    return tuple(out)


@dataclass(frozen=True)
class _Names:
    """C text of the symbols of the set's expressions."""

    names: VehicleNames
    bank: dict[Node, int]  # filter input node -> bank index
    temps: frozenset[str]

    def __call__(self, s: sympy.Symbol) -> str:
        text = str(s)
        if text in self.temps:
            return text
        if text.startswith("xprev_"):
            return "xp"
        if text.startswith("xhat_") or s == XHAT:
            return "xh"
        n = node_of(s)
        if n.level == 0:
            return f"in->value[{self.names.sig_index(n.signal)}]"
        src = n.source()
        assert src is not None
        return f"b[{self.bank[src]}].{'x1' if n.order == src.order else 'x2'}"


@dataclass(frozen=True)
class _Temp:
    symbol: sympy.Symbol
    expr: sympy.Expr  # over nodes, the estimates and earlier temporaries


@dataclass(frozen=True)
class _Outputs:
    """One slot's expressions in the global pass: names and positions in the pass's list."""

    predict: tuple[str, ...]  # at the previous estimate (observer slots)
    at_new: tuple[str, ...]  # at the new estimate (or the plain residual)
    start: int


def _renamed(e: sympy.Expr, old: sympy.Symbol, new: sympy.Symbol) -> sympy.Expr:
    """`e` with the symbol `old` renamed, without re-evaluating its functions (a Max keeps its arguments)."""
    with evaluate(False):
        return e.xreplace({old: new})


def _slot_exprs(k: int, g: Generator) -> tuple[list[str], list[str], list[sympy.Expr]]:
    o = g.observer
    if o is None:
        return [], ["value"], [g.expr]
    pre = [o.update, o.gain, o.a, o.c, g.expr]
    new = [o.update, g.expr]
    return (["f", "l", "a", "c", "e"], ["fx", "value"],
            [_renamed(e, XHAT, _xp(k)) for e in pre] + [_renamed(e, XHAT, _xh(k)) for e in new])


@dataclass(frozen=True)
class _Pass:
    temps: tuple[_Temp, ...]
    reduced: tuple[sympy.Expr, ...]
    outputs: tuple[_Outputs, ...]
    mask: dict[sympy.Symbol, int]  # slots that use each temporary
    owner: dict[sympy.Symbol, tuple[int, str]]  # estimate-dependent temporaries: (slot, "pre" or "post")


def _global_pass(generators: Sequence[Generator]) -> _Pass:
    """One common-subexpression pass over every slot's residual and observer expressions."""
    exprs: list[sympy.Expr] = []
    outputs = []
    for k, g in enumerate(generators):
        pre, new, e = _slot_exprs(k, g)
        outputs.append(_Outputs(tuple(pre), tuple(new), len(exprs)))
        exprs += e
    subs, red = sympy.cse(exprs, symbols=sympy.numbered_symbols("t"), order="canonical")
    temps = tuple(_Temp(s, e) for s, e in subs)
    owner: dict[sympy.Symbol, tuple[int, str]] = {}
    deps: dict[sympy.Symbol, set[sympy.Symbol]] = {}
    for t in temps:
        deps[t.symbol] = {v for v in t.expr.free_symbols if v in deps}
        for k in range(len(generators)):
            if _xp(k) in t.expr.free_symbols:
                owner[t.symbol] = (k, "pre")
            elif _xh(k) in t.expr.free_symbols:
                owner[t.symbol] = (k, "post")
        for v in deps[t.symbol]:
            if v in owner:
                owner[t.symbol] = owner[v]
    mask: dict[sympy.Symbol, int] = {t.symbol: 0 for t in temps}
    for k, out in enumerate(outputs):
        todo = [v for e in red[out.start:out.start + len(out.predict) + len(out.at_new)]
                for v in e.free_symbols if v in mask]
        while todo:
            v = todo.pop()
            if not mask[v] >> k & 1:
                mask[v] |= 1 << k
                todo += list(deps[v])
    return _Pass(temps, tuple(red), tuple(outputs), mask, owner)


def _ordered_shared(p: _Pass) -> list[list[_Temp]]:
    """The temporaries used by several slots, in dependency order, grouped by the slots that use them (one gate per
    group)."""
    shared = [t for t in p.temps if t.symbol not in p.owner and bin(p.mask[t.symbol]).count("1") > 1]
    done: set[sympy.Symbol] = set()
    names = {t.symbol for t in shared}
    groups: list[list[_Temp]] = []
    left = list(shared)
    while left:
        ready = [t for t in left if not ({v for v in t.expr.free_symbols if v in names} - done)]
        m = p.mask[groups[-1][0].symbol] if groups else None
        same = [t for t in ready if p.mask[t.symbol] == m]
        pick = same[0] if same else ready[0]
        if not same:
            groups.append([])
        groups[-1].append(pick)
        done.add(pick.symbol)
        left.remove(pick)
    return groups


def _reusing(exprs: Sequence[sympy.Expr], temps: Sequence[_Temp]) -> list[sympy.Expr]:
    """`exprs` with the subexpressions that an available temporary (in dependency order) already holds replaced by
    it: top down, a subtree equal to a temporary's value written out over the nodes (sympy flattens sums and
    products, so t47 = t15 + 0.66 xh with t15 = b4 - 0.66 b3 matches the flat sum b4 - 0.66 b3 + 0.66 xh), a sum
    whose negation is such a value, the terms of a sum or factors of a product that make up such a value (largest
    first); then bottom up the exact subtrees of a temporary's own expression. So the sensitivities reuse the
    residual's sums, square roots, Max and calls instead of computing them again."""
    value: dict[sympy.Basic, sympy.Basic] = {}
    whole: dict[sympy.Basic, sympy.Symbol] = {}
    for t in temps:
        v = t.expr.xreplace(value)
        value[t.symbol] = v
        whole.setdefault(v, t.symbol)
    parts = {op: sorted(((Counter(v.args), sym) for v, sym in whole.items() if v.func is op),
                        key=lambda c: -sum(c[0].values()))
             for op in (sympy.Add, sympy.Mul)}
    known = {t.expr: t.symbol for t in temps}
    memo: dict[sympy.Basic, sympy.Basic] = {}

    def split(e: sympy.Basic) -> sympy.Basic:
        left = Counter(e.args)
        held: list[sympy.Basic] = []
        for need, sym in parts[e.func]:
            if sum(need.values()) < sum(left.values()) and not need - left:
                left -= need
                held.append(sym)
        return e.func(*held, *[rw(a) for a in left.elements()]) if held else e.func(*[rw(a) for a in e.args])

    def rw(e: sympy.Basic) -> sympy.Basic:
        if e in memo:
            return memo[e]
        if e in whole:
            out: sympy.Basic = whole[e]
        elif e.is_Atom:
            out = e
        elif e.func is sympy.Add and -e in whole:
            out = -whole[-e]
        else:
            out = split(e) if e.func in parts else e.func(*[rw(a) for a in e.args])
            out = known.get(out, out)
        memo[e] = out
        return out

    return [sympy.sympify(rw(e)) for e in exprs]


def _sens_block(k: int, g: Generator, name: _Names, faults: Sequence[str], temps: Sequence[_Temp],
                indent: str) -> str:
    """The sensitivity block of slot k: d r / d f of `g.sensitivities`, in ascending fault order, from the
    temporaries in scope `temps` and common subexpressions of their own; an observer slot's at the estimate its
    step predicted from (xp, `evaluate.sensitivity_estimate`), where its gain and Jacobian are in scope."""
    if not g.sensitivities:
        return ""
    ordered = sorted(g.sensitivities, key=lambda fs: faults.index(fs[0]))
    # the sensitivities over the slot's previous estimate, as the temporaries of its prediction are
    exprs = _reusing([_renamed(e, XHAT, _xp(k)) for _, e in ordered], temps)
    subs, red = sympy.cse(exprs, symbols=sympy.numbered_symbols("s"), order="canonical")
    sname = replace(name, temps=name.temps | {str(s) for s, _ in subs})
    lines = [f"{indent}    const float {s} = {to_c(e, sname)};" for s, e in subs]
    lines += [f"{indent}    sv[{j}] = {to_c(e, sname)}; /* {f} */" for j, ((f, _), e) in enumerate(zip(ordered, red,
                                                                                                        strict=True))]
    return SENS_FMT.substitute(indent=indent, faults=" ".join(f for f, _ in ordered), lines="\n".join(lines),
                               bit=f"{1 << k:08X}", slot=k)


def _spread_block(k: int, g: Generator, name: _Names, widths: Mapping[str, float], temps: Sequence[_Temp],
                  indent: str, estimated: Sequence[Estimated] = ()) -> str:
    """The adaptive threshold's term of slot k: sum over `g.uncertainty` but the `estimated` quantities of
    |d r / d theta| * w_theta (`widths`), and the estimated quantities' regressors (io->reg), from the temporaries in
    scope `temps` and common subexpressions of their own; an observer slot's at the estimate its step predicted from
    (xp), as its sensitivities. "" for a generator without uncertainty sensitivities."""
    if not g.uncertainty:
        return ""
    taken = {n for e in estimated for n in e.names}
    rest = [(q, e) for q, e in g.uncertainty if q not in taken]
    terms = _reusing([_renamed(e, XHAT, _xp(k)) for _, e in rest]
                     + [_renamed(e.regressor, XHAT, _xp(k)) for e in estimated], temps)
    subs, red = sympy.cse(terms, symbols=sympy.numbered_symbols("u"), order="canonical")
    uname = replace(name, temps=name.temps | {str(s) for s, _ in subs})
    lines = [f"{indent}    const float {s} = {to_c(e, uname)};" for s, e in subs]
    spread_red, reg_red = red[:len(rest)], red[len(rest):]
    # the terms of constant sensitivity (an unknown input entering linearly) add up to one constant; one statement
    # a line (c_order.defined_before_use moves each temporary to just before its first use)
    fixed = [(q, widths[q] * abs(float(e))) for (q, _), e in zip(rest, spread_red, strict=True) if e.is_Number]
    lines.append(f"{indent}    float spread = {c_float(sum(v for _, v in fixed))}; /* "
                 + (" ".join(q for q, _ in fixed) or "no constant term") + " */")
    lines += [f"{indent}    spread += ({c_float(widths[q])} * fabsf({to_c(e, uname)})); /* {q} */"
              for (q, _), e in zip(rest, spread_red, strict=True) if not e.is_Number]
    check = ["spread"]
    for j, (est, e) in enumerate(zip(estimated, reg_red, strict=True)):
        lines.append(f"{indent}    const float reg{j} = {to_c(e, uname)}; /* d r / d ({est.label}) */")
        lines.append(f"{indent}    io->reg[(io->at[{k}] * FDI_EST_MAX_PARAMS) + {j}U] = reg{j};")
        check.append(f"(0.0f * reg{j})")
    note = (f"; regressors of the estimable {', '.join(e.label for e in estimated)}" if estimated else "")
    return SPREAD_FMT.substitute(indent=indent, quantities=" ".join(q for q, _ in rest) or "(none left)",
                                 estimated=note, lines="\n".join(lines), slot=k, bit=f"{1 << k:08X}",
                                 check=" + ".join(check)) + "\n"


def _const_lines(temps: Sequence[_Temp], name: _Names, indent: str) -> str:
    return "".join(f"{indent}const float {t.symbol} = {to_c(t.expr, name)};\n" for t in temps)


def _slot_body(k: int, g: Generator, p: _Pass, name: _Names, faults: Sequence[str],
               widths: Mapping[str, float], estimated: Sequence[Estimated] = ()) -> str:
    """Slot k's block: the temporaries only it uses, its residual (and observer step), its sensitivities."""
    own = [t for t in p.temps if t.symbol not in p.owner and p.mask[t.symbol] == 1 << k]
    pre = [t for t in p.temps if p.owner.get(t.symbol) == (k, "pre")]
    post = [t for t in p.temps if p.owner.get(t.symbol) == (k, "post")]
    scope = [t for t in p.temps if t.symbol not in p.owner and p.mask[t.symbol] >> k & 1] + pre
    out = p.outputs[k]
    red = p.reduced[out.start:out.start + len(out.predict) + len(out.at_new)]
    bit = f"{1 << k:08X}"
    if g.observer is None:
        return PLAIN_FMT.substitute(own=_const_lines(own, name, "        "), value=to_c(red[0], name), slot=k, bit=bit,
                                    spread=_spread_block(k, g, name, widths, scope, "        ", estimated),
                                    sens=_sens_block(k, g, name, faults, scope, "        "))
    o = g.observer
    if o.initial.free_symbols:
        # the state's sensor is outside the MSO set (not in the input mask, not checked by the diagnoser):
        # used only when finite, else 0 (an error of the reset value decays with the error pole)
        restart = RESET_SENSOR_FMT.substitute(x0=to_c(o.initial, name), state=o.state)
    else:
        restart = RESET_CONST_FMT.substitute(x0=c_float(float(o.initial)))
    predict = _const_lines(pre, name, "            ") + "".join(
        f"            const float {n} = {to_c(e, name)};\n" for n, e in zip(out.predict, red[:len(out.predict)],
                                                                          strict=True))
    at_new = _const_lines(post, name, "            ") + "".join(
        f"            const float {n} = {to_c(e, name)};\n" for n, e in zip(out.at_new, red[len(out.predict):],
                                                                          strict=True))
    return OBSERVER_FMT.substitute(slot=k, bit=bit, own=_const_lines(own, name, "        "), restart=restart,
                                   predict=predict.rstrip("\n"), at_new=at_new.rstrip("\n"),
                                   spread=_spread_block(k, g, name, widths, scope, "            ", estimated),
                                   sens=_sens_block(k, g, name, faults, scope, "            "))


def _shared_text(p: _Pass, name: _Names, all_slots: int, slots_text: str) -> str:
    """The shared temporaries: those of every slot computed unconditionally (the set's step runs only for some
    slot), the others computed under the gate of the slots that use them: declared first when read outside their
    gate's block (`slots_text`: the slots' code), else local constants of the block."""
    groups = _ordered_shared(p)
    always = [t for grp in groups for t in grp if p.mask[t.symbol] == all_slots]
    gated = [grp for grp in groups if p.mask[grp[0].symbol] != all_slots]
    lines = [[f"{t.symbol} = {to_c(t.expr, name)};" for t in grp] for grp in gated]

    def outside(sym: str, g: int) -> bool:
        pat = re.compile(rf"\b{re.escape(sym)}\b")
        return bool(pat.search(slots_text)) or any(pat.search(ln) for h, grp in enumerate(lines) if h != g
                                                   for ln in grp)

    wide = [[outside(str(t.symbol), g) for t in grp] for g, grp in enumerate(gated)]
    decls = "".join(f"    float {t.symbol} = 0.0f;\n" for g, grp in enumerate(gated)
                    for t, w in zip(grp, wide[g], strict=True) if w)
    blocks = [GATED_FMT.substitute(mask=f"{p.mask[grp[0].symbol]:08X}",
                                   lines="\n".join(f"        {'' if w else 'const float '}{ln}"
                                                   for ln, w in zip(lines[g], wide[g], strict=True)))
              for g, grp in enumerate(gated)]
    return (decls + _const_lines(always, name, "    ") + "\n".join(blocks)).rstrip("\n")


def _slot_code(k: int, g: Generator, p: _Pass, name: _Names, names: VehicleNames,
               faults: Sequence[str], widths: Mapping[str, float], estimated: Sequence[Estimated] = ()) -> SlotCode:
    unknown = [f for f, _ in g.sensitivities if f not in faults]
    if unknown:
        raise EmitError(f"{g.name}: sensitivities to {unknown}, not faults of the model")
    if len(g.sensitivities) > MAX_SENS:
        raise EmitError(f"{g.name}: {len(g.sensitivities)} sensitivities, the diagnoser holds {MAX_SENS}")
    domain = (f"fabsf({name(Node(DOMAIN_SIGNAL, 0, 0).symbol)}) >= {c_float(g.min_speed)}" if g.min_speed > 0.0
              else "")
    in_range = ""
    if g.max_accel > 0.0:
        ax, ay = (name(Node(k, 0, 0).symbol) for k in ACCEL_SIGNALS)
        in_range = f"(({ax} * {ax}) + ({ay} * {ay})) <= {c_float(g.max_accel * g.max_accel)}"
    sens_faults = tuple(sorted((f for f, _ in g.sensitivities), key=faults.index))
    unknown = [f for f, _ in g.rate_gains if f not in faults or f in sens_faults]
    if unknown:
        raise EmitError(f"{g.name}: rate gains of {unknown}, not faults of the model without a sensitivity")
    rates = tuple(sorted(g.rate_gains, key=lambda fg: faults.index(fg[0])))
    unknown = [q for q, _ in g.uncertainty if q not in widths]
    if unknown:
        raise EmitError(f"{g.name}: sensitivities to {unknown}, not uncertain quantities of the model")
    body = SLOT_FMT.substitute(bit=f"{1 << k:08X}", name=g.name, equations=" ".join(g.equations),
                               lines=_slot_body(k, g, p, name, faults, widths, estimated).rstrip("\n"))
    return SlotCode(slot=k, name=g.name, equations=" ".join(g.equations), causality=g.causality(), body=body,
                    domain_condition=domain, domain_note=g.domain(), range_condition=in_range, range_limit=g.max_accel,
                    inputs=names.mask_expr(inputs(g)),
                    sens_faults=sens_faults, sens_mask=sum(1 << faults.index(f) for f in sens_faults),
                    n_obs=0 if g.observer is None else 1,
                    rate_gains=rates, rate_mask=sum(1 << faults.index(f) for f, _ in rates),
                    spread=tuple((q, widths[q]) for q, _ in g.uncertainty), estimated=tuple(estimated))


def generators_file(generators: Sequence[Generator], names: VehicleNames, faults: Sequence[str],
                    banner: str, signals: Sequence[str], widths: Mapping[str, float] | None = None,
                    estimation: Mapping[str, Sequence[Estimated]] | None = None,
                    capacity: Capacity = DEFAULT_CAPACITY) -> GeneratorsFile:
    """What goes into the generator files: the set of `generators` (slot = position), for the model's fault list
    `faults` (bit j of a sensitivity mask = faults[j]); `signals`: the frame's signals in index order (the bank's
    order; the derived signals take the places after them), every signal the generators read among them;
    `widths`: the half-width of every uncertain quantity the generators' `uncertainty` names (the spread of the
    adaptive threshold, fdi_gen.h); `estimation`: by generator name, the quantities the diagnoser may estimate on line
    for it (fdi_est.h; the spread leaves them out, the step writes their regressors); `capacity`: the capacities the
    firmware is built with (export.capacity; default: the C defaults): more generators (tests), sensitivities in
    all, bank filters or estimated quantities of a test than it holds are refused, naming both numbers."""
    if not 0 < len(generators) <= MAX_GENERATORS:
        raise EmitError(f"{len(generators)} generators; the firmware holds 1..{MAX_GENERATORS}")
    est = estimation or {}
    over = [capacity.exceeded("max_tests", len(generators), "generators (one test each)"),
            capacity.exceeded("max_sens", sum(len(g.sensitivities) for g in generators), "sensitivities in all")]
    over += [capacity.exceeded("est_max_params", len(est.get(g.name, ())), f"{g.name}: estimated quantities")
             for g in generators]
    reasons = [r for r in over if r]
    if reasons:
        raise EmitError("; ".join(reasons))
    order = list(signals)
    missing = sorted({k for g in generators for k in g.knowns} - set(order))
    if missing:
        raise EmitError(f"the generators read {', '.join(missing)}, not signals of the frame")
    composites = [(g.name, g.composite) for g in generators if g.composite is not None]
    if len(order) + len(composites) > MAX_FRAME:
        raise EmitError(f"{len(order)} signals and {len(composites)} derived signals; the frame holds {MAX_FRAME}")
    nodes = bank_nodes(generators, order + [c.signal for _, c in composites])
    if len(nodes) > MAX_BANK:
        raise EmitError(f"{len(nodes)} filters in the bank, the firmware holds {MAX_BANK}")
    too_many = capacity.exceeded("max_filters", len(nodes), "filters in the bank")
    if too_many:
        raise EmitError(too_many)
    p = _global_pass(generators)
    name = _Names(names, {n: k for k, n in enumerate(nodes)}, frozenset(str(t.symbol) for t in p.temps))
    all_slots = (1 << len(generators)) - 1
    slots = tuple(_slot_code(k, g, p, name, names, faults, widths or {}, est.get(g.name, ()))
                  for k, g in enumerate(generators))
    derived = tuple(DerivedSignal(len(order) + k, c.signal, gname, to_c(c.expr, name), c.sources,
                                  readable(c.expr)) for k, (gname, c) in enumerate(composites))
    return GeneratorsFile(banner, names, bank_of(nodes), derived, _shared_text(p, name, all_slots,
                                                                      "\n".join(c.body for c in slots)), slots)


# ------------------------------------------------------------------------------------------ rendering
def _derived_text(f: GeneratorsFile) -> str:
    if not f.derived:
        return ""
    n = f.names
    return DERIVED_FMT.substitute(
        vehicle=n.vehicle, n_derived=len(f.derived),
        defines="\n".join(DERIVED_DEFINE_FMT.substitute(macro=n.sig_index(d.signal), index=d.index,
                                                        generator=d.generator, what=comment_text(d.what))
                          for d in f.derived),
        lines="\n".join(DERIVED_LINE_FMT.substitute(macro=n.sig_index(d.signal), value=d.value) for d in f.derived),
        entries="\n".join(DERIVED_ENTRY_FMT.substitute(macro=n.sig_index(d.signal), sources=n.mask_expr(d.sources))
                           for d in f.derived))


def _bank_text(f: GeneratorsFile) -> str:
    if not f.bank:
        return ""
    n = f.names
    lines = "\n".join(BANK_LINE_FMT.substitute(
        signal=n.sig_index(b.signal), source="FDI_GEN_BANK_RAW" if b.source is None else f"{b.source}U",
        order=b.order, k=b.k, what=comment_text(b.what)) for b in f.bank)
    return BANK_FMT.substitute(vehicle=n.vehicle, n_bank=len(f.bank), lines=lines)


def _prelude(body: str) -> str:
    lines = []
    if "b[" in body:
        lines.append("    const fdi_svf_t *const b = io->bank;")
    if "in->" in body:
        lines.append("    const fdi_frame_t *const in = io->in;")
    lines.append("    const uint32_t run = io->run;")
    return "\n".join(lines)


def render(f: GeneratorsFile) -> tuple[str, str]:
    """Header and source text of the generator files."""
    n = f.names
    listing = "\n".join(LISTING_FMT.substitute(base=n.generators, slot=c.slot, name=c.name,
                                               causality=comment_text(c.causality)) for c in f.slots)
    header = HEADER_FMT.substitute(banner=f.banner, base=n.generators, vehicle=n.vehicle, listing=listing,
                                   guard=n.generators.upper() + "_H", count_macro=n.n_generators, set=n.gen_set,
                                   count=len(f.slots), n_bank=len(f.bank), max_sens=max(len(c.sens_faults)
                                                                                        for c in f.slots),
                                   n_sens=sum(len(c.sens_faults) for c in f.slots))
    # one domain (range) function per distinct condition (the diagnoser evaluates a function shared by consecutive
    # tests once per step, fdi_diag.c), named after the first slot that has it
    first: dict[str, SlotCode] = {}
    first_range: dict[str, SlotCode] = {}
    for c in f.slots:
        if c.domain_condition:
            first.setdefault(c.domain_condition, c)
        if c.range_condition:
            first_range.setdefault(c.range_condition, c)
    all_rates = [(c, fg) for c in f.slots for fg in c.rate_gains]
    rates = RATES_FMT.substitute(
        notes="; ".join(f"{c.name}: {fault}" for c, (fault, _) in all_rates), vehicle=n.vehicle, count=len(all_rates),
        gains=", ".join(c_float(gain) for _, (_, gain) in all_rates)) if all_rates else ""
    # each constant defined just before its first use: shorter lives, fewer values moved to the stack (c_order.py)
    body = defined_before_use(f.shared + "\n" + "\n".join(c.body for c in f.slots))
    source = SOURCE_FMT.substitute(banner=f.banner, base=n.generators, signals=n.signals, vehicle=n.vehicle,
                                   derived=_derived_text(f), bank=_bank_text(f),
                                   domains=_domain_functions(f, first, first_range), rates=rates,
                                   estimates=_estimate_arrays(f), count_macro=n.n_generators,
                                   descriptors=_descriptors(f, first, first_range), set=n.gen_set,
                                   bank_ref=f"{n.vehicle}_bank" if f.bank else "NULL", n_bank=len(f.bank),
                                   derive_ref=f"{n.vehicle}_gen_derive" if f.derived else "NULL",
                                   derived_ref=f"{n.vehicle}_derived" if f.derived else "NULL",
                                   n_derived=len(f.derived),
                                   prelude=_prelude(body), body=body)
    return header, source


def _descriptors(f: GeneratorsFile, first: Mapping[str, SlotCode], first_range: Mapping[str, SlotCode]) -> str:
    """The generator descriptors (fdi_gen_desc_t), one per slot."""
    n = f.names
    rate_at: dict[int, int] = {}  # slot -> its first gain in <vehicle>_rate_gain
    for c in f.slots:
        if c.rate_gains:
            rate_at[c.slot] = sum(len(d.rate_gains) for d in f.slots if d.slot < c.slot)
    return "\n".join(DESCRIPTOR_FMT.substitute(
        name=c.name,
        domain=f"{n.vehicle}_gen_{first[c.domain_condition].slot + 1}_in_domain" if c.domain_condition else "NULL",
        inputs=c.inputs, sens_mask=f"{c.sens_mask:08X}", n_obs=c.n_obs, set=n.gen_set, slot=c.slot,
        rate_mask=f"{c.rate_mask:08X}",
        rate_ref=f"&{n.vehicle}_rate_gain[{rate_at[c.slot]}]" if c.rate_gains else "NULL",
        n_est=len(c.estimated), est_ref=f"{n.vehicle}_est_{c.slot}" if c.estimated else "NULL",
        range=f"{n.vehicle}_gen_{first_range[c.range_condition].slot + 1}_in_range" if c.range_condition else "NULL",
        sens_note=(("sensitivities " + " ".join(c.sens_faults)) if c.sens_faults else "no sensitivities")
        + ("; rate gains " + " ".join(fault for fault, _ in c.rate_gains) if c.rate_gains else "")
        + ("; adaptive threshold over " + " ".join(q for q, _ in c.spread) if c.spread else "")
        + ("; estimable " + ", ".join(e.label for e in c.estimated) if c.estimated else ""))
        for c in f.slots)


def _estimate_arrays(f: GeneratorsFile) -> str:
    """The estimable quantities' declarations (fdi_est_param_t arrays), one array per slot that has some."""
    if not any(c.estimated for c in f.slots):
        return ""
    return ESTIMATES_FMT.substitute(arrays="\n".join(ESTIMATE_ARRAY_FMT.substitute(
        vehicle=f.names.vehicle, slot=c.slot, n=len(c.estimated),
        lines="\n".join(ESTIMATE_LINE_FMT.substitute(mean=c_float(e.mean), var=c_float(e.var), q=c_float(e.q),
                                                     lo=c_float(e.lo), hi=c_float(e.hi), step=c_float(e.step),
                                                     label=e.label)
                        for e in c.estimated)) for c in f.slots if c.estimated))


def _domain_functions(f: GeneratorsFile, first: Mapping[str, SlotCode], first_range: Mapping[str, SlotCode]) -> str:
    """The operating-domain and range functions, one per distinct condition."""
    vehicle = f.names.vehicle
    out = "".join(DOMAIN_FMT.substitute(
        name=", ".join(d.name for d in f.slots if d.domain_condition == cond), note=comment_text(c.domain_note),
        function=f"{vehicle}_gen_{c.slot + 1}", condition=cond) + "\n" for cond, c in first.items())
    return out + "".join(RANGE_FMT.substitute(
        name=", ".join(d.name for d in f.slots if d.range_condition == cond), limit=f"{c.range_limit:g}",
        function=f"{vehicle}_gen_{c.slot + 1}", condition=cond) + "\n" for cond, c in first_range.items())
