"""Choose the residual equation and the computation sequence of an MSO set, and build the residual.

Structural part (`closure`): starting from the measured signals, repeatedly
  - solve an equation with exactly one not yet computed unknown for it (`solvability.Solver`), or
  - take a differential constraint dx = d/dt x whose x is computed: dx comes from the filtered derivative
    (derivative causality; the level of dx is the level of x plus one filter), or, when neither applies,
  - solve an algebraic loop: the next just-determined block (Dulmage-Mendelsohn) of k >= 2 equations in k
    unknowns, jointly by Cramer's rule when they are linear in those unknowns (`Solver.solve_block`; a
    tyre law in the loop, a singular or an unclearable determinant is rejected with the equation and
    the variable). With no residual equation chosen yet a loop can sit in the overdetermined part; each
    of its equations is then tried as the residual equation.
When every unknown is computed, the equation left over is the residual equation. An MSO set is realizable
when, for some residual equation, the rest is computed that way; otherwise the reason names what blocks it
(an unknown only reachable by integrating a differential constraint without a measurement to correct it,
i.e. open-loop simulation, an equation that cannot be solved for its last unknown, or a loop and why).

Integral causality (`observer_closure`): when the only block is the open-loop integration of ONE state x,
x becomes an observer estimate (known), its differential constraint the state update, and the closure runs
again; the equation left over must depend on x (it is the observer's output equation and the residual), no
filtered derivative is taken of a value computed from x, and no step divides by a signal. More states
integrated open loop are rejected ("needs k observer states"). Plans without an observer win over plans
with one; `observer` designs the gain and the discretisation.

Each equation of the MSO is tried as the residual equation; the one with the fewest filter levels, then the
fewest derivatives, then the fewest divisions by signals wins (ties: model order). A state whose
derivative that plan takes twice (`twice_differentiated`) may instead be estimated by an observer
(`integral_alternative`); `synthesize` takes it when the residual equation sees the state uniformly
(d r / d x a nonzero constant), and otherwise keeps the second derivative and records why in
`Generator.note` (ROMO's MSO3/MSO4 = ARR3/ARR4: their observer alternative sees vy resp. vx only through
the yaw rate). The symbolic part substitutes the sequence into the residual equation, lifts all signals to
one filter level, and clears divisions by signals (the residual is multiplied by its denominator, as the
paper's ARR3/ARR4).
"""

from __future__ import annotations

import functools
from collections.abc import Container, Iterable, Mapping
from dataclasses import dataclass
from typing import Literal

import numpy as np
import sympy
from numpy.typing import NDArray

from fdi_analysis.dm import dulmage_mendelsohn
from fdi_analysis.model import Equation, Model
from fdi_analysis.residuals.generator import DOMAIN_FACTOR, LOOP_JOIN, XHAT, Generator, Observer, Step
from fdi_analysis.residuals.observer import (
    ObserverReference,
    align_with_state,
    d_dstate,
    design_observer,
    initial_estimate,
)
from fdi_analysis.residuals.reasons import NotRealizableError, Reason, Rejection
from fdi_analysis.residuals.signals import align, derivative, filter_bank, nodes_in, raw, readable
from fdi_analysis.residuals.solvability import BlockSolution, Solution, Solver
from fdi_analysis.residuals.whole_terms import whole_terms

FloatArray = NDArray[np.float64]
Causality = Literal["auto", "derivative", "integral"]
MAX_LEVEL = 2  # at most two filter stages (second derivatives), as the hand-written ARR3/ARR4


@dataclass(frozen=True)
class Plan:
    residual: str
    steps: tuple[Step, ...]
    level: int  # filter level of the residual
    derivatives: int
    divisions: int
    observer: str = ""  # state estimated by an observer (integral causality), "" for none


