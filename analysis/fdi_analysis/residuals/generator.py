"""A synthesised residual generator: the computation sequence and its residual over filtered signals."""

from __future__ import annotations

from dataclasses import dataclass

import sympy

from fdi_analysis.residuals.signals import Node
from fdi_analysis.residuals.whole_terms import Composite

DOMAIN_SIGNAL = "vx_m"  # measured signal of the operating-domain condition (longitudinal speed)
# The domain of a residual with a regularised slip (Max(..., v_eps) in an equation it uses) starts at
# DOMAIN_FACTOR * v_eps: there the normaliser is the wheel's own speed with margin, and the relative error of
# the filtered speeds (all delayed alike, but differentiated and divided) is small.
DOMAIN_FACTOR = 4.0
# A tyre law holds near its linear range only: a generator with a tyre law (min_speed > 0) may also carry a limit on
# the vehicle's acceleration, sqrt(ax_m^2 + ay_m^2) <= max_accel (the tyres' use of the road's friction; beyond it the
# road's friction, which no test knows, decides the forces).
ACCEL_SIGNALS = ("ax_m", "ay_m")
# Observer error pole: OBSERVER_POLE_FACTOR x the derivative filters' bandwidth 2 pi f_c (f_c = 1 Hz of the
# table design: lambda = 12.6 1/s, the estimate settles to 5 % in 3/lambda = 0.24 s, inside the 300 ms
# detection goal and faster than the filtered signals it reads).
OBSERVER_POLE_FACTOR = 2.0
# Regularisation of the run-time output injection L = -(lambda + a) c / (c^2 + eps): eps = (OBSERVER_EPS x
# the output sensitivity |c| at the reference point)^2, so the pole is placed wherever the residual
# equation sees the state at least a tenth as well as at the reference point, and the gain fades out (no
# division by zero) where it does not.
OBSERVER_EPS = 0.1


LOOP_JOIN = "+"  # Step.equation of an algebraic loop: its equations joined


@dataclass(frozen=True)
class Step:
    var: str
    equation: str  # the equation used; for a loop its equations joined by LOOP_JOIN
    kind: str  # "measured", "algebraic", "loop" (an algebraic loop solved jointly), "derivative" or "observer"
    level: int  # filter level of the computed value
    division: bool = False  # the solution divides by a signal

    @property
    def equations(self) -> tuple[str, ...]:
        return tuple(self.equation.split(LOOP_JOIN))

    def text(self) -> str:
        how = {"measured": "from the measurement", "algebraic": "solved from", "loop": "solved jointly from",
               "derivative": "filtered derivative by", "observer": "estimated by an observer integrating"}[self.kind]
        return f"{self.var} {how} {self.equation}" + (" (divides by a signal)" if self.division else "")


@dataclass(frozen=True)
class Observer:
    """Integral causality for one state x (estimate xh, symbol XHAT): the differential constraint gives the
    update xh' = update + gain * r, with r = the generator's residual expr (a function of xh and nodes);
    a = d(update)/dxh and c = d(expr)/dxh are the linearisation the gain and the discretisation use."""

    state: str
    equation: str  # the differential constraint dx = d/dt x integrated by the observer
    update: sympy.Expr  # dx over XHAT and Node symbols (at the generator's level)
    gain: sympy.Expr  # L over XHAT and Node symbols
    a: sympy.Expr
    c: sympy.Expr
    pole: float  # lambda [1/s]: the error pole where the residual sees the state
    eps: float  # regularisation of the gain (0: constant c, no regularisation)
    initial: sympy.Expr  # xh at a reset: the state from its measurement outside the MSO set (raw nodes), else 0

    def text(self) -> str:
        how = "constant gain" if not self.gain.free_symbols else "run-time gain -max(lambda + a, 0) c / (c^2 + eps)"
        return f"observer for {self.state} (integrates {self.equation}, {how}, lambda = {self.pole:.3g} 1/s)"


