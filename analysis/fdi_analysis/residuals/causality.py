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

Integral causality (`observer_closure`): when the only block is the open-loop integration of ONE state x,
x becomes an observer estimate (known), its differential constraint the state update, and the closure runs
again; the equation left over must depend on x (it is the observer's output equation and the residual), no
filtered derivative is taken of a value computed from x, and no step divides by a signal. More states
integrated open loop are rejected ("needs k observer states"). Plans without an observer win over plans
with one; `observer` designs the gain and the discretisation.

Each equation of the MSO is tried as the residual equation; the one with the fewest filter levels, then the
fewest derivatives, then the fewest divisions by signals wins (ties: model order). The symbolic part
(`synthesize`) substitutes the sequence into the residual equation, lifts all signals to one filter level,
and clears divisions by signals (the residual is multiplied by its denominator, as the paper's ARR3/ARR4).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np
import sympy
from numpy.typing import NDArray

from fdi_analysis.model import Equation, Model
from fdi_analysis.residuals.generator import DOMAIN_FACTOR, XHAT, Generator, Observer, Step
from fdi_analysis.residuals.observer import align_with_state, d_dstate, design_observer, initial_estimate
from fdi_analysis.residuals.signals import align, derivative, filter_bank, nodes_in, raw
from fdi_analysis.residuals.solvability import Solution, Solver

FloatArray = NDArray[np.float64]
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
    observer: str = ""  # state estimated by an observer (integral causality), "" for none


def closure(model: Model, solver: Solver, eq_ids: Iterable[str], residual: str | None,
            observed: str | None = None) -> Plan | str:
    """The sequence computing every unknown of the MSO without `residual`, or the reason it fails.

    With residual None every equation may be used and the one left over becomes the residual equation
    (the computable set does not depend on the order, so this decides realizability in one pass).
    With `observed` = a state x: x is the observer's estimate (known), its differential constraint is the
    state update (not in the sequence), no filtered derivative is taken of a value computed from x, and the
    residual equation must depend on x."""
    ids = list(eq_ids)
    obs_eq = ""
    if observed is not None:
        obs_eq = next((e for e in ids if (d := model.equation(e).differential) is not None and d[1] == observed), "")
        if not obs_eq or obs_eq == residual:
            return f"{observed} has no differential constraint to drive an observer"
    eqs = [model.equation(e) for e in ids if e != residual and e != obs_eq]
    unknowns = sorted({u for e in eqs for u in e.unknowns}
                      | (set(model.equation(residual).unknowns) if residual is not None else set())
                      | ({observed} if observed is not None else set()))
    level: dict[str, int] = {}
    tainted: set[str] = set()  # values that hold a division by a signal
    from_obs: set[str] = set()  # values computed from the observer state
    singular = ""
    steps: list[Step] = []
    used: set[str] = set()
    if observed is not None:
        level[observed] = 0
        from_obs.add(observed)
        steps.append(Step(observed, obs_eq, "observer", 0))
    progress = True
    while progress and len(level) < len(unknowns):
        progress = False
        for e in eqs:
            if e.id in used:
                continue
            if e.differential is not None:
                dx, x = e.differential
                if x in level and dx not in level:
                    if x in from_obs:
                        singular = singular or (f"{e.id} would differentiate {x}, computed from the observer "
                                                f"state {observed}")
                        continue
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
                div = bool(sol.coefficient.free_symbols)
                if observed is not None and (div or any(v in tainted for v in e.unknowns if v != u)):
                    singular = singular or (f"{e.id} solved for {u} divides by a signal inside the observer "
                                            "(singular when the divisor vanishes)")
                    continue
                if div or any(v in tainted for v in e.unknowns if v != u):
                    tainted.add(u)
                if any(v in from_obs for v in e.unknowns if v != u):
                    from_obs.add(u)
                lv = max((level[v] for v in e.unknowns if v != u), default=0)
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
        if observed is not None:
            left = [e for e in left if set(model.equation(e).unknowns) & from_obs] or left
        if not left:
            return "no equation left for a residual"
        residual = left[0]
    res_eq = model.equation(residual)
    bad = [v for v in res_eq.unknowns if v in tainted and not solver.rational_in(res_eq, v)]
    if bad:
        return (f"residual {residual} is not rational in {bad[0]}, which holds a division by a signal "
                "(singular when the divisor vanishes)")
    if observed is not None:
        if res_eq.differential is not None:
            return f"residual {residual} is a differential constraint, not an output equation of {observed}"
        if not set(res_eq.unknowns) & from_obs:
            return (f"residual {residual}: {observed} not observable from the residual equation (it does not "
                    "depend on it)")
    if res_eq.differential is not None:
        dx, x = res_eq.differential
        lv = max(level[x] + 1, level[dx])
    else:
        lv = max((level[u] for u in res_eq.unknowns), default=0)
    if lv > MAX_LEVEL:
        return f"needs {lv} filter levels (derivatives of derivatives beyond {MAX_LEVEL})"
    n_der = sum(s.kind == "derivative" for s in steps) + (res_eq.differential is not None)
    return Plan(residual, tuple(steps), lv, n_der, sum(s.division for s in steps), observed or "")


def open_loop_states(model: Model, reason: str) -> str | None:
    """The state named by an open-loop-integration reason of `closure`, else None."""
    if " is reachable only by integrating " not in reason:
        return None
    return reason.split(" is reachable only by integrating ", 1)[0]


def observer_closure(model: Model, solver: Solver, eq_ids: Iterable[str], residual: str | None,
                     reason: str) -> Plan | str:
    """When the plain closure fails with `reason` = open-loop integration of a state: the closure with that
    state estimated by an observer; more than one such state is rejected ("needs k observer states")."""
    ids = list(eq_ids)
    states: list[str] = []
    why = reason
    while (x := open_loop_states(model, why)) is not None and x not in states:
        states.append(x)
        if len(states) > 1:
            break
        p = closure(model, solver, ids, residual, x)
        if isinstance(p, str) and residual is None and p.startswith("residual "):
            # the equation left over does not see x: another choice of the residual equation may
            for r in ids:
                q = closure(model, solver, ids, r, x)
                if isinstance(q, Plan):
                    return q
        if isinstance(p, Plan):
            return p
        why = p
    if len(states) > 1:
        more = _open_loop_count(model, solver, ids, residual, states)
        return f"needs {more} observer states ({', '.join(states)}{', ...' if more > len(states) else ''})"
    return why if why != reason else reason


def _open_loop_count(model: Model, solver: Solver, ids: list[str], residual: str | None,
                     states: list[str]) -> int:
    """Number of states an MSO set integrates open loop: pretend each found state is measured and repeat."""
    found = list(states)
    diffs = {d[1]: d for e in ids if (d := model.equation(e).differential) is not None}
    while True:
        extra = [e for e in ids if (d := model.equation(e).differential) is None or d[1] not in found]
        # a pretend measurement of each found state: drop its differential constraint and seed it known
        p = _closure_seeded(model, solver, extra, residual, found)
        x = open_loop_states(model, p) if isinstance(p, str) else None
        if x is None or x in found or x not in diffs:
            return len(found)
        found.append(x)


def _closure_seeded(model: Model, solver: Solver, ids: list[str], residual: str | None,
                    seeds: list[str]) -> str:
    eqs = [model.equation(e) for e in ids if e != residual]
    known = set(seeds)
    used: set[str] = set()
    unknowns = {u for e in eqs for u in e.unknowns} - known
    progress = True
    while progress and not unknowns <= known:
        progress = False
        for e in eqs:
            if e.id in used:
                continue
            if e.differential is not None:
                if e.differential[1] in known and e.differential[0] not in known:
                    known.add(e.differential[0])
                    used.add(e.id)
                    progress = True
                continue
            todo = [u for u in e.unknowns if u not in known]
            if len(todo) == 1 and solver.solvable(e, todo[0]):
                known.add(todo[0])
                used.add(e.id)
                progress = True
    missing = sorted(unknowns - known)
    if missing:
        return _blocked(model, eqs, missing, used)
    return "ok"


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
    """The best plan over all residual equations, or NotRealizableError with the first equation's reason.
    Plans without an observer state win over plans with one."""
    ids = list(eq_ids)
    best: Plan | None = None
    first_reason = ""
    for r in ids:
        p = closure(model, solver, ids, r)
        if isinstance(p, str) and open_loop_states(model, p) is not None:
            p = observer_closure(model, solver, ids, r, p)
        if isinstance(p, str):
            first_reason = first_reason or f"{p} (residual {r})"
            continue
        key = (bool(p.observer), p.level, p.derivatives, p.divisions)
        if best is None or key < (bool(best.observer), best.level, best.derivatives, best.divisions):
            best = p
    if best is None:
        raise NotRealizableError(first_reason)
    return best


def synthesize(model: Model, eq_ids: Iterable[str], name: str, solver: Solver | None = None,
               reference: Mapping[str, FloatArray] | None = None) -> Generator:
    """The residual generator of the MSO set `eq_ids` (raises NotRealizableError). `reference`: fault-free
    measured signals for the gain design of an observer generator (default: the simulator's reference
    drive, `observer.reference_sensitivity`)."""
    solver = solver or Solver(model)
    ids = [e.id for e in model.equations if e.id in set(eq_ids)]
    p = plan(model, solver, ids)
    known_sub = {sympy.Symbol(k.name): raw(k.name) for k in model.knowns}
    value: dict[sympy.Symbol, sympy.Expr] = {}
    inverses: dict[sympy.Symbol, sympy.Expr] = {}  # placeholder 1/c for a division by the signal c
    if p.observer:
        value[sympy.Symbol(p.observer)] = XHAT
    for s in p.steps:
        if s.kind == "observer":
            continue
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
    observer: Observer | None = None
    if p.observer:
        obs_eq = next(s.equation for s in p.steps if s.kind == "observer")
        pair = model.equation(obs_eq).differential
        assert pair is not None
        update, expr, level = align_with_state(value[sympy.Symbol(pair[0])], expr)
        observer = Observer(p.observer, obs_eq, update, sympy.Integer(0), d_dstate(update),
                            d_dstate(expr), 0.0, 0.0, initial_estimate(model, solver, p.observer))
        if observer.c == 0:
            raise NotRealizableError(f"{p.observer} not observable from the residual equation {p.residual} "
                                     f"(d r / d {p.observer} is identically 0)")
    else:
        expr, level = align(expr)
    if scaled_by:
        scaled_by = scaled_by.replace("__L0d0", f" (filtered x{level})")
    if not expr.free_symbols:
        raise NotRealizableError(f"residual of {p.residual} is identically {expr}")
    nodes = nodes_in(expr) | (nodes_in(observer.update) if observer is not None else set())
    order = [k.name for k in model.knowns]
    used_eqs = {s.equation for s in p.steps} | {p.residual}
    faults = sorted({f for e in used_eqs for f in model.equation(e).faults}, key=[f.name for f in model.faults].index)
    min_speed, why = operating_domain(model, sorted(used_eqs))
    g = Generator(
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
        observer=observer,
    )
    return g if observer is None else design_observer(g, reference)


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