def closure(model: Model, solver: Solver, eq_ids: Iterable[str], residual: str | None,
            observed: str | None = None) -> Plan | Rejection:
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
            return Rejection(Reason.NO_OBSERVER_EQUATION, f"{observed} has no differential constraint to drive an "
                             "observer", residual or "", observed)
    eqs = [model.equation(e) for e in ids if e != residual and e != obs_eq]
    unknowns = sorted({u for e in eqs for u in e.unknowns}
                      | (set(model.equation(residual).unknowns) if residual is not None else set())
                      | ({observed} if observed is not None else set()))
    level: dict[str, int] = {}
    tainted: set[str] = set()  # values that hold a division by a signal
    from_obs: set[str] = set()  # values computed from the observer state
    singular: Rejection | None = None  # the first step refused for a division by a signal
    loop_why: Rejection | None = None  # why an algebraic loop of the set is not solved
    steps: list[Step] = []
    used: set[str] = set()
    if observed is not None:
        level[observed] = 0
        from_obs.add(observed)
        steps.append(Step(observed, obs_eq, "observer", 0))

    def accept(block: list[Equation], sols: dict[str, Solution], kind: str) -> bool:
        """Take the step computing `sols` from `block` (one equation, or an algebraic loop solved jointly),
        unless it would divide by a signal where that cannot be cleared; the reason then goes to `singular`."""
        nonlocal singular
        names = LOOP_JOIN.join(e.id for e in block)
        inputs = {v for e in block for v in e.unknowns if v not in sols}
        bad = [(e.id, v) for e in block for v in e.unknowns if v in tainted and not solver.rational_in(e, v)]
        if bad:
            singular = singular or Rejection(
                Reason.DIVISION, f"{bad[0][1]} holds a division by a signal and {bad[0][0]} is not rational in it "
                "(singular when the divisor vanishes)", bad[0][0], bad[0][1])
            return False
        div = any(bool(sol.coefficient.free_symbols) for sol in sols.values())
        if observed is not None and (div or inputs & tainted):
            singular = singular or Rejection(
                Reason.OBSERVER_DIVISION, f"{names} solved for {', '.join(sols)} divides by a signal inside the "
                "observer (singular when the divisor vanishes)", names, next(iter(sols)))
            return False
        lv = max((level[v] for v in inputs), default=0)
        for u in sols:
            if div or inputs & tainted:
                tainted.add(u)
            if inputs & from_obs:
                from_obs.add(u)
            level[u] = lv
            steps.append(Step(u, names, kind, lv, division=div))
        used.update(e.id for e in block)
        return True

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
                        singular = singular or Rejection(
                            Reason.OBSERVER_DERIVATIVE, f"{e.id} would differentiate {x}, computed from the observer "
                            f"state {observed}", e.id, x)
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
                sol = solver.solve(e, todo[0])
                assert isinstance(sol, Solution)
                kind = "measured" if e.knowns and len(e.unknowns) == 1 else "algebraic"
                progress = accept([e], {todo[0]: sol}, kind) or progress
        if not progress and len(level) < len(unknowns):
            for block, vars_ in _loops(solver, eqs, used, level):
                blk = solver.solve_block(block, vars_)
                if isinstance(blk, Rejection):
                    loop_why = loop_why or blk
                    continue
                if accept(block, dict(zip(blk.unknowns, blk.solutions, strict=True)), "loop"):
                    progress = True
                    break
    missing = [u for u in unknowns if u not in level]
    if missing:
        why = singular or _blocked(model, solver, eqs, missing, used, loop_why)
        if residual is None and why.kind is not Reason.OPEN_LOOP:
            # an algebraic loop inside the overdetermined part splits into blocks only once the residual
            # equation is chosen: try each equation of that part that could close a solvable loop
            for r in _loop_residuals(solver, eqs, used, missing):
                q = closure(model, solver, ids, r, observed)
                if isinstance(q, Plan):
                    return q
                if q.kind is Reason.ALGEBRAIC_LOOP and why.kind is not Reason.ALGEBRAIC_LOOP:
                    why = q
        return why
    if residual is None:
        left = [e.id for e in eqs if e.id not in used]
        if observed is not None:
            left = [e for e in left if set(model.equation(e).unknowns) & from_obs] or left
        if not left:
            return Rejection(Reason.NO_RESIDUAL, "no equation left for a residual")
        residual = left[0]
    res_eq = model.equation(residual)
    bad = [v for v in res_eq.unknowns if v in tainted and not solver.rational_in(res_eq, v)]
    if bad:
        return Rejection(Reason.RESIDUAL_DIVISION, f"residual {residual} is not rational in {bad[0]}, which holds a "
                         "division by a signal (singular when the divisor vanishes)", residual, bad[0])
    if observed is not None:
        if res_eq.differential is not None:
            return Rejection(Reason.OBSERVER_OUTPUT, f"residual {residual} is a differential constraint, not an "
                             f"output equation of {observed}", residual, observed)
        if not set(res_eq.unknowns) & from_obs:
            return Rejection(Reason.NOT_OBSERVABLE, f"residual {residual}: {observed} not observable from the "
                             "residual equation (it does not depend on it)", residual, observed)
    if res_eq.differential is not None:
        dx, x = res_eq.differential
        lv = max(level[x] + 1, level[dx])
    else:
        lv = max((level[u] for u in res_eq.unknowns), default=0)
    if lv > MAX_LEVEL:
        return Rejection(Reason.FILTER_LEVELS, f"needs {lv} filter levels (derivatives of derivatives beyond "
                         f"{MAX_LEVEL})", residual)
    n_der = sum(s.kind == "derivative" for s in steps) + (res_eq.differential is not None)
    return Plan(residual, tuple(steps), lv, n_der, sum(s.division for s in steps), observed or "")


