"""Choose the residual equation and the computation sequence of an MSO set, and build the residual.

Structural part (`closure`): starting from the measured signals, repeatedly
  - solve an equation with exactly one not yet computed unknown for it (`solvability.Solver`), or
  - take a differential constraint dx = d/dt x whose x is computed: dx comes from the filtered derivative
    (derivative causality; the level of dx is the level of x plus one filter).
The set of computable unknowns does not depend on the order. When every unknown is computed, the equation
left over is the residual equation. An MSO set is realizable when, for some residual equation, the rest is
computed that way; otherwise the reason names what blocks it (an unknown only reachable by integrating a
differential constraint without a measurement to correct it, i.e. open-loop simulation, or an equation that
cannot be solved for its last unknown).

Each equation of the MSO is tried as the residual equation; the one with the fewest filter levels, then the
fewest derivatives, then the fewest divisions by signals wins (ties: model order). The symbolic part
(`synthesize`) substitutes the sequence into the residual equation, lifts all signals to one filter level,
and clears divisions by signals (the residual is multiplied by its denominator, as the paper's ARR3/ARR4).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import sympy

from fdi_analysis.model import Equation, Model
from fdi_analysis.residuals.generator import DOMAIN_FACTOR, Generator, Step
from fdi_analysis.residuals.signals import align, derivative, filter_bank, nodes_in, raw
from fdi_analysis.residuals.solvability import Solution, Solver

MAX_LEVEL = 2  # at most two filter stages (second derivatives), as the hand-written ARR3/ARR4


class NotRealizableError(ValueError):
    """The MSO set has no residual generator of this kind; str() is 'not realizable: <reason>'."""

    def __init__(self, reason: str) -> None:
        super().__init__(f"not realizable: {reason}")
        self.reason = reason


@dataclass(frozen=True)
class Plan:
    residual: str
    steps: tuple[Step, ...]
    level: int  # filter level of the residual
    derivatives: int
    divisions: int


def closure(model: Model, solver: Solver, eq_ids: Iterable[str], residual: str | None) -> Plan | str:
    """The sequence computing every unknown of the MSO without `residual`, or the reason it fails.

    With residual None every equation may be used and the one left over becomes the residual equation
    (the computable set does not depend on the order, so this decides realizability in one pass)."""
    eqs = [model.equation(e) for e in eq_ids if e != residual]
    unknowns = sorted({u for e in eqs for u in e.unknowns}
                      | (set(model.equation(residual).unknowns) if residual is not None else set()))
    level: dict[str, int] = {}
    tainted: set[str] = set()  # values that hold a division by a signal
    singular = ""
    steps: list[Step] = []
    used: set[str] = set()
    progress = True
    while progress and len(level) < len(unknowns):
        progress = False
        for e in eqs:
            if e.id in used:
                continue
            if e.differential is not None:
                dx, x = e.differential
                if x in level and dx not in level:
                    level[dx] = level[x] + 1
                    if x in tainted:
                        tainted.add(dx)
                    steps.append(Step(dx, e.id, "derivative", level[dx]))
                    used.add(e.id)
                    progress = True
                continue
            todo = [u for u in e.unknowns if u not in level]
            if len(todo) == 1 and solver.solvable(e, todo[0]):
                u = todo[0]
                sol = solver.solve(e, u)
                assert isinstance(sol, Solution)
                bad = [v for v in e.unknowns if v in tainted and not solver.rational_in(e, v)]
                if bad:
                    singular = singular or (f"{bad[0]} holds a division by a signal and {e.id} is not rational "
                                            f"in it (singular when the divisor vanishes)")
                    continue
                if sol.coefficient.free_symbols or any(v in tainted for v in e.unknowns if v != u):
                    tainted.add(u)
                lv = max((level[v] for v in e.unknowns if v != u), default=0)
                div = bool(sol.coefficient.free_symbols)
                level[u] = lv
                steps.append(Step(u, e.id, "measured" if e.knowns and len(e.unknowns) == 1 else "algebraic", lv,
                                  division=div))
                used.add(e.id)
                progress = True
    missing = [u for u in unknowns if u not in level]
    if missing:
        return singular or _blocked(model, eqs, missing, used)
    if residual is None:
        left = [e.id for e in eqs if e.id not in used]
        if not left:
            return "no equation left for a residual"
        residual = left[0]
    res_eq = model.equation(residual)
    bad = [v for v in res_eq.unknowns if v in tainted and not solver.rational_in(res_eq, v)]
    if bad:
        return (f"residual {residual} is not rational in {bad[0]}, which holds a division by a signal "
                "(singular when the divisor vanishes)")
    if res_eq.differential is not None:
        dx, x = res_eq.differential
        lv = max(level[x] + 1, level[dx])
    else:
        lv = max((level[u] for u in res_eq.unknowns), default=0)
    if lv > MAX_LEVEL:
        return f"needs {lv} filter levels (derivatives of derivatives beyond {MAX_LEVEL})"
    n_der = sum(s.kind == "derivative" for s in steps) + (res_eq.differential is not None)
    return Plan(residual, tuple(steps), lv, n_der, sum(s.division for s in steps))


def _blocked(model: Model, eqs: list[Equation], missing: list[str], used: set[str]) -> str:
    for e in eqs:
        if e.id not in used and e.differential is not None and e.differential[1] in missing:
            return (f"{e.differential[1]} is reachable only by integrating {e.id} with no measurement of it in "
                    "the set (open-loop simulation, drifts)")
    reasons = []
    for e in eqs:
        if e.id in used or e.differential is not None:
            continue
        todo = [u for u in e.unknowns if u in missing]
        if len(todo) == 1:
            reasons.append(f"{e.id} cannot be solved for {todo[0]}")
    if reasons:
        return "; ".join(reasons[:3])
    return f"algebraic loop in {', '.join(missing[:6])} (no equation with a single unknown left)"


def plan(model: Model, solver: Solver, eq_ids: Iterable[str]) -> Plan:
    """The best plan over all residual equations, or NotRealizableError with the first equation's reason."""
    ids = list(eq_ids)
    best: Plan | None = None
    first_reason = ""
    for r in ids:
        p = closure(model, solver, ids, r)
        if isinstance(p, str):
            first_reason = first_reason or f"{p} (residual {r})"
            continue
        if best is None or (p.level, p.derivatives, p.divisions) < (best.level, best.derivatives, best.divisions):
            best = p
    if best is None:
        raise NotRealizableError(first_reason)
    return best


