"""A simulator for any model file without algebraic loops: the second model's drives (e.g. the three-tank
system), with the model's own equations and nothing else.

States are the integrated variables of the differential constraints, inputs the knowns declared `input = true`,
the other knowns are measurements. The normal equations (those without a measured known) are solved one at a
time for the one unknown each still lacks (a causal ordering from the states and inputs; an equation is
solved only for an unknown it is linear in, with the faults kept as symbols), which yields every derivative;
each measurement equation is then solved for its measured known. The whole sequence becomes one function
(`sympy.lambdify`, common subexpressions shared), integrated with the classical Runge-Kutta method at the
sample time with the inputs and faults held over each step; measurement noise is white and Gaussian.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import sympy
from numpy.typing import NDArray

from fdi_analysis.model import Model
from fdi_analysis.residuals.solvability import Solution, Solver
from fdi_host.errors import FdiHostError

FloatArray = NDArray[np.float64]


class GenericPlantError(FdiHostError, ValueError):
    """A model the generic simulator cannot order causally (an algebraic loop, a state without a derivative)."""


@dataclass(frozen=True)
class StepFault:
    fault: str
    onset: float  # s
    size: float  # in the fault's unit
    end: float = float("inf")


@dataclass(frozen=True)
class Run:
    t: FloatArray
    states: dict[str, FloatArray]
    measured: dict[str, FloatArray]  # with noise
    inputs: dict[str, FloatArray]


class GenericPlant:
    def __init__(self, model: Model) -> None:
        self.model = model
        solver = Solver(model, keep_faults=True)
        diffs = [e.differential for e in model.equations if e.differential is not None]
        self.states = tuple(x for _, x in diffs)
        self.inputs = tuple(k.name for k in model.knowns if k.input)
        self.measured = tuple(k.name for k in model.knowns if not k.input)
        self.faults = tuple(f.name for f in model.faults)
        known = set(self.states) | set(self.inputs)
        values: dict[sympy.Symbol, sympy.Expr] = {}
        normal = [e for e in model.equations
                  if e.differential is None and not set(e.knowns) & set(self.measured)]
        todo = list(normal)
        progress = True
        while todo and progress:
            progress = False
            for e in list(todo):
                missing = [u for u in e.unknowns if u not in known]
                if len(missing) > 1:
                    continue
                todo.remove(e)
                progress = True
                if not missing:
                    raise GenericPlantError(f"{model.name}: equation {e.id} has no unknown left to compute (the "
                                            "model is not a causal simulation model)")
                sol = solver.solve(e, missing[0])
                if not isinstance(sol, Solution) or sol.coefficient.free_symbols:
                    raise GenericPlantError(f"{model.name}: equation {e.id} cannot be solved for {missing[0]} "
                                            "(not linear in it, or divides by a signal)")
                values[sympy.Symbol(missing[0])] = sol.expr.xreplace(values)
                known.add(missing[0])
        if todo:
            raise GenericPlantError(f"{model.name}: an algebraic loop in {', '.join(e.id for e in todo)}")
        derivs = []
        for dx, x in diffs:
            if sympy.Symbol(dx) not in values:
                raise GenericPlantError(f"{model.name}: no equation computes {dx}, the derivative of {x}")
            derivs.append(values[sympy.Symbol(dx)])
        meas = []
        for name in self.measured:
            e = next(eq for eq in model.equations if name in eq.knowns)
            expr = solver.residual(e)
            target = sympy.Symbol(name)
            coef = sympy.diff(expr, target)
            if coef.free_symbols or coef == 0:
                raise GenericPlantError(f"{model.name}: measurement equation {e.id} is not linear in {name}")
            meas.append((-(expr.xreplace({target: 0})) / coef).xreplace(values))
        args = [sympy.Symbol(s) for s in (*self.states, *self.inputs)] + [sympy.Symbol(f, real=True)
                                                                          for f in self.faults]
        self._f = sympy.lambdify(args, derivs, modules="numpy", cse=True)
        self._y = sympy.lambdify(args, meas, modules="numpy", cse=True)

    def derivatives(self, x: FloatArray, u: Sequence[float], f: Sequence[float]) -> FloatArray:
        return np.asarray(self._f(*x, *u, *f), dtype=np.float64)

    def measurements(self, x: FloatArray, u: Sequence[float], f: Sequence[float]) -> FloatArray:
        return np.asarray(self._y(*x, *u, *f), dtype=np.float64)

    def simulate(self, x0: Mapping[str, float], inputs: Mapping[str, Callable[[float], float]], duration: float,
                 dt: float = 0.01, faults: Sequence[StepFault] = (), noise: Mapping[str, float] | None = None,
                 seed: int = 0) -> Run:
        """A run from the state `x0` with `inputs` (functions of time) and step `faults`; `noise` is the
        standard deviation per measured known (0 where not given)."""
        unknown = [f.fault for f in faults if f.fault not in self.faults]
        if unknown:
            raise GenericPlantError(f"{self.model.name}: unknown fault(s) {unknown}")
        n = round(duration / dt) + 1
        t = np.arange(n, dtype=np.float64) * dt
        xs = np.zeros((n, len(self.states)))
        ys = np.zeros((n, len(self.measured)))
        us = np.zeros((n, len(self.inputs)))
        x = np.array([float(x0[s]) for s in self.states], dtype=np.float64)

        def fault_values(tk: float) -> list[float]:
            out = [0.0] * len(self.faults)
            for fs in faults:
                if fs.onset <= tk < fs.end:
                    out[self.faults.index(fs.fault)] += fs.size
            return out

        for k in range(n):
            tk = float(t[k])
            u = [float(inputs[name](tk)) for name in self.inputs]
            fv = fault_values(tk)
            xs[k], us[k] = x, u
            ys[k] = self.measurements(x, u, fv)
            k1 = self.derivatives(x, u, fv)
            k2 = self.derivatives(x + 0.5 * dt * k1, u, fv)
            k3 = self.derivatives(x + 0.5 * dt * k2, u, fv)
            k4 = self.derivatives(x + dt * k3, u, fv)
            x = x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        rng = np.random.default_rng(seed)
        sd = noise or {}
        measured = {name: ys[:, i] + rng.normal(0.0, float(sd.get(name, 0.0)), n)
                    for i, name in enumerate(self.measured)}
        return Run(t, {s: xs[:, i] for i, s in enumerate(self.states)}, measured,
                   {name: us[:, i] for i, name in enumerate(self.inputs)})