# Reasons found on the equation left over as the residual: with another residual equation the set may work.
RESIDUAL_CHECKS = frozenset({Reason.RESIDUAL_DIVISION, Reason.OBSERVER_OUTPUT, Reason.NOT_OBSERVABLE})


def open_loop_state(reason: Rejection) -> str | None:
    """The state an open-loop-integration reason of `closure` names, else None."""
    return reason.variable if reason.kind is Reason.OPEN_LOOP else None


def observer_closure(model: Model, solver: Solver, eq_ids: Iterable[str], residual: str | None,
                     reason: Rejection) -> Plan | Rejection:
    """When the plain closure fails with `reason` = open-loop integration of a state: the closure with that
    state estimated by an observer; more than one such state is rejected ("needs k observer states")."""
    ids = list(eq_ids)
    states: list[str] = []
    why = reason
    while (x := open_loop_state(why)) is not None and x not in states:
        states.append(x)
        if len(states) > 1:
            break
        p = closure(model, solver, ids, residual, x)
        if isinstance(p, Rejection) and residual is None and p.kind in RESIDUAL_CHECKS:
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
        return Rejection(Reason.OBSERVER_STATES, f"needs {more} observer states "
                         f"({', '.join(states)}{', ...' if more > len(states) else ''})", states=tuple(states))
    return why


def _open_loop_count(model: Model, solver: Solver, ids: list[str], residual: str | None,
                     states: list[str]) -> int:
    """Number of states an MSO set integrates open loop: pretend each found state is measured and repeat."""
    found = list(states)
    diffs = {d[1]: d for e in ids if (d := model.equation(e).differential) is not None}
    while True:
        extra = [e for e in ids if (d := model.equation(e).differential) is None or d[1] not in found]
        # a pretend measurement of each found state: drop its differential constraint and seed it known
        p = _closure_seeded(model, solver, extra, residual, found)
        x = open_loop_state(p) if p is not None else None
        if x is None or x in found or x not in diffs:
            return len(found)
        found.append(x)


def _closure_seeded(model: Model, solver: Solver, ids: list[str], residual: str | None,
                    seeds: list[str]) -> Rejection | None:
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
        return _blocked(model, solver, eqs, missing, used)
    return None


def _loops(solver: Solver, eqs: list[Equation], used: set[str],
           known: Mapping[str, int]) -> list[tuple[list[Equation], list[str]]]:
    """The algebraic loops that can be solved next: the just-determined blocks (Dulmage-Mendelsohn, in
    solvable order) of two or more unused algebraic equations over the unknowns not yet computed, each
    equation linear in the unknowns it still lacks and holding only computed unknowns and those of its block
    (`_loopable`)."""
    lack = _loopable(solver, eqs, used, known)
    if len(lack) < 2:
        return []
    by_id = {e.id: e for e in eqs}
    return [([by_id[e] for e in rows], list(cols))
            for rows, cols in _square_blocks(tuple(sorted((e, frozenset(us)) for e, us in lack.items())))]


