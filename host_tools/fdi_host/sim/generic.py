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

import math
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import sympy
from numpy.typing import NDArray

from fdi_analysis.model import Model
from fdi_analysis.residuals.solvability import Solution, Solver
from fdi_host.errors import FdiHostError
from fdi_host.sim.faults import FaultSpec, fault_matrix, ground_truth

FloatArray = NDArray[np.float64]


class GenericPlantError(FdiHostError, ValueError):
    """A model the generic simulator cannot order causally (an algebraic loop, a state without a derivative)."""


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
                 dt: float = 0.01, faults: Sequence[FaultSpec] = (), noise: Mapping[str, float] | None = None,
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
        F = fault_matrix(faults, t, self.faults)  # held over each step

        for k in range(n):
            tk = float(t[k])
            u = [float(inputs[name](tk)) for name in self.inputs]
            fv = F[k].tolist()
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


@dataclass(frozen=True)
class FaultRun:
    fault: str
    size: float
    onset: float
    seed: int
    candidates: tuple[str, ...] = ()  # the candidate faults the diagnoser must end with


@dataclass(frozen=True)
class Scenario:
    """A scenario file: one drive (initial state, inputs as offset plus sines, sensor noise) and its seeds."""

    source: str
    dt: float
    duration: float
    initial: dict[str, float]
    inputs: dict[str, tuple[float, tuple[tuple[float, float], ...]]]  # input -> (offset, ((amplitude, period)))
    noise: dict[str, float]
    reference_seed: int
    seeds: tuple[int, ...]
    warmup: float
    fault_runs: tuple[FaultRun, ...]
    sweep_seed: int = 0

    @staticmethod
    def load(path: Path) -> Scenario:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
        d = doc["drive"]
        inputs = {name: (float(v.get("offset", 0.0)), tuple((float(a), float(p)) for a, p in v.get("sines", [])))
                  for name, v in d.get("inputs", {}).items()}
        runs = tuple(FaultRun(str(r["fault"]), float(r["size"]), float(r["onset"]), int(r["seed"]),
                              tuple(str(c) for c in r.get("candidates", [])))
                     for r in doc.get("fault_run", []))
        return Scenario(path.as_posix(), float(d["dt"]), float(d["duration"]),
                        {k: float(v) for k, v in d["initial"].items()}, inputs,
                        {k: float(v) for k, v in d.get("noise", {}).items()}, int(doc["reference"]["seed"]),
                        tuple(int(s) for s in doc["calibration"]["seeds"]), float(doc["calibration"]["warmup"]), runs,
                        int(doc.get("sweep", {}).get("seed", 0)))

    def input_functions(self) -> dict[str, Callable[[float], float]]:
        def make(offset: float, sines: tuple[tuple[float, float], ...]) -> Callable[[float], float]:
            return lambda t: offset + sum(a * math.sin(2.0 * math.pi * t / p) for a, p in sines)

        return {name: make(o, s) for name, (o, s) in self.inputs.items()}


def drive(plant: GenericPlant, sc: Scenario, seed: int, faults: Sequence[FaultSpec] = ()) -> dict[str, FloatArray]:
    """The knowns (measured with noise, and the inputs) of one drive of the scenario."""
    run = plant.simulate(sc.initial, sc.input_functions(), sc.duration, sc.dt, faults, sc.noise, seed)
    return {**run.measured, **run.inputs}


@dataclass(frozen=True)
class VehicleDrive:
    """One drive of a vehicle's model plant: the signals its bus carries (measured with noise, and the inputs),
    sampled every `dt`, and the ground truth in the form ``fdi-sim`` writes for ROMO (``<log>.truth.json``)."""

    t: FloatArray
    dt: float
    signals: dict[str, FloatArray]
    truth: dict[str, Any]


def vehicle_drive(model: Model, sc: Scenario, faults: Sequence[FaultSpec] = (), seed: int | None = None,
                  duration: float | None = None, noise: bool = True, label: str = "") -> VehicleDrive:
    """A drive of the scenario on the model plant of `model` with `faults` (any shape of `FaultSpec`)."""
    plant = GenericPlant(model)
    seed = sc.seeds[0] if seed is None else seed
    length = sc.duration if duration is None else duration
    run = plant.simulate(sc.initial, sc.input_functions(), length, sc.dt, faults, sc.noise if noise else {}, seed)
    info = {f.name: {"unit": f.unit, "desc": f.desc, "equations": [e.id for e in model.equations if f.name in e.faults]}
            for f in model.faults}
    truth = ground_truth(faults, run.t, info, plant.faults) | {
        "scenario": sc.source, "seed": seed, "duration": length, "start_time": 0.0, "noise": noise,
        "plant": label or f"model plant of {model.name}"}
    return VehicleDrive(run.t, sc.dt, {**run.measured, **run.inputs}, truth)