XHAT = sympy.Symbol("xhat", real=True)  # the observer state in Observer and Generator expressions


@dataclass(frozen=True)
class Generator:
    name: str
    equations: tuple[str, ...]  # the MSO set
    residual_equation: str
    steps: tuple[Step, ...]
    expr: sympy.Expr  # residual over Node symbols, all at `level`
    level: int  # filters each signal passes through
    filters: tuple[Node, ...]  # filter inputs, in evaluation order (fdi_svf instances)
    nodes: tuple[Node, ...]  # filter outputs / raw samples the residual reads
    knowns: tuple[str, ...]  # measured signals read
    faults: tuple[str, ...]  # faults of the equations used (the MSO's fault set)
    scaled_by: str = ""  # denominator cleared from the residual ("" if none)
    min_speed: float = 0.0  # operating domain: evaluable only while |DOMAIN_SIGNAL| >= min_speed (0: always)
    domain_reason: str = ""  # where min_speed comes from in the model
    max_accel: float = 0.0  # operating domain: evaluable only while |(ax_m, ay_m)| <= max_accel (0: no limit)
    observer: Observer | None = None  # integral causality for one state (expr then depends on XHAT)
    note: str = ""  # a causality the synthesis considered and did not take, and why ("" for none)
    # d r / d f_j of each fault of the signature with a nonzero steady-state sensitivity, over the same Node
    # symbols (and XHAT) as `expr`: what the generator also computes on line (`residuals.sensitivity`)
    sensitivities: tuple[tuple[str, sympy.Expr], ...] = ()
    # the faults of the signature that reach the residual only through a derivative (no steady-state sensitivity)
    # with a constant rate gain d r / d (df_j/dt): the steady residual of a drift of rate rho is gain * rho
    # (`residuals.sensitivity.rate_gains`); the diagnoser bounds how far such a fault has moved with it
    rate_gains: tuple[tuple[str, float], ...] = ()
    # d r / d theta of each uncertain quantity of the model the residual depends on (parameters with a range,
    # nuisances not decoupled), over the same symbols as `sensitivities` (`residuals.uncertainty_sensitivity`):
    # what the generated step weighs with the quantities' half-widths into the adaptive threshold's spread
    uncertainty: tuple[tuple[str, sympy.Expr], ...] = ()
    # the residual's derivative-free nonlinear terms, computed from raw samples and filtered as one derived signal
    # (`residuals.whole_terms`); None when it has none
    composite: Composite | None = None

    def domain(self) -> str:
        if self.min_speed <= 0.0 and self.max_accel <= 0.0:
            return "always evaluable"
        parts = [f"|{DOMAIN_SIGNAL}| >= {self.min_speed:g} m/s ({self.domain_reason})"] if self.min_speed > 0.0 else []
        if self.max_accel > 0.0:
            parts.append(f"|({', '.join(ACCEL_SIGNALS)})| <= {self.max_accel:g} m/s^2 (the tyres near their linear "
                         "range)")
        return " and ".join(parts)

    def causality(self) -> str:
        der = [s.var for s in self.steps if s.kind == "derivative"]
        text = f"residual {self.residual_equation}; "
        text += ("derivative causality for " + ", ".join(der)) if der else "algebraic only"
        loops = list(dict.fromkeys(s.equation for s in self.steps if s.kind == "loop"))
        for loop in loops:
            text += (f"; algebraic loop {loop} solved jointly for "
                     + ", ".join(s.var for s in self.steps if s.equation == loop))
        if self.observer is not None:
            text += "; " + self.observer.text()
        if self.composite is not None:
            text += "; its terms without derivatives filtered as one signal"
        text += f"; {len(self.filters)} filters, level {self.level}"
        if self.scaled_by:
            text += f"; multiplied by {self.scaled_by}"
        if self.min_speed > 0.0 or self.max_accel > 0.0:
            text += f"; domain {self.domain()}"
        return text