@functools.lru_cache(maxsize=65536)
def _square_blocks(lack: tuple[tuple[str, frozenset[str]], ...]) -> tuple[tuple[tuple[str, ...], tuple[str, ...]], ...]:
    """The just-determined blocks of two or more equations of the structure `lack` (equation -> the unknowns
    it lacks) that lack nothing outside the block, in solvable order (a pure function of the structure,
    so many MSO sets share one decomposition)."""
    cols = sorted({u for _, us in lack for u in us})
    col = {u: j for j, u in enumerate(cols)}
    inc = np.zeros((len(lack), len(cols)), dtype=bool)
    for i, (_, us) in enumerate(lack):
        for u in us:
            inc[i, col[u]] = True
    out = []
    for rows, vs in dulmage_mendelsohn(inc).zero_blocks:
        inside = {cols[j] for j in vs}
        if len(rows) >= 2 and all(lack[i][1] <= inside for i in rows):
            out.append((tuple(lack[i][0] for i in rows), tuple(cols[j] for j in vs)))
    return tuple(out)


def _loopable(solver: Solver, eqs: list[Equation], used: set[str], known: Container[str]) -> dict[str, set[str]]:
    """The unused algebraic equations that may lie on a loop Cramer's rule solves, with the unknowns they
    lack: each lacks two or more unknowns, is linear in each of them (not marked not_solvable_for it), and
    every unknown it lacks is lacked by another such equation (in a strongly connected block of two or more
    equations each unknown appears twice); pruned until that holds."""
    lack: dict[str, set[str]] = {}
    for e in eqs:
        if e.id in used or e.differential is not None:
            continue
        todo = {u for u in e.unknowns if u not in known}
        if len(todo) > 1 and todo <= solver.loop_unknowns(e):
            lack[e.id] = todo
    changed = True
    while changed and lack:
        count: dict[str, int] = {}
        for us in lack.values():
            for u in us:
                count[u] = count.get(u, 0) + 1
        drop = [k for k, us in lack.items() if any(count[u] < 2 for u in us)]
        changed = bool(drop)
        for k in drop:
            del lack[k]
    return lack


def _loop_residuals(solver: Solver, eqs: list[Equation], used: set[str], missing: list[str]) -> list[str]:
    """Residual equations worth trying when the plain closure stalls in the overdetermined part: when two or
    more unused equations could form a loop (`_loopable`), the equations of the M+ part of what is left."""
    gone = set(missing)
    if len(_loopable(solver, eqs, used, {u for e in eqs for u in e.unknowns} - gone)) < 2:
        return []
    lack = tuple((e.id, frozenset(set(e.unknowns) & gone)) for e in eqs
                 if e.id not in used and e.differential is None and set(e.unknowns) & gone)
    return list(_overdetermined(lack))


@functools.lru_cache(maxsize=65536)
def _overdetermined(lack: tuple[tuple[str, frozenset[str]], ...]) -> tuple[str, ...]:
    """The M+ equations of the structure `lack` (equation -> the unknowns it lacks), a pure function of it."""
    cols = sorted({u for _, us in lack for u in us})
    inc = np.array([[u in us for u in cols] for _, us in lack], dtype=bool)
    return tuple(lack[i][0] for i in dulmage_mendelsohn(inc).plus_eqs)