def synthesize(model: Model, eq_ids: Iterable[str], name: str, solver: Solver | None = None) -> Generator:
    """The residual generator of the MSO set `eq_ids` (raises NotRealizableError)."""
    solver = solver or Solver(model)
    ids = [e.id for e in model.equations if e.id in set(eq_ids)]
    p = plan(model, solver, ids)
    known_sub = {sympy.Symbol(k.name): raw(k.name) for k in model.knowns}
    value: dict[sympy.Symbol, sympy.Expr] = {}
    inverses: dict[sympy.Symbol, sympy.Expr] = {}  # placeholder 1/c for a division by the signal c
    for s in p.steps:
        if s.kind == "derivative":
            pair = model.equation(s.equation).differential
            assert pair is not None
            value[sympy.Symbol(s.var)] = derivative(value[sympy.Symbol(pair[1])], inverses)
        else:
            sol = solver.solve(model.equation(s.equation), s.var)
            assert isinstance(sol, Solution)
            if sol.coefficient.free_symbols:
                inv = sympy.Symbol(f"inv{len(inverses)}")
                inverses[inv] = sol.coefficient.xreplace(known_sub).xreplace(value)
                value[sympy.Symbol(s.var)] = (sol.expr * sol.coefficient).xreplace(known_sub).xreplace(value) * inv
            else:
                value[sympy.Symbol(s.var)] = sol.expr.xreplace(known_sub).xreplace(value)
    req = model.equation(p.residual)
    if req.differential is not None:
        dx, x = req.differential
        expr = value[sympy.Symbol(dx)] - derivative(value[sympy.Symbol(x)], inverses)
    else:
        expr = solver.residual(req).xreplace(known_sub).xreplace(value)
    scaled_by = ""
    if inverses:
        invs = sorted(inverses, key=str)
        try:
            poly = sympy.Poly(sympy.expand(expr), *invs)
        except sympy.PolynomialError as exc:
            raise NotRealizableError(f"residual {p.residual} is not polynomial in a quotient by a signal") from exc
        degs = [max(m[i] for m in poly.monoms()) for i in range(len(invs))]
        scale = sympy.Mul(*[inverses[v] ** d for v, d in zip(invs, degs, strict=True)])
        expr = sympy.expand(expr.xreplace({v: 1 / inverses[v] for v in invs}) * scale)
        scaled_by = sympy.sstr(scale)
    expr, level = align(expr)
    if scaled_by:
        scaled_by = scaled_by.replace("__L0d0", f" (filtered x{level})")
    if not expr.free_symbols:
        raise NotRealizableError(f"residual of {p.residual} is identically {expr}")
    nodes = nodes_in(expr)
    order = [k.name for k in model.knowns]
    used_eqs = {s.equation for s in p.steps} | {p.residual}
    faults = sorted({f for e in used_eqs for f in model.equation(e).faults}, key=[f.name for f in model.faults].index)
    min_speed, why = operating_domain(model, sorted(used_eqs))
    return Generator(
        name=name,
        equations=tuple(ids),
        residual_equation=p.residual,
        steps=p.steps,
        expr=expr,
        level=level,
        filters=tuple(filter_bank(nodes, order)),
        nodes=tuple(sorted(nodes, key=lambda n: (order.index(n.signal), n.level, n.order))),
        knowns=tuple(k for k in order if any(n.signal == k for n in nodes)),
        faults=tuple(faults),
        scaled_by=scaled_by,
        min_speed=min_speed,
        domain_reason=why,
    )


def operating_domain(model: Model, eq_ids: Iterable[str]) -> tuple[float, str]:
    """(minimum speed, reason) of a residual computed from `eq_ids`: a regularisation floor Max(..., p) with a
    parameter p (the tyre slip's v_eps) marks a law that is only meaningful away from standstill; the residual
    is then evaluable for |DOMAIN_SIGNAL| >= DOMAIN_FACTOR * p. (0, "") when no equation has such a floor."""
    params = model.parameter_values()
    floors: dict[str, float] = {}
    for e in eq_ids:
        for mx in model.equation(e).residual.atoms(sympy.Max):
            for a in mx.args:
                if isinstance(a, sympy.Symbol) and str(a) in params:
                    floors[str(a)] = float(params[str(a)])
    if not floors:
        return 0.0, ""
    name = max(sorted(floors), key=lambda k: floors[k])
    return (DOMAIN_FACTOR * floors[name],
            f"{DOMAIN_FACTOR:g} x {name} = {floors[name]:g}, the slip regularisation floor of the tyre law")
