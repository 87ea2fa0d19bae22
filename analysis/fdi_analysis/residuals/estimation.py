"""What the on-line estimator of a test estimates (fw/include/fdi_est.h): a few of the model's uncertain quantities,
each as its deviation from the model's value, with the residual's sensitivity to it as the regressor.

A test's estimated quantities are given as groups of names (the thresholds file's [estimation] table): a group of
one name is that quantity, its regressor d r / d theta; a group of several names is an offset, the quantities of a
residual that enter it with constant sensitivities c_k (an accelerometer bias and the grade in the longitudinal
inertial test: the residual cannot tell them apart, it needs only their sum), estimated as o = sum c_k theta_k with
regressor 1.

Each estimated quantity's declaration, for the Kalman filter of fdi_est.h (deviations from the model's value):

    prior mean  (lo + hi) / 2 - nominal        a vehicle anywhere in the declared range
    prior var   (hi - lo)^2 / 12               uniform over it
    q           (drift * dt / RAMP_LAG)^2      per step, for a quantity that may change (a bias's drift, the grade):
                                               a random walk of this step variance is what a Kalman filter follows
                                               with a steady gain K ~ drift dt / (RAMP_LAG sigma), so a ramp at the
                                               declared drift lags by RAMP_LAG residual sigmas (sigma: the test's
                                               noise) and a step fault is absorbed at K per step until it alarms
                var * dt / CONSTANT_FORGET_S   for a vehicle's constant (forgets over an hour)
    bounds      [lo - nominal, hi - nominal]
    step        max(drift, (hi - lo) / LEARN_S) * dt   the most the estimate moves in one step: no faster than the
                                               quantity can change, or than the learning of its range takes; a fault
                                               that the estimate would follow faster is absorbed no faster

and for an offset the sums of c_k theta_k's (means, variances, q, the bounds' sum of the extremes). An unknown input
without a drift (the road's friction, which changes where the road does) is never estimated."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import sympy

from fdi_analysis.errors import FdiError
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.uncertainty_sensitivity import Uncertainty

CONSTANT_FORGET_S = 3600.0  # a vehicle's constant: its estimate's variance regrows over an hour
RAMP_LAG = 2.0  # [residual sigmas] how far an estimate lags behind a quantity changing at its declared drift
LEARN_S = 5.0  # [s] the shortest time an estimate crosses its quantity's whole range in (`Estimated.step`)


class EstimationError(FdiError, ValueError):
    """An [estimation] entry the test cannot estimate: a name it holds no sensitivity to, an input without a drift,
    a group of quantities whose sensitivities are not constants."""


@dataclass(frozen=True)
class Estimated:
    """One estimated quantity (or offset) of a test: its regressor and its declaration (units of the quantity)."""

    names: tuple[str, ...]
    regressor: sympy.Expr  # d r / d theta over the generator's node symbols (1 for an offset)
    mean: float
    var: float
    q: float  # per step
    lo: float
    hi: float
    step: float  # the most the estimate moves in one step

    @property
    def label(self) -> str:
        return " + ".join(self.names) if len(self.names) > 1 else self.names[0]

    @property
    def width(self) -> float:
        """The largest deviation inside the bounds (the adaptive threshold's weight without estimation)."""
        return max(-self.lo, self.hi)


def _one(u: Uncertainty, dt: float) -> tuple[float, float, float, float, float, float]:
    lo, hi = u.range[0] - u.nominal, u.range[1] - u.nominal
    var = (hi - lo) ** 2 / 12.0
    step = max(u.drift, (hi - lo) / LEARN_S) * dt
    if u.drift > 0.0:
        q = (u.drift * dt / RAMP_LAG) ** 2
    elif u.kind == "input":
        raise EstimationError(f"{u.name} is an input without a declared drift: it may change at any time, so no "
                              "estimator follows it (declare its drift in the model to estimate it)")
    else:
        q = var * dt / CONSTANT_FORGET_S
    return (lo + hi) / 2.0, var, q, lo, hi, step


def estimated(g: Generator, groups: Sequence[Sequence[str]], quantities: Mapping[str, Uncertainty],
              dt: float) -> tuple[Estimated, ...]:
    """The estimated quantities of generator `g` (with its uncertainty sensitivities, `Generator.uncertainty`) for the
    groups of names `groups`, in that order; `quantities`: the model's uncertain quantities by name."""
    sens = dict(g.uncertainty)
    out: list[Estimated] = []
    seen: set[str] = set()
    for group in groups:
        names = tuple(group)
        if not names:
            raise EstimationError(f"{g.name}: an empty [estimation] group")
        for n in names:
            if n in seen:
                raise EstimationError(f"{g.name}: {n} is estimated twice")
            if n not in sens:
                raise EstimationError(f"{g.name}: its residual holds no sensitivity to {n!r} (it holds "
                                      f"{', '.join(sens) or 'none'})")
            seen.add(n)
        decl = [_one(quantities[n], dt) for n in names]
        if len(names) == 1:
            mean, var, q, lo, hi, step = decl[0]
            out.append(Estimated(names, sympy.sympify(sens[names[0]]), mean, var, q, lo, hi, step))
            continue
        c = [sympy.sympify(sens[n]) for n in names]
        if not all(x.is_Number for x in c):
            raise EstimationError(f"{g.name}: {' '.join(names)} lumped as one offset, but the sensitivity of "
                                  f"{', '.join(n for n, x in zip(names, c, strict=True) if not x.is_Number)} "
                                  "is not a constant")
        k = [float(x) for x in c]
        out.append(Estimated(
            names, sympy.Integer(1),
            mean=sum(ki * d[0] for ki, d in zip(k, decl, strict=True)),
            var=sum(ki * ki * d[1] for ki, d in zip(k, decl, strict=True)),
            q=sum(ki * ki * d[2] for ki, d in zip(k, decl, strict=True)),
            lo=sum(min(ki * d[3], ki * d[4]) for ki, d in zip(k, decl, strict=True)),
            hi=sum(max(ki * d[3], ki * d[4]) for ki, d in zip(k, decl, strict=True)),
            step=sum(abs(ki) * d[5] for ki, d in zip(k, decl, strict=True))))
    return tuple(out)