def _blocked(model: Model, solver: Solver, eqs: list[Equation], missing: list[str], used: set[str],
             loop_why: Rejection | None = None) -> Rejection:
    for e in eqs:
        if e.id not in used and e.differential is not None and e.differential[1] in missing:
            return Rejection(Reason.OPEN_LOOP, f"{e.differential[1]} is reachable only by integrating {e.id} with no "
                             "measurement of it in the set (open-loop simulation, drifts)", e.id, e.differential[1])
    reasons: list[tuple[str, str]] = []
    for e in eqs:
        if e.id in used or e.differential is not None:
            continue
        todo = [u for u in e.unknowns if u in missing]
        if len(todo) == 1:
            reasons.append((e.id, todo[0]))
    if loop_why is not None:
        return loop_why
    if reasons:
        return Rejection(Reason.NOT_SOLVABLE, "; ".join(f"{e} cannot be solved for {v}" for e, v in reasons[:3]),
                         reasons[0][0], reasons[0][1])
    why = ""
    where = ("", "")
    for e in eqs:  # the first equation of the loop that Cramer's rule cannot take, and why
        if e.id in used or e.differential is not None:
            continue
        bad = [u for u in e.unknowns if u in missing and not solver.linear_in(e, u)]
        if bad:
            how = "is marked not_solvable_for" if bad[0] in e.not_solvable_for else "is not linear in"
            why = f": {e.id} {how} {bad[0]}"
            where = (e.id, bad[0])
            break
    return Rejection(Reason.ALGEBRAIC_LOOP, f"algebraic loop in {', '.join(missing[:6])} (no equation with a single "
                     f"unknown left{why})", *where)


def plan(model: Model, solver: Solver, eq_ids: Iterable[str]) -> Plan:
    """The best plan over all residual equations, or NotRealizableError with the first equation's reason.
    Plans without an observer state win over plans with one."""
    ids = list(eq_ids)
    best: Plan | None = None
    first_reason: Rejection | None = None
    for r in ids:
        p = closure(model, solver, ids, r)
        if isinstance(p, Rejection) and open_loop_state(p) is not None:
            p = observer_closure(model, solver, ids, r, p)
        if isinstance(p, Rejection):
            first_reason = first_reason or Rejection(p.kind, f"{p.text} (residual {r})", p.equation, p.variable,
                                                     p.states)
            continue
        key = (bool(p.observer), p.level, p.derivatives, p.divisions)
        if best is None or key < (bool(best.observer), best.level, best.derivatives, best.divisions):
            best = p
    if best is None:
        raise NotRealizableError(first_reason or Rejection(Reason.NO_RESIDUAL, "no equation to try as residual"))
    return best


def twice_differentiated(model: Model, p: Plan) -> list[str]:
    """The states whose derivative the plan takes of a value that already holds a filtered derivative (a
    second derivative of a measured signal, e.g. vy = (d/dt vx - ax) / psidot, then d/dt vy in ARR3)."""
    out = []
    for s in p.steps:
        pair = model.equation(s.equation).differential if s.kind == "derivative" else None
        if pair is not None and s.level >= 2 and pair[1] not in out:
            out.append(pair[1])
    pair = model.equation(p.residual).differential  # a residual dx - d/dt x differentiates x once more
    if pair is not None and pair[1] not in out and any(s.var == pair[1] and s.level >= 1 for s in p.steps):
        out.append(pair[1])
    return out


def integral_alternative(model: Model, solver: Solver, eq_ids: Iterable[str], p: Plan) -> Plan | None:
    """The best plan that estimates, by an observer, a state `p` differentiates twice (integral causality
    for that state instead of a second derivative), with fewer filter levels than `p`; None when there is
    none (or `p` already has an observer state: one per generator)."""
    if p.observer:
        return None
    ids = list(eq_ids)
    best: Plan | None = None
    for x in twice_differentiated(model, p):
        for r in ids:
            q = closure(model, solver, ids, r, x)
            if isinstance(q, Plan) and q.level < p.level and (
                    best is None or (q.level, q.derivatives, q.divisions) < (best.level, best.derivatives,
                                                                             best.divisions)):
                best = q
    return best


