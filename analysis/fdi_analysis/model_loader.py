"""Load a model file (TOML, documented in analysis/models/README.md) or an FDT-style structural JSON file.

TOML layout (see the ROMO files under analysis/models/ for complete examples)::

    [model]
    name = "tank"
    description = "..."
    # optional, to derive a model from another one:
    extends = "base.toml"            # path relative to this file
    remove_equations = ["E7"]
    explicit_derivatives = true      # der(x) -> new unknown dx plus a differential constraint
    [parameters]
    m = { value = 1046.0, unit = "kg", desc = "vehicle mass" }
    l = { expr = "l_f + l_r", unit = "m" }
    [[unknown]]                       # also [[known]] and [[fault]]
    name = "vx"
    unit = "m/s"
    [[equation]]
    id = "B1"
    expr = "m*(dvx - vy*psidot) = Fx1 + Fx2"
    [[equation]]
    id = "D1"
    differential = ["dvx", "vx"]     # dvx = d/dt vx
    [[eliminate]]                     # step-4 grouping: solve `equation` for `variable`, substitute
    variable = "vL1"
    equation = "W1.vL"
    # what the model does not know (fdi_analysis.uncertainty decouples it):
    # m = { value = 1046.0, range = [1046.0, 1307.5] }   in [parameters]: an uncertain parameter
    [[unknown_parameter]]             # an unknown constant (or, with drift, slowly varying) parameter
    name = "b_ax"
    range = [-0.15, 0.15]
    drift = 0.005                     # optional: at most this many units per second
    [[unknown_input]]                 # an unknown input (a disturbance)
    name = "grade"
    range = [-0.08, 0.08]

Any table in a ``[[...]]`` list may carry ``foreach = { i = [1, 2], x = ["a", "b"] }``: the entry is
repeated once per position of the (equal-length) lists with ``{i}``, ``{x}`` substituted in every string.
A structural-only equation gives ``unknowns``, ``knowns`` and ``faults`` lists instead of ``expr``.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Iterable, Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

import sympy

from fdi_analysis.expressions import ExpressionError, der, derivative_symbols, parse_equation, parse_side
from fdi_analysis.model import Equation, Model, ModelError, Nuisance, NuisanceKind, Parameter, Role, Variable
from fdi_analysis.structure import Structure, StructureError, warn_structure

_ROLES: tuple[Role, ...] = ("unknown", "known", "fault")
_NUISANCE_TABLES = ("unknown_parameter", "unknown_input")


def load_model(path: str | Path) -> Model:
    """Load a TOML model file or an FDT-style structural JSON file."""
    return _load(Path(path), chain=())


def _load(path: Path, chain: tuple[Path, ...]) -> Model:
    path = path.resolve()
    if path in chain:
        raise ModelError("'extends' forms a cycle: " + " -> ".join(p.name for p in (*chain, path)))
    if not path.is_file():
        raise ModelError("no such model file", file=str(path))
    if path.suffix == ".json":
        return _from_fdt_json(path)
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ModelError(f"not valid TOML: {exc}", file=str(path)) from exc
    except UnicodeDecodeError as exc:
        raise ModelError(f"not a UTF-8 text file (byte {exc.start}): expected a TOML model", file=str(path)) from exc
    return _ModelBuilder(path, doc, (*chain, path)).build()


def _from_fdt_json(path: Path) -> Model:
    try:
        st = Structure.from_fdt_json(path)
    except UnicodeDecodeError as exc:
        raise ModelError(f"not a UTF-8 text file (byte {exc.start}): expected FDT JSON", file=str(path)) from exc
    except StructureError as exc:
        msg = str(exc)
        msg = msg.removeprefix(f"{path}: ")  # ModelError names the file once
        raise ModelError(msg, file=str(path)) from exc
    return model_from_structure(st, source=path)


def model_from_structure(st: Structure, source: Path | None = None) -> Model:
    """A structural-only Model from incidence matrices (an FDT structure).

    What Fault Diagnosis Toolbox accepts loads: a variable that appears in no equation is a warning naming it
    (it takes no part in the analysis), not an error as in a TOML model; repeated names were renamed, with a
    warning, by Structure.from_fdt_dict. A structure without equations stays an error."""
    eqs = []
    for r, eid in enumerate(st.equations):
        unk = tuple(st.unknowns[c] for c in range(st.nx) if st.X[r, c])
        diff = None
        d = [c for c in range(st.nx) if st.X[r, c] == 3]
        i = [c for c in range(st.nx) if st.X[r, c] == 2]
        if d and i:
            diff = (st.unknowns[d[0]], st.unknowns[i[0]])
        eqs.append(
            Equation(
                id=eid,
                unknowns=unk,
                knowns=tuple(st.knowns[c] for c in range(st.nz) if st.Z[r, c]),
                faults=tuple(st.faults[c] for c in range(st.nf) if st.F[r, c]),
                differential=diff,
            )
        )
    model = Model(
        name=st.name or (source.stem if source else "structure"),
        unknowns=tuple(Variable(n, "unknown") for n in st.unknowns),
        knowns=tuple(Variable(n, "known") for n in st.knowns),
        faults=tuple(Variable(n, "fault") for n in st.faults),
        equations=tuple(eqs),
        source=source,
    )
    where = str(source or model.name)
    if not model.equations:
        raise ModelError("the model has no equations (X has no rows)", file=where)
    for names, mat, role in ((st.unknowns, st.X, "unknown"), (st.knowns, st.Z, "known"), (st.faults, st.F, "fault")):
        for c, n in enumerate(names):
            if not mat[:, c].any():
                warn_structure(where, f"{role} {n!r} appears in no equation; loaded, it takes no part in the analysis")
    return model


# --------------------------------------------------------------------------------------------------
def expand_foreach(entry: Mapping[str, Any], where: str) -> list[dict[str, Any]]:
    """Repeat a table once per position of its `foreach` lists, substituting ``{name}`` in strings."""
    if "foreach" not in entry:
        return [dict(entry)]
    loops = entry["foreach"]
    if not isinstance(loops, dict) or not loops:
        raise ModelError("'foreach' must be a table of lists", file=where)
    lengths = {len(v) if isinstance(v, list) else -1 for v in loops.values()}
    if len(lengths) != 1 or -1 in lengths:
        raise ModelError(f"'foreach' lists must all be lists of one length, got {loops}", file=where)
    (n,) = lengths
    out = []
    for k in range(n):
        subst = {name: str(vals[k]) for name, vals in loops.items()}
        body = {key: val for key, val in entry.items() if key != "foreach"}
        out.append(_substitute(body, subst, where))
    return out


def _substitute(value: Any, subst: Mapping[str, str], where: str) -> Any:
    if isinstance(value, str):
        try:
            return value.format_map(subst)
        except (KeyError, IndexError, ValueError) as exc:
            raise ModelError(f"bad placeholder in {value!r}: {exc}", file=where) from exc
    if isinstance(value, list):
        return [_substitute(v, subst, where) for v in value]
    if isinstance(value, dict):
        return {k: _substitute(v, subst, where) for k, v in value.items()}
    return value


class _ModelBuilder:
    def __init__(self, path: Path, doc: dict[str, Any], chain: tuple[Path, ...]) -> None:
        self.path = path
        self.file = str(path)
        self.doc = doc
        self.chain = chain
        self.meta: dict[str, Any] = doc.get("model", {})
        if not isinstance(self.meta, dict):
            raise ModelError("[model] must be a table", file=self.file)
        known_meta = {"name", "description", "extends", "remove_equations", "explicit_derivatives"}
        for key in self.meta:
            if key not in known_meta:
                raise ModelError(f"unknown key {key!r} in [model] (expected one of {sorted(known_meta)})",
                                 file=self.file)
        known_top = {"model", "parameters", "unknown", "known", "fault", "equation", "eliminate",
                     *_NUISANCE_TABLES}
        for key in doc:
            if key not in known_top:
                raise ModelError(f"unknown top-level key {key!r} (expected one of {sorted(known_top)})",
                                 file=self.file)

    # ---- top level ----------------------------------------------------------------------------------
    def build(self) -> Model:
        base: Model | None = None
        if "extends" in self.meta:
            base = _load(self.path.parent / str(self.meta["extends"]), self.chain)
        params = dict(base.parameters) if base else {}
        params.update(self._parameters(params))
        variables: dict[str, Variable] = {}
        if base:
            for v in (*base.unknowns, *base.knowns, *base.faults):
                variables[v.name] = v
        for role in _ROLES:
            for raw in self._entries(role):
                name = raw.get("name")
                if not isinstance(name, str) or not name.isidentifier():
                    raise ModelError(f"[[{role}]] entry needs a valid 'name', got {name!r}", file=self.file)
                if name in variables or name in params:
                    raise ModelError(f"variable {name!r} declared twice", file=self.file, symbol=name)
                variables[name] = Variable(name, role, str(raw.get("unit", "")), str(raw.get("desc", "")),
                                           bool(raw.get("input", False)) and role == "known")
        nuisances: dict[str, Nuisance] = {n.name: n for n in base.nuisances} if base else {}
        for n in self._nuisances(variables, params):
            if n.name in nuisances:
                raise ModelError(f"{n.name!r} declared twice", file=self.file, symbol=n.name)
            nuisances[n.name] = n
        # the base's equations with its nuisances still symbols, so that eliminations carry them along
        equations: list[Equation] = list((base.nuisance_equations or base.equations) if base else [])
        removed = self.meta.get("remove_equations", [])
        for eid in removed:
            if not any(e.id == eid for e in equations):
                raise ModelError(f"remove_equations names {eid!r}, which the base model does not have",
                                 file=self.file, equation=eid)
        equations = [e for e in equations if e.id not in removed]
        symbols = {n: sympy.Symbol(n) for n in (*variables, *params, *nuisances)}
        for raw in self._entries("equation"):
            eq = self._equation(raw, variables, symbols)
            if any(e.id == eq.id for e in equations):
                raise ModelError("equation id used twice", file=self.file, equation=eq.id)
            equations.append(eq)
        if self.meta.get("explicit_derivatives", False):
            equations, variables = _make_derivatives_explicit(equations, variables, self.file)
        for raw in self._entries("eliminate"):
            equations, variables = _eliminate(
                equations, variables, str(raw.get("variable", "")), str(raw.get("equation", "")), self.file
            )
        nominal = _at_nominal(equations, nuisances, variables, self.file) if nuisances else equations
        model = Model(
            name=str(self.meta.get("name", self.path.stem)),
            description=str(self.meta.get("description", "")),
            unknowns=tuple(v for v in variables.values() if v.role == "unknown"),
            knowns=tuple(v for v in variables.values() if v.role == "known"),
            faults=tuple(v for v in variables.values() if v.role == "fault"),
            equations=tuple(nominal),
            parameters=params,
            source=self.path,
            nuisances=tuple(nuisances.values()),
            nuisance_equations=tuple(equations) if nuisances else (),
        )
        _check_usage(model, self.file)
        return model

    # ---- what the model does not know ---------------------------------------------------------------
    def _nuisances(self, variables: Mapping[str, Variable], params: Mapping[str, Parameter]) -> list[Nuisance]:
        out: list[Nuisance] = []
        for table in _NUISANCE_TABLES:
            allowed = {"name", "unit", "desc", "value", "range", "drift"}
            for raw in self._entries(table):
                name = raw.get("name")
                if not isinstance(name, str) or not name.isidentifier():
                    raise ModelError(f"[[{table}]] entry needs a valid 'name', got {name!r}", file=self.file)
                for key in raw:
                    if key not in allowed:
                        raise ModelError(f"[[{table}]] {name!r}: unknown key {key!r} (expected one of "
                                         f"{sorted(allowed)})", file=self.file, symbol=name)
                if name in variables or name in params or any(n.name == name for n in out):
                    raise ModelError(f"{name!r} declared twice", file=self.file, symbol=name)
                where = f"[[{table}]] {name!r}"
                value = _finite(raw.get("value", 0.0), f"{where}: 'value'", self.file, name)
                if "range" not in raw:
                    raise ModelError(f"{where} needs a 'range' = [lo, hi]: what a vehicle may hold", file=self.file,
                                     symbol=name)
                lo, hi = _range(raw["range"], value, where, self.file, name)
                drift = _finite(raw.get("drift", 0.0), f"{where}: 'drift'", self.file, name)
                if drift < 0.0:
                    raise ModelError(f"{where}: 'drift' must be >= 0 (units per second), got {drift}",
                                     file=self.file, symbol=name)
                kind: NuisanceKind = "input" if table == "unknown_input" else ("slow" if drift > 0.0 else "constant")
                out.append(Nuisance(name, kind, (lo, hi), value, str(raw.get("unit", "")), str(raw.get("desc", "")),
                                    drift))
        return out

    def _entries(self, key: str) -> list[dict[str, Any]]:
        raw = self.doc.get(key, [])
        if not isinstance(raw, list):
            raise ModelError(f"'{key}' must be an array of tables ([[{key}]])", file=self.file)
        out: list[dict[str, Any]] = []
        for entry in raw:
            out.extend(expand_foreach(entry, self.file))
        return out

    # ---- parameters ---------------------------------------------------------------------------------
    def _parameters(self, inherited: Mapping[str, Parameter]) -> dict[str, Parameter]:
        raw = self.doc.get("parameters", {})
        if not isinstance(raw, dict):
            raise ModelError("[parameters] must be a table", file=self.file)
        values: dict[str, float] = {n: p.value for n, p in inherited.items()}
        pending: dict[str, tuple[str, dict[str, Any]]] = {}
        out: dict[str, Parameter] = {}
        for name, spec in raw.items():
            if isinstance(spec, int | float):
                spec = {"value": spec}
            if not isinstance(spec, dict) or ("value" in spec) == ("expr" in spec):
                raise ModelError(f"parameter {name!r} needs exactly one of 'value' or 'expr'",
                                 file=self.file, symbol=name)
            unexpected = set(spec) - {"value", "expr", "unit", "desc", "range"}
            if unexpected:
                raise ModelError(f"parameter {name!r}: unknown key {sorted(unexpected)[0]!r} (expected value or "
                                 "expr, unit, desc, range)", file=self.file, symbol=name)
            if "value" in spec:
                value = _finite(spec["value"], f"parameter {name!r}: 'value'", self.file, name)
                rng = _range(spec["range"], value, f"parameter {name!r}", self.file, name) if "range" in spec else None
                values[name] = value
                out[name] = Parameter(name, value, str(spec.get("unit", "")), str(spec.get("desc", "")), rng)
            else:
                if "range" in spec:
                    raise ModelError(f"parameter {name!r}: a 'range' belongs to a parameter with a 'value'; an "
                                     "'expr' parameter follows the ranges of the parameters it uses",
                                     file=self.file, symbol=name)
                pending[name] = (str(spec["expr"]), spec)
        while pending:
            progressed = False
            for name, (text, spec) in list(pending.items()):
                syms = {n: sympy.Symbol(n) for n in (*values, *pending)}
                try:
                    expr = parse_side(text, syms)
                except ExpressionError as exc:
                    raise ModelError(f"parameter {name!r}: {exc}", file=self.file, symbol=exc.symbol) from exc
                if any(str(s) in pending for s in expr.free_symbols):
                    continue
                try:
                    val = float(expr.subs({sympy.Symbol(n): v for n, v in values.items()}))
                except (TypeError, ValueError) as exc:
                    raise ModelError(f"parameter {name!r}: {text!r} does not evaluate to a real number",
                                     file=self.file, symbol=name) from exc
                if not math.isfinite(val):
                    raise ModelError(f"parameter {name!r}: {text!r} evaluates to {val}, not a finite number",
                                     file=self.file, symbol=name)
                values[name] = val
                out[name] = Parameter(name, val, str(spec.get("unit", "")), str(spec.get("desc", "")))
                del pending[name]
                progressed = True
            if not progressed:
                raise ModelError(f"parameters {sorted(pending)} depend on each other in a cycle", file=self.file)
        return out

    # ---- equations ----------------------------------------------------------------------------------
    def _equation(self, raw: dict[str, Any], variables: Mapping[str, Variable],
                  symbols: Mapping[str, sympy.Symbol]) -> Equation:
        eid = raw.get("id")
        if not isinstance(eid, str) or not eid:
            raise ModelError(f"an equation has no 'id': {raw}", file=self.file)
        allowed = {"id", "expr", "differential", "unknowns", "knowns", "faults", "desc", "group",
                   "not_solvable_for"}
        for key in raw:
            if key not in allowed:
                raise ModelError(f"unknown key {key!r}", file=self.file, equation=eid)
        desc, group = str(raw.get("desc", "")), str(raw.get("group", ""))
        has_lists = any(k in raw for k in ("unknowns", "knowns", "faults"))
        n_forms = sum(("expr" in raw, "differential" in raw, has_lists))
        if n_forms != 1:
            raise ModelError("give exactly one of 'expr', 'differential', or the structural lists "
                             "'unknowns'/'knowns'/'faults'", file=self.file, equation=eid)
        if "differential" in raw:
            pair = raw["differential"]
            if not isinstance(pair, list) or len(pair) != 2:
                raise ModelError(f"differential constraint needs the pair [dx, x], got {pair!r}",
                                 file=self.file, equation=eid)
            for n in pair:
                var = variables.get(str(n))
                if var is None or var.role != "unknown":
                    raise ModelError(f"differential constraint pair {pair!r}: {n!r} is not a declared unknown",
                                     file=self.file, equation=eid, symbol=str(n))
            if pair[0] == pair[1]:
                raise ModelError("differential constraint pairs a variable with itself", file=self.file,
                                 equation=eid, symbol=str(pair[0]))
            dx, x = str(pair[0]), str(pair[1])
            return Equation(id=eid, unknowns=(dx, x), knowns=(), faults=(), lhs=sympy.Symbol(dx),
                            rhs=der(sympy.Symbol(x)), differential=(dx, x), desc=desc, group=group)
        if has_lists:
            lists: dict[str, tuple[str, ...]] = {}
            for key, role in (("unknowns", "unknown"), ("knowns", "known"), ("faults", "fault")):
                listed = raw.get(key, [])
                if not isinstance(listed, list) or not all(isinstance(n, str) for n in listed):
                    raise ModelError(f"'{key}' must be a list of names, got {listed!r}", file=self.file,
                                     equation=eid)
                names = tuple(listed)
                for n in names:
                    var = variables.get(n)
                    if var is None:
                        raise ModelError(f"undeclared symbol {n!r}", file=self.file, equation=eid, symbol=n)
                    if var.role != role:
                        raise ModelError(f"{n!r} is listed under {key} but declared as {var.role}",
                                         file=self.file, equation=eid, symbol=n)
                lists[key] = names
            eq = Equation(id=eid, unknowns=lists["unknowns"], knowns=lists["knowns"], faults=lists["faults"],
                          desc=desc, group=group)
        else:
            if not isinstance(raw["expr"], str):
                raise ModelError(f"'expr' must be a string such as \"y = x + f\", got {raw['expr']!r}",
                                 file=self.file, equation=eid)
            try:
                lhs, rhs = parse_equation(raw["expr"], symbols)
            except ExpressionError as exc:
                raise ModelError(str(exc), file=self.file, equation=eid, symbol=exc.symbol) from exc
            eq = with_expression(Equation(id=eid, unknowns=(), knowns=(), faults=(), desc=desc, group=group),
                                  lhs, rhs, variables, self.file)
        nsf = tuple(str(n) for n in raw.get("not_solvable_for", []))
        for n in nsf:
            if n not in eq.unknowns:
                raise ModelError(f"not_solvable_for names {n!r}, which is not an unknown of this equation",
                                 file=self.file, equation=eid, symbol=n)
        eq = replace(eq, not_solvable_for=nsf)
        if not eq.unknowns:
            raise ModelError("equation has no unknowns", file=self.file, equation=eid)
        return eq


def with_expression(eq: Equation, lhs: sympy.Expr, rhs: sympy.Expr, variables: Mapping[str, Variable],
                     file: str) -> Equation:
    """Set the expression and derive the variable lists from it."""
    order = {n: i for i, n in enumerate(variables)}
    names = sorted({str(s) for s in (lhs.free_symbols | rhs.free_symbols) if str(s) in variables},
                   key=order.__getitem__)
    derivs = tuple(sorted(derivative_symbols(lhs) | derivative_symbols(rhs), key=lambda n: order.get(n, -1)))
    for d in derivs:
        if d not in variables or variables[d].role != "unknown":
            raise ModelError(f"der({d}) is only allowed on a declared unknown", file=file, equation=eq.id,
                             symbol=d)
    return replace(
        eq,
        lhs=lhs,
        rhs=rhs,
        unknowns=tuple(n for n in names if variables[n].role == "unknown"),
        knowns=tuple(n for n in names if variables[n].role == "known"),
        faults=tuple(n for n in names if variables[n].role == "fault"),
        derivatives=derivs,
    )


def _make_derivatives_explicit(equations: list[Equation], variables: dict[str, Variable],
                               file: str) -> tuple[list[Equation], dict[str, Variable]]:
    """Replace each inline der(x) by a new unknown ``dx`` and add ``dx = d/dt x`` after the equation."""
    out: list[Equation] = []
    variables = dict(variables)
    for eq in equations:
        if not eq.derivatives or eq.lhs is None or eq.rhs is None:
            out.append(eq)
            continue
        subs = {}
        new_diff = []
        for x in eq.derivatives:
            dname = f"d{x}"
            if dname in variables:
                raise ModelError(f"explicit_derivatives: the name {dname!r} for d/dt {x} is already taken",
                                 file=file, equation=eq.id, symbol=dname)
            variables[dname] = Variable(dname, "unknown", "", f"time derivative of {x}")
            subs[der(sympy.Symbol(x))] = sympy.Symbol(dname)
            new_diff.append(Equation(id=f"D.{x}", unknowns=(dname, x), knowns=(), faults=(),
                                     lhs=sympy.Symbol(dname), rhs=der(sympy.Symbol(x)), differential=(dname, x),
                                     desc=f"{dname} = d/dt {x} (made explicit from {eq.id})", group=eq.group))
        out.append(with_expression(eq, eq.lhs.xreplace(subs), eq.rhs.xreplace(subs), variables, file))
        out.extend(new_diff)
    return out, variables


def _solve_for(eq: Equation, var: str, file: str) -> sympy.Expr:
    assert eq.lhs is not None and eq.rhs is not None
    s = sympy.Symbol(var)
    for a, b in ((eq.lhs, eq.rhs), (eq.rhs, eq.lhs)):
        if a == s and s not in b.free_symbols:
            return b
    sols = sympy.solve(sympy.Eq(eq.lhs, eq.rhs), s, dict=False)
    if len(sols) != 1:
        raise ModelError(f"cannot eliminate {var!r}: the equation has {len(sols)} solutions for it",
                         file=file, equation=eq.id, symbol=var)
    sol: sympy.Expr = sols[0]
    return sol


def _eliminate(equations: list[Equation], variables: dict[str, Variable], var: str, eq_id: str,
               file: str) -> tuple[list[Equation], dict[str, Variable]]:
    """Step-4 grouping: solve `eq_id` for `var`, substitute it everywhere, drop both."""
    src = next((e for e in equations if e.id == eq_id), None)
    if src is None:
        raise ModelError(f"eliminate: no equation {eq_id!r}", file=file, equation=eq_id)
    if var not in src.unknowns:
        raise ModelError(f"eliminate: {var!r} is not an unknown of this equation", file=file, equation=eq_id,
                         symbol=var)
    for e in equations:
        if var in e.unknowns and (e.differential is not None or var in e.derivatives):
            raise ModelError(f"eliminate: {var!r} is a dynamic variable (used in {e.id!r})", file=file,
                             equation=eq_id, symbol=var)
    symbolic = src.lhs is not None
    sol = _solve_for(src, var, file) if symbolic else None
    s = sympy.Symbol(var)
    out = []
    for e in equations:
        if e.id == eq_id:
            continue
        if var not in e.unknowns:
            out.append(e)
            continue
        merged = tuple(dict.fromkeys([*(e.merged_from or (e.id,)), *(src.merged_from or (src.id,))]))
        if symbolic and e.lhs is not None and e.rhs is not None and sol is not None:
            ne = with_expression(e, e.lhs.subs(s, sol), e.rhs.subs(s, sol),
                                  {n: v for n, v in variables.items() if n != var}, file)
        else:
            def merge(a: Iterable[str], b: Iterable[str]) -> tuple[str, ...]:
                return tuple(dict.fromkeys([*a, *b]))
            ne = replace(e, unknowns=tuple(n for n in merge(e.unknowns, src.unknowns) if n != var),
                         knowns=merge(e.knowns, src.knowns), faults=merge(e.faults, src.faults))
        out.append(replace(ne, merged_from=merged, not_solvable_for=_merged_not_solvable(ne, e, src, var)))
    variables = {n: v for n, v in variables.items() if n != var}
    return out, variables


def _merged_not_solvable(merged: Equation, receiving: Equation, src: Equation, var: str) -> tuple[str, ...]:
    """not_solvable_for of `receiving` after `var` (from `src`) was substituted into it: its own pairs, the
    pairs of `src` (var is a non-invertible function of them, so the merged equation is too), and, when
    `receiving` cannot be solved for `var`, every unknown that enters through var. Restricted to the merged
    equation's unknowns, in their order."""
    blocked = set(receiving.not_solvable_for) | set(src.not_solvable_for)
    if var in receiving.not_solvable_for:
        blocked |= set(src.unknowns)
    blocked.discard(var)
    return tuple(u for u in merged.unknowns if u in blocked)


