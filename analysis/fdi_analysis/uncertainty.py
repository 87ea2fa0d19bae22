"""What a model does not know, as the structural analysis sees it: the nuisances of a model (its unknown
parameters and unknown inputs, `Model.nuisances`) made unknown variables, so that the MSO sets, the isolability
and the selection decouple the residuals from them.

* An unknown **input** (road grade, driving resistance) becomes an unknown without an equation of its own.
* An unknown **constant** or **slowly varying** parameter (a sensor bias) becomes an unknown ``b`` with a zero
  derivative: the differential constraint ``D.b: db = d/dt b`` and ``C.b: db = 0``. A residual that uses them
  tests that ``b`` does not change. In derivative causality that residual is the time derivative of an estimate
  of ``b``, so it sees a fault's change (an abrupt step, at its onset) and is blind to a constant offset or a
  drift as slow as the bias's own: what an estimator can tell apart from a fault is the speed of the change.
  ``strict=True`` instead treats such a parameter as an unknown input (no constancy): what is left then is what
  the diagnosis can tell apart from a bias whatever its time course.

Uncertain parameters (a `range` on a parameter) stay known constants here: they do not change the structure.
The nominal model (`Model.equations`) holds every nuisance at its nominal value."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import replace

import sympy

from fdi_analysis.expressions import der
from fdi_analysis.model import Equation, Model, ModelError, Nuisance, Variable
from fdi_analysis.model_loader import nominal_number, with_expression


def derivative_name(n: Nuisance) -> str:
    return f"d{n.name}"


def decoupled(model: Model, names: Iterable[str] | None = None, *, strict: bool = False) -> Model:
    """`model` with the nuisances `names` (default: all) as unknowns; the others at their nominal values.

    The equations keep their ids and order; constancy equations ``D.<b>``, ``C.<b>`` follow the last equation.
    A name that is not a nuisance of the model is an error naming it."""
    by_name = {n.name: n for n in model.nuisances}
    chosen = list(by_name) if names is None else list(dict.fromkeys(names))
    _check_names(model, chosen, by_name, "an unknown parameter or input")
    if not chosen:
        return model
    variables = _variables(model)
    taken = set(variables) | set(model.parameters)
    new_unknowns: list[Variable] = []
    extra: list[Equation] = []
    for name in chosen:
        n = by_name[name]
        new_unknowns.append(Variable(n.name, "unknown", n.unit, n.desc))
        if n.kind != "input" and not strict:
            dname = derivative_name(n)
            if dname in taken or dname in by_name:
                raise ModelError(f"the name {dname!r} for d/dt {name} is already taken",
                                 file=str(model.source or model.name), symbol=dname)
            new_unknowns.append(Variable(dname, "unknown", f"({n.unit})/s", f"time derivative of {name}"))
            d, x = sympy.Symbol(dname), sympy.Symbol(name)
            extra.append(Equation(id=f"D.{name}", unknowns=(dname, name), knowns=(), faults=(), lhs=d,
                                  rhs=der(x), differential=(dname, name),
                                  desc=f"{dname} = d/dt {name}", group="nuisances"))
            extra.append(Equation(id=f"C.{name}", unknowns=(dname,), knowns=(), faults=(), lhs=d,
                                  rhs=sympy.Integer(0), desc=f"{name} is constant (it drifts at most {n.drift:g} "
                                  f"{n.unit}/s)" if n.kind == "slow" else f"{name} is constant", group="nuisances"))
    variables.update({v.name: v for v in new_unknowns})
    # a variable keeps the declared order, nuisances after the unknowns
    order = {v.name: i for i, v in enumerate((*model.unknowns, *new_unknowns, *model.knowns, *model.faults))}
    variables = dict(sorted(variables.items(), key=lambda kv: order[kv[0]]))
    left = tuple(n for n in model.nuisances if n.name not in chosen)
    rest = {sympy.Symbol(n.name): nominal_number(n.value) for n in left}
    nominal = _rewritten(model, rest, variables)
    raw = _rewritten(model, {}, variables) if left else []  # the others still symbols: a later decoupling
    return replace(model, unknowns=(*model.unknowns, *new_unknowns), equations=(*nominal, *extra),
                   nuisances=left, nuisance_equations=(*raw, *extra) if left else ())


def _rewritten(model: Model, subs: Mapping[sympy.Symbol, sympy.Expr], variables: Mapping[str, Variable],
               ) -> list[Equation]:
    """The model's equations, nuisances still symbols (`Model.nuisance_equations`), with `subs` applied and
    their variable lists derived again over `variables`."""
    file = str(model.source or model.name)
    out: list[Equation] = []
    for e in model.nuisance_equations or model.equations:
        if e.lhs is None or e.rhs is None or e.differential is not None:
            out.append(e)
            continue
        out.append(with_expression(e, e.lhs.xreplace(subs), e.rhs.xreplace(subs), variables, file))
    return out


def _variables(model: Model) -> dict[str, Variable]:
    return {v.name: v for v in (*model.unknowns, *model.knowns, *model.faults)}


def _check_names(model: Model, names: Iterable[str], allowed: Iterable[str], what: str) -> None:
    known = list(allowed)
    for name in names:
        if name not in known:
            raise ModelError(f"{name!r} is not {what} of the model (it declares: {', '.join(known) or 'none'})",
                             file=str(model.source or model.name), symbol=name)


def at_values(model: Model, values: Mapping[str, float]) -> Model:
    """`model` as a vehicle with other values of its uncertain parameters and nuisances: `values` maps a
    parameter or a nuisance to its value there (the others keep theirs). The result's nominal values are these,
    so that a plant compiled from it (`fdi_host.sim.plant.Plant`) is that vehicle, and its generators are the
    ones designed for it. A value outside the declared range is allowed (a study may go beyond the envelope)."""
    by_name = {n.name: n for n in model.nuisances}
    _check_names(model, values, (*model.parameters, *by_name), "a parameter or an unknown parameter or input")
    params = dict(model.parameters)
    for name, v in values.items():
        if name in params:
            params[name] = replace(params[name], value=float(v))
    nuisances = tuple(replace(n, value=float(values[n.name])) if n.name in values else n for n in model.nuisances)
    subs = {sympy.Symbol(n.name): nominal_number(n.value) for n in nuisances}
    equations = _rewritten(model, subs, _variables(model)) if nuisances else list(model.equations)
    return replace(model, parameters=params, nuisances=nuisances, equations=tuple(equations))


PERTURBATION = "unc__"  # prefix of the perturbation symbol of an uncertain parameter or nuisance


def perturbation_name(name: str) -> str:
    return f"{PERTURBATION}{name}"


def perturbed(model: Model, name: str) -> Model:
    """`model` with one uncertain parameter or nuisance ``p`` written as its nominal value plus a perturbation,
    ``p -> p0 + unc__p``, the perturbation the model's only fault (the faults at 0, the other uncertain
    quantities at their nominal values). The machinery that gives a residual's d r / d f then gives its
    d r / d p (`fdi_analysis.residuals.uncertainty_sensitivity`); one quantity at a time keeps the symbolic
    residual as small as the nominal one. Parameters computed from others (``expr``) keep their value: their
    uncertainty is their inputs'."""
    by_name = {n.name: n for n in model.nuisances}
    ranged = model.uncertain_parameters()
    _check_names(model, [name], (*ranged, *by_name), "an uncertain parameter or an unknown parameter or input")
    value, unit, desc = ((ranged[name].value, ranged[name].unit, ranged[name].desc) if name in ranged
                         else (by_name[name].value, by_name[name].unit, by_name[name].desc))
    pname = perturbation_name(name)
    variables = {v.name: v for v in (*model.unknowns, *model.knowns)}
    if pname in variables or pname in model.parameters or pname in {f.name for f in model.faults}:
        raise ModelError(f"the name {pname!r} for the perturbation of {name} is already taken",
                         file=str(model.source or model.name), symbol=pname)
    perturbation = Variable(pname, "fault", unit, f"perturbation of {name} ({desc})")
    variables[pname] = perturbation
    subs: dict[sympy.Symbol, sympy.Expr] = {sympy.Symbol(f.name): sympy.Integer(0) for f in model.faults}
    subs |= {sympy.Symbol(n.name): nominal_number(n.value) for n in model.nuisances if n.name != name}
    subs[sympy.Symbol(name)] = sympy.Add(nominal_number(value), sympy.Symbol(pname))
    equations = _rewritten(model, subs, variables)
    params = {k: p for k, p in model.parameters.items() if k != name}
    return replace(model, faults=(perturbation,), equations=tuple(equations), parameters=params, nuisances=(),
                   nuisance_equations=())