def synthesize(model: Model, eq_ids: Iterable[str], name: str, solver: Solver | None = None,
               reference: ObserverReference | None = None, causality: Causality = "auto") -> Generator:
    """The residual generator of the MSO set `eq_ids` (raises NotRealizableError). `reference`: what the gain
    design of an observer generator whose output sensitivity varies takes its regularisation from (fault-free
    reference signals or the sensitivity already measured on them, `observer.ObserverReference`); without
    it such a generator is rejected (Reason.NO_REFERENCE).

    Causality: filtered derivatives for measured signals; an observer for a state only the integration of
    its differential constraint reaches; for a state whose derivative would be taken twice (`causality`):
    "auto" estimates it by an observer when the residual equation sees it uniformly (d r / d x a nonzero
    constant), else keeps the second derivative and says why in the generator's `note` (an estimate the
    output does not see somewhere integrates open loop there); "integral" always takes the observer where
    there is one, "derivative" never."""
    solver = solver or Solver(model)
    ids = [e.id for e in model.equations if e.id in set(eq_ids)]
    p = plan(model, solver, ids)
    alt = integral_alternative(model, solver, ids, p) if causality != "derivative" else None
    note = ""
    if alt is not None:
        g_alt = _assemble(model, solver, ids, alt, name)
        assert g_alt.observer is not None
        c = g_alt.observer.c
        if causality == "integral" or (not c.free_symbols and c != 0):
            return design_observer(g_alt, reference)
        twice = ", ".join(twice_differentiated(model, p))
        note = (f"an observer for {alt.observer} (residual {alt.residual}) instead of the second derivative "
                f"of {twice}: d r / d {alt.observer} = {readable(c)} vanishes in some manoeuvres, where the "
                "estimate would integrate open loop")
    g = _assemble(model, solver, ids, p, name, note)
    return g if g.observer is None else design_observer(g, reference)


@dataclass(frozen=True)
class SequenceValues:
    """The values of a plan's computation sequence: each computed variable as an expression over the raw
    node symbols, XHAT and the placeholders of divisions by signals (`inverses`: placeholder -> divisor)."""

    value: dict[sympy.Symbol, sympy.Expr]
    inverses: dict[sympy.Symbol, sympy.Expr]


def sequence_values(model: Model, solver: Solver, p: Plan) -> SequenceValues:
    """Run the steps of plan `p` symbolically (with a fault-keeping solver the values hold the fault symbols)."""
    known_sub = {sympy.Symbol(k.name): raw(k.name) for k in model.knowns}
    value: dict[sympy.Symbol, sympy.Expr] = {}
    inverses: dict[sympy.Symbol, sympy.Expr] = {}  # placeholder 1/c for a division by the signal c
    loop_inverse: dict[str, sympy.Symbol] = {}  # one placeholder per algebraic loop (its determinant)
    faults = solver.fault_symbols
    if p.observer:
        value[sympy.Symbol(p.observer)] = XHAT
    for s in p.steps:
        if s.kind == "observer":
            continue
        if s.kind == "derivative":
            pair = model.equation(s.equation).differential
            assert pair is not None
            value[sympy.Symbol(s.var)] = derivative(value[sympy.Symbol(pair[1])], inverses, faults, solver.fault_rates)
            continue
        if s.kind == "loop":
            block = [model.equation(e) for e in s.equations]
            blk = solver.solve_block(block, [t.var for t in p.steps if t.equation == s.equation])
            assert isinstance(blk, BlockSolution)
            sol = blk.solutions[blk.unknowns.index(s.var)]
        else:
            one = solver.solve(model.equation(s.equation), s.var)
            assert isinstance(one, Solution)
            sol = one
        if sol.coefficient.free_symbols:
            inv = loop_inverse.get(s.equation) if s.kind == "loop" else None
            if inv is None:
                inv = sympy.Symbol(f"inv{len(inverses)}")
                inverses[inv] = sol.coefficient.xreplace(known_sub).xreplace(value)
                if s.kind == "loop":
                    loop_inverse[s.equation] = inv
            value[sympy.Symbol(s.var)] = (sol.expr * sol.coefficient).xreplace(known_sub).xreplace(value) * inv
        else:
            value[sympy.Symbol(s.var)] = sol.expr.xreplace(known_sub).xreplace(value)
    return SequenceValues(value, inverses)


