"""The typed model: variables, parameters and equations, and the structure derived from them.

A `Model` comes from `fdi_analysis.model_loader.load_model`. Its bipartite structure (`Model.structure`)
is derived from the equations' expressions, never typed separately; a purely structural model (no
expressions) carries the variable lists per equation instead.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np
import sympy

from fdi_analysis.errors import FdiError
from fdi_analysis.structure import DIFF_DERIVATIVE, DIFF_INTEGRATED, INCIDENCE, Structure

Role = Literal["unknown", "known", "fault"]
EquationKind = Literal["normal", "differential", "measurement"]
NuisanceKind = Literal["constant", "slow", "input"]


class ModelError(FdiError, ValueError):
    """A model file that is not well formed. The message names the file, the equation and the symbol."""

    def __init__(
        self, message: str, *, file: str = "", equation: str | None = None, symbol: str | None = None
    ) -> None:
        where = file or "<model>"
        if equation is not None:
            where += f": equation {equation!r}"
        super().__init__(f"{where}: {message}")
        self.file = file
        self.equation = equation
        self.symbol = symbol


@dataclass(frozen=True)
class Variable:
    name: str
    role: Role
    unit: str = ""
    desc: str = ""
    input: bool = False  # a known that drives the system (actuator command) rather than a measurement


@dataclass(frozen=True)
class Parameter:
    """A model constant. With `range` it is an uncertain parameter: the model uses `value`, the vehicle's lies
    anywhere in [lo, hi] (the residuals stay coupled to it; their spread over the range bounds the thresholds)."""

    name: str
    value: float
    unit: str = ""
    desc: str = ""
    range: tuple[float, float] | None = None


@dataclass(frozen=True)
class Nuisance:
    """Something the model does not know and the diagnosis must not mistake for a fault.

    * ``constant``: an unknown constant parameter (a sensor bias); ``slow``: one that varies slowly, at most
      `drift` units per second (a bias with drift, the payload). Decoupled as an unknown with a zero derivative.
    * ``input``: an unknown input (road grade, bank, driving resistance). Decoupled as an unknown without an
      equation of its own. Its `drift`, when given, is the fastest change (units per second) the on-line
      estimators follow (fw/include/fdi_est.h); without one no estimator follows it (a road's friction).

    The nominal model sets it to `value`; `range` is what a vehicle may hold."""

    name: str
    kind: NuisanceKind
    range: tuple[float, float]
    value: float = 0.0
    unit: str = ""
    desc: str = ""
    drift: float = 0.0


@dataclass(frozen=True)
class Equation:
    """One model equation ``lhs = rhs`` with the variables it holds.

    `differential` is set for a differential constraint ``dx = d/dt x`` as the pair ``(dx, x)``;
    `derivatives` lists the unknowns that appear inline as ``der(x)``. `not_solvable_for` lists the
    unknowns this equation must not be solved for when building a computation sequence.
    """

    id: str
    unknowns: tuple[str, ...]
    knowns: tuple[str, ...]
    faults: tuple[str, ...]
    lhs: sympy.Expr | None = None
    rhs: sympy.Expr | None = None
    differential: tuple[str, str] | None = None
    derivatives: tuple[str, ...] = ()
    desc: str = ""
    group: str = ""
    merged_from: tuple[str, ...] = ()
    not_solvable_for: tuple[str, ...] = ()

    @property
    def kind(self) -> EquationKind:
        if self.differential is not None:
            return "differential"
        if self.knowns:
            return "measurement"
        return "normal"

    @property
    def residual(self) -> sympy.Expr:
        """``lhs - rhs`` (zero when the equation holds)."""
        if self.lhs is None or self.rhs is None:
            raise ValueError(f"equation {self.id!r} is structural only (no expression)")
        return sympy.Add(self.lhs, -self.rhs)

    def text(self) -> str:
        if self.differential is not None:
            return f"{self.differential[0]} = d/dt {self.differential[1]}"
        if self.lhs is None or self.rhs is None:
            return ""
        return f"{sympy.sstr(self.lhs)} = {sympy.sstr(self.rhs)}"


@dataclass(frozen=True)
class Model:
    name: str
    unknowns: tuple[Variable, ...]
    knowns: tuple[Variable, ...]
    faults: tuple[Variable, ...]
    equations: tuple[Equation, ...]
    parameters: dict[str, Parameter] = field(default_factory=dict)
    description: str = ""
    source: Path | None = None
    nuisances: tuple[Nuisance, ...] = ()
    # the equations with the nuisances as symbols (`equations` holds them at their nominal values); empty when the
    # model declares no nuisance. `fdi_analysis.uncertainty.decoupled` makes them unknowns.
    nuisance_equations: tuple[Equation, ...] = ()

    @property
    def symbolic(self) -> bool:
        """True when every equation carries an expression (the model can be simulated)."""
        return all(e.lhs is not None or e.differential is not None for e in self.equations)

    def equation(self, eq_id: str) -> Equation:
        return self._equations_by_id[eq_id]

    @functools.cached_property
    def _equations_by_id(self) -> dict[str, Equation]:
        return {e.id: e for e in self.equations}

    def symbol(self, name: str) -> sympy.Symbol:
        return sympy.Symbol(name)

    def parameter_values(self) -> dict[str, float]:
        return {p.name: p.value for p in self.parameters.values()}

    def uncertain_parameters(self) -> dict[str, Parameter]:
        """The parameters declared with a range."""
        return {n: p for n, p in self.parameters.items() if p.range is not None}

    def counts(self) -> dict[str, int]:
        kinds = [e.kind for e in self.equations]
        return {
            "equations": len(self.equations),
            "normal_equations": sum(k != "measurement" for k in kinds),
            "measurement_equations": kinds.count("measurement"),
            "differential_constraints": kinds.count("differential"),
            "unknowns": len(self.unknowns),
            "knowns": len(self.knowns),
            "faults": len(self.faults),
        }

    def structure(self) -> Structure:
        """The incidence structure (X with FDT differential markings, F, Z)."""
        xs = [v.name for v in self.unknowns]
        zs = [v.name for v in self.knowns]
        fs = [v.name for v in self.faults]
        xi = {n: i for i, n in enumerate(xs)}
        zi = {n: i for i, n in enumerate(zs)}
        fi = {n: i for i, n in enumerate(fs)}
        ne = len(self.equations)
        X = np.zeros((ne, len(xs)), dtype=np.int8)
        Z = np.zeros((ne, len(zs)), dtype=np.int8)
        F = np.zeros((ne, len(fs)), dtype=np.int8)
        for r, e in enumerate(self.equations):
            for u in e.unknowns:
                X[r, xi[u]] = INCIDENCE
            if e.differential is not None:
                X[r, xi[e.differential[0]]] = DIFF_DERIVATIVE
                X[r, xi[e.differential[1]]] = DIFF_INTEGRATED
            for k in e.knowns:
                Z[r, zi[k]] = 1
            for f in e.faults:
                F[r, fi[f]] = 1
        return Structure(
            equations=tuple(e.id for e in self.equations),
            unknowns=tuple(xs),
            knowns=tuple(zs),
            faults=tuple(fs),
            X=X,
            F=F,
            Z=Z,
            name=self.name,
            equation_kinds=tuple(e.kind for e in self.equations),
        )
