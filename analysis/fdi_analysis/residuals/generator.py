"""A synthesised residual generator: the computation sequence and its residual over filtered signals."""

from __future__ import annotations

from dataclasses import dataclass

import sympy

from fdi_analysis.residuals.signals import Node

DOMAIN_SIGNAL = "vx_m"  # measured signal of the operating-domain condition (longitudinal speed)
# The domain of a residual with a regularised slip (Max(..., v_eps) in an equation it uses) starts at
# DOMAIN_FACTOR * v_eps: there the normaliser is the wheel's own speed with margin, and the relative error of
# the filtered speeds (all delayed alike, but differentiated and divided) is small.
DOMAIN_FACTOR = 4.0


@dataclass(frozen=True)
class Step:
    var: str
    equation: str
    kind: str  # "measured", "algebraic" or "derivative"
    level: int  # filter level of the computed value
    division: bool = False  # the solution divides by a signal

    def text(self) -> str:
        how = {"measured": "from the measurement", "algebraic": "solved from",
               "derivative": "filtered derivative by"}[self.kind]
        return f"{self.var} {how} {self.equation}" + (" (divides by a signal)" if self.division else "")


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

    def domain(self) -> str:
        if self.min_speed <= 0.0:
            return "always evaluable"
        return f"|{DOMAIN_SIGNAL}| >= {self.min_speed:g} m/s ({self.domain_reason})"

    def causality(self) -> str:
        der = [s.var for s in self.steps if s.kind == "derivative"]
        text = f"residual {self.residual_equation}; "
        text += ("derivative causality for " + ", ".join(der)) if der else "algebraic only"
        text += f"; {len(self.filters)} filters, level {self.level}"
        if self.scaled_by:
            text += f"; multiplied by {self.scaled_by}"
        if self.min_speed > 0.0:
            text += f"; domain {self.domain()}"
        return text