def residual_value(model: Model, solver: Solver, p: Plan, seq: SequenceValues) -> sympy.Expr:
    """The residual equation of `p` evaluated on the sequence (divisions still as placeholders)."""
    known_sub = {sympy.Symbol(k.name): raw(k.name) for k in model.knowns}
    req = model.equation(p.residual)
    if req.differential is not None:
        dx, x = req.differential
        return seq.value[sympy.Symbol(dx)] - derivative(seq.value[sympy.Symbol(x)], seq.inverses, solver.fault_symbols,
                                                     solver.fault_rates)
    return solver.residual(req).xreplace(known_sub).xreplace(seq.value)


def division_degrees(p: Plan, expr: sympy.Expr, inverses: dict[sympy.Symbol, sympy.Expr]) -> list[int]:
    """The highest power of each placeholder (sorted by name) in `expr`: the divisors' powers to clear."""
    invs = sorted(inverses, key=str)
    try:
        poly = sympy.Poly(sympy.expand(expr), *invs)
    except sympy.PolynomialError as exc:
        raise NotRealizableError(Rejection(Reason.NOT_POLYNOMIAL, f"residual {p.residual} is not polynomial in a "
                                           "quotient by a signal", p.residual)) from exc
    return [max(m[i] for m in poly.monoms()) for i in range(len(invs))]


def cleared(expr: sympy.Expr, inverses: dict[sympy.Symbol, sympy.Expr], degs: list[int]) -> sympy.Expr:
    """`expr` times the divisors to the powers `degs` (placeholders sorted by name), expanded: no division by a
    signal is left. A divisor that is a sum (the determinant of an algebraic loop) stands for a symbol of its
    own until the powers have cancelled."""
    invs = sorted(inverses, key=str)
    stand = {v: sympy.Dummy(f"d_{v}") for v in invs}
    out = sympy.expand(expr.xreplace({v: 1 / stand[v] for v in invs})
                       * sympy.Mul(*[stand[v] ** d for v, d in zip(invs, degs, strict=True)]))
    return sympy.expand(out.xreplace({stand[v]: inverses[v] for v in invs}))


def _assemble(model: Model, solver: Solver, ids: list[str], p: Plan, name: str, note: str = "") -> Generator:
    """The generator of plan `p` (an observer generator without its gain: `design_observer` adds it)."""
    seq = sequence_values(model, solver, p)
    value, inverses = seq.value, seq.inverses
    expr = residual_value(model, solver, p, seq)
    scaled_by = ""
    if inverses:
        invs = sorted(inverses, key=str)
        degs = division_degrees(p, expr, inverses)
        scale = sympy.Mul(*[inverses[v] ** d for v, d in zip(invs, degs, strict=True)])
        expr = cleared(expr, inverses, degs)
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
            raise NotRealizableError(Rejection(Reason.NOT_OBSERVABLE, f"{p.observer} not observable from the residual "
                                               f"equation {p.residual} (d r / d {p.observer} is identically 0)",
                                               p.residual, p.observer))
    else:
        expr, level = align(expr)
    plain_nodes = nodes_in(expr)  # the sensitivities (computed over filtered signals) may read any of them
    composite = None
    if observer is None:
        expr, composite = whole_terms(expr, level, name)
    if scaled_by:
        scaled_by = scaled_by.replace("__L0d0", f" (filtered x{level})")
    if not expr.free_symbols:
        raise NotRealizableError(Rejection(Reason.CONSTANT_RESIDUAL, f"residual of {p.residual} is identically {expr}",
                                           p.residual))
    nodes = nodes_in(expr) | plain_nodes | (nodes_in(observer.update) if observer is not None else set())
    measured = [k.name for k in model.knowns]
    order = measured + ([composite.signal] if composite is not None else [])
    used_eqs = {e for s in p.steps for e in s.equations} | {p.residual}
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
        knowns=tuple(k for k in measured if any(n.signal == k for n in nodes)),
        faults=tuple(faults),
        scaled_by=scaled_by,
        min_speed=min_speed,
        domain_reason=why,
        observer=observer,
        note=note,
        composite=composite,
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
