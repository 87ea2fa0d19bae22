"""Sensitivity of a residual generator to what the model does not know: d r / d theta for every uncertain
parameter (declared with a range) and every nuisance the residual is not decoupled from, analytically.

The same machinery as the fault sensitivities (`fdi_analysis.residuals.sensitivity`): in the perturbed model
(`fdi_analysis.uncertainty.perturbed`) each such theta is its nominal value plus a perturbation that the
model declares as a fault, so the generator's computation sequence run with the faults kept gives the residual
under a vehicle whose theta differs by delta, H(u, delta), and

    r = H(u, 0) ~ -dH/d delta (u, 0) delta                 sensitivity  s_theta = -dH/d delta at delta = 0

for a vehicle that holds theta0 + delta (constant over the operating point): positive s_theta means the
residual rises on a vehicle with a larger theta. An observer generator absorbs part of it, as of a fault. An input
that no estimator follows (`bounded_whole`: the road's friction, from dry asphalt down to ice) is taken by its
secant to the far end of its range instead, -(H(u, delta_far) - H(u, 0)) / delta_far: the tyre law is far from
linear in it, and its first-order term at the dry road would understate what ice does by a factor of several.

Over a box of uncertainty (each theta anywhere in its declared range), the residual's worst-case spread at an
operating point is, to first order,

    spread(u) = sum over theta of |s_theta(u)| * w_theta        w_theta = max(hi - theta0, theta0 - lo)

and a fault's fault-to-uncertainty ratio is |s_f(u)| size_f / spread(u), next to its fault-to-noise ratio
|s_f(u)| size_f / sigma. The expressions are over the generator's node symbols, like the fault sensitivities,
so the C step can compute the spread from the same common subexpressions (an adaptive threshold)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np
import sympy
from numpy.typing import NDArray

from fdi_analysis.model import Model
from fdi_analysis.residuals.evaluate import FilterDesign, sensitivity_series
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.sensitivity import fault_sensitivities
from fdi_analysis.residuals.solvability import Solver
from fdi_analysis.uncertainty import perturbation_name, perturbed

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Uncertainty:
    """One uncertain quantity of a model: a parameter with a range, or a nuisance not decoupled."""

    name: str
    kind: str  # "parameter", or the nuisance's kind ("constant", "slow", "input")
    nominal: float
    range: tuple[float, float]
    unit: str = ""
    drift: float = 0.0  # units per second: how fast it may change (0: constant for a vehicle; an input: not followed)

    @property
    def half_width(self) -> float:
        """The largest deviation from the nominal value inside the range."""
        return max(self.range[1] - self.nominal, self.nominal - self.range[0])


def uncertainties(model: Model) -> tuple[Uncertainty, ...]:
    """The model's uncertain parameters, then its nuisances (those a decoupling left), in declared order."""
    out = [Uncertainty(p.name, "parameter", p.value, p.range, p.unit)
           for p in model.uncertain_parameters().values() if p.range is not None]
    out += [Uncertainty(n.name, n.kind, n.value, n.range, n.unit, n.drift) for n in model.nuisances]
    return tuple(out)


class UncertaintySolver:
    """The perturbed models of `model` (one per uncertain quantity) and their fault-keeping solvers, built on
    first use and kept for many generators."""

    def __init__(self, model: Model) -> None:
        self.model = model
        self.quantities = uncertainties(model)
        self._solvers: dict[str, Solver] = {}

    def solver(self, name: str) -> Solver:
        if name not in self._solvers:
            self._solvers[name] = Solver(perturbed(self.model, name), keep_faults=True)
        return self._solvers[name]


def uncertainty_sensitivities(model: Model, g: Generator, solver: UncertaintySolver | None = None
                              ) -> tuple[tuple[str, sympy.Expr], ...]:
    """(name, d r / d theta) for every uncertain parameter and nuisance that `g`'s equations hold and whose
    sensitivity is not identically zero, in the model's declared order; () when the generator's residual
    cannot be formed with the faults kept (a node above its filter level, as for its fault sensitivities)."""
    us = solver or UncertaintySolver(model)
    raw = {e.id: e for e in model.nuisance_equations or model.equations}  # nuisances still symbols
    held: set[str] = set()
    for e in (raw.get(eq, model.equation(eq)) for eq in g.equations):
        if e.lhs is not None and e.rhs is not None:
            held.update(str(s) for s in e.lhs.free_symbols | e.rhs.free_symbols)
    out: list[tuple[str, sympy.Expr]] = []
    for u in us.quantities:
        if u.name not in held:
            continue
        pname = perturbation_name(u.name)
        s = us.solver(u.name)
        secant = {pname: far_end(u)} if bounded_whole(u) else None
        sens = dict(fault_sensitivities(s.model, replace(g, faults=(pname,)), s, secant))
        if pname in sens:
            out.append((u.name, sens[pname]))
    return tuple(out)


def bounded_whole(u: Uncertainty) -> bool:
    """An input no estimator follows (no declared drift: the road's friction): it may sit anywhere in its range at
    any time, so its term must hold over the whole range, not to first order at the nominal value."""
    return u.kind == "input" and u.drift <= 0.0


def far_end(u: Uncertainty) -> float:
    """The deviation from the nominal value to the farther end of the range (its sign included)."""
    lo, hi = u.range[0] - u.nominal, u.range[1] - u.nominal
    return hi if hi >= -lo else lo


def with_uncertainty(model: Model, g: Generator, solver: UncertaintySolver | None = None) -> Generator:
    """`g` carrying its uncertainty sensitivities (`Generator.uncertainty`, what the generated step turns into
    the adaptive threshold's spread)."""
    return replace(g, uncertainty=uncertainty_sensitivities(model, g, solver))


def half_widths(model: Model) -> dict[str, float]:
    """w_theta of every uncertain quantity of `model` (`Uncertainty.half_width`), by name."""
    return {u.name: u.half_width for u in uncertainties(model)}


def spread_series(g: Generator, sensitivities: tuple[tuple[str, sympy.Expr], ...],
                  widths: Mapping[str, float], signals: Mapping[str, FloatArray],
                  design: FilterDesign | None = None) -> tuple[FloatArray, dict[str, FloatArray]]:
    """(worst-case spread of the residual at every sample, each theta's share |s_theta| w_theta) along
    `signals`; `widths` holds w_theta per name (`Uncertainty.half_width`)."""
    n = len(next(iter(signals.values())))
    if not sensitivities:
        return np.zeros(n), {}
    series = sensitivity_series(replace(g, sensitivities=sensitivities), signals, design)
    parts = {name: np.abs(s) * widths[name] for name, s in series.items()}
    total = np.sum(np.vstack(list(parts.values())), axis=0)
    return np.asarray(total, dtype=float), parts



def offset_like(sensitivities: tuple[tuple[str, sympy.Expr], ...]) -> tuple[str, ...]:
    """The quantities whose d r / d theta is a constant (no signal in it): they add an offset to the residual
    that does not depend on the operating point, which an on-line offset estimator (fw/include/fdi_est.h) can
    follow; the others (a mass, a tyre stiffness) scale with the manoeuvre and it cannot."""
    return tuple(name for name, s in sensitivities if not sympy.sympify(s).free_symbols)


def is_offset_like(sensitivities: tuple[tuple[str, sympy.Expr], ...]) -> bool:
    """Every uncertainty of the residual enters as an offset (`offset_like`), and there is at least one: the
    test belongs in the diagnoser's estimate mask (fdi_diag_config_t.estimate)."""
    return bool(sensitivities) and len(offset_like(sensitivities)) == len(sensitivities)