def _finite(value: Any, what: str, file: str, symbol: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ModelError(f"{what} must be a finite number, got {value!r}", file=file, symbol=symbol)
    return float(value)


def _range(raw: Any, value: float, where: str, file: str, symbol: str) -> tuple[float, float]:
    """[lo, hi] with lo < hi and the nominal value inside."""
    if not isinstance(raw, list) or len(raw) != 2:
        raise ModelError(f"{where}: 'range' must be [lo, hi], got {raw!r}", file=file, symbol=symbol)
    lo = _finite(raw[0], f"{where}: 'range' lower bound", file, symbol)
    hi = _finite(raw[1], f"{where}: 'range' upper bound", file, symbol)
    if not lo < hi:
        raise ModelError(f"{where}: 'range' [{lo:g}, {hi:g}] is empty (lo must be below hi)", file=file, symbol=symbol)
    if not lo <= value <= hi:
        raise ModelError(f"{where}: the nominal value {value:g} lies outside its range [{lo:g}, {hi:g}]", file=file,
                         symbol=symbol)
    return lo, hi


def nominal_number(value: float) -> sympy.Expr:
    """A nuisance's value as it enters an equation: an exact 0 (the term vanishes), else a float."""
    return sympy.Integer(0) if value == 0.0 else sympy.Float(value)


def _at_nominal(equations: list[Equation], nuisances: Mapping[str, Nuisance], variables: Mapping[str, Variable],
                file: str) -> list[Equation]:
    """The equations with every nuisance at its nominal value (the model as it was before they were declared);
    an error names a nuisance that no equation holds."""
    subs = {sympy.Symbol(n.name): nominal_number(n.value) for n in nuisances.values()}
    used: set[str] = set()
    out = []
    for e in equations:
        if e.lhs is None or e.rhs is None or e.differential is not None:
            out.append(e)
            continue
        held = {str(s) for s in (e.lhs.free_symbols | e.rhs.free_symbols)} & set(nuisances)
        if not held:
            out.append(e)
            continue
        used |= held
        out.append(with_expression(e, e.lhs.xreplace(subs), e.rhs.xreplace(subs), variables, file))
    for name, n in nuisances.items():
        if name not in used:
            kind = "unknown input" if n.kind == "input" else "unknown parameter"
            raise ModelError(f"{kind} {name!r} appears in no equation", file=file, symbol=name)
    return out


def _check_usage(model: Model, file: str) -> None:
    if not model.equations:
        raise ModelError("the model has no equations (expected [[equation]] entries)", file=file)
    used: set[str] = set()
    for e in model.equations:
        used.update(e.unknowns, e.knowns, e.faults)
    for v in (*model.unknowns, *model.knowns, *model.faults):
        if v.name not in used:
            raise ModelError(f"{v.role} {v.name!r} appears in no equation", file=file, symbol=v.name)
    ids: set[str] = set()
    for e in model.equations:
        if e.id in ids:
            raise ModelError("equation id used twice", file=file, equation=e.id)
        ids.add(e.id)


def export_fdt_json(model: Model, path: Path) -> None:
    """Write the model's structure in the JSON form Fault Diagnosis Toolbox users hold."""
    model.structure().to_fdt_json(path)
