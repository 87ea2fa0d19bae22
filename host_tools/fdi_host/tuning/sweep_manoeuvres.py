"""Stated sizes in other manoeuvres for the (fault, test) pairs the primary sweep (steady cornering) leaves
without one.

Some pairs of the structural signatures are nearly silent in steady cornering for physical reasons, not for
noise: a torque fault of wheel 2 enters a body-balance test through the moment about wheel 4, where
the longitudinal force of wheel 2 has no lever arm; an accelerometer offset moves the computed tyre load, which
changes a tyre force in proportion to the force itself, small at constant speed. Accelerating, braking and
transient steering excite them. For such a pair each other scenario is driven whole with the fault as a step
from ONSET to the end (one drive per size and noise seed, as the ECU sees it), and the test counts as
alarming when it raises a raw alarm after the onset (inside its operating domain, CUSUM from the onset) in
the faulty drive of every seed while the fault-free drive of that seed has none.

Sizes: the grid of `sweep` from `lo` up to the fault's limit, the limit itself its last value (`capped_grid`).
Every scenario is first swept on the decades (1 x 10^k and the limit), then on the grid between the last quiet
decade and the first alarming one (sizes in increasing order: detection is taken to grow with the size, as
in the primary sweep). In the scenario with the smallest first alarm the stated size is the next grid value
above it, confirmed like the primary sweep's (every seed and seed + CONFIRM_SEED_OFFSETS, raised along the grid
up to the limit); when it cannot be confirmed the next scenario is tried. Ties: the order of `scenarios`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from fdi_analysis.residuals.generator import Generator
from fdi_host.tuning.seeds import CONFIRM_SEED_OFFSETS
from fdi_host.tuning.sweep import ScenarioLimit, alarms_in_windows, grid

FloatArray = NDArray[np.float64]

ONSET = 4.0  # s: the fault step (the diagnoser's warm-up is 3 s)

# (scenario, fault, size, seed) -> measured signals as the ECU sees them; size 0: the fault-free drive
ScenarioDrive = Callable[[str, str, float, int], dict[str, FloatArray]]


def capped_grid(lo: float, limit: float) -> list[float]:
    """The sweep grid from lo up to the limit, with the limit as its last value."""
    out = grid(lo, limit)
    if not out or out[-1] < limit * (1 - 1e-9):
        out.append(float(limit))
    return out


def scenario_drive(dt: float = 0.01) -> ScenarioDrive:
    """Whole scenario drives with the fault stepped in at ONSET (size 0: fault-free), as the ECU sees them."""
    from fdi_host.tuning.drives import drive

    def run(scenario: str, fault: str, size: float, seed: int) -> dict[str, FloatArray]:
        faults = [(fault, ONSET, size)] if size > 0.0 else []
        return drive(scenario, faults=faults, dt=dt, seed=seed, as_ecu_sees=True)[1]

    return run


def _signal_seconds(signals: dict[str, FloatArray], dt: float) -> float:
    return len(next(iter(signals.values()))) * dt


class _Alarms:
    """Alarm after ONSET per (test, scenario, size, seed), each drive simulated once."""

    def __init__(self, tests: Sequence[tuple[Generator, float]], gate: float, fault: str, drive: ScenarioDrive,
                 dt: float, warmup: int) -> None:
        self.tests = {g.name: (g, s) for g, s in tests}
        self.gate, self.fault, self.drive, self.dt, self.warmup = gate, fault, drive, dt, warmup
        self.signals: dict[tuple[str, float, int], dict[str, FloatArray]] = {}
        self.alarm: dict[tuple[str, str, float, int], bool] = {}

    def _one(self, test: str, scenario: str, size: float, seed: int) -> bool:
        key = (test, scenario, size, seed)
        if key not in self.alarm:
            if (scenario, size, seed) not in self.signals:
                self.signals[(scenario, size, seed)] = self.drive(scenario, self.fault, size, seed)
            sig = self.signals[(scenario, size, seed)]
            g, s = self.tests[test]
            on = _signal_seconds(sig, self.dt) - ONSET
            self.alarm[key] = alarms_in_windows(g, s, self.gate, sig, [ONSET], self.dt, self.warmup, on=on)[0]
        return self.alarm[key]

    def hit(self, test: str, scenario: str, size: float, seeds: Sequence[int]) -> bool:
        """An alarm in the faulty drive of every seed and none in that seed's fault-free drive."""
        return all(self._one(test, scenario, size, seed) and not self._one(test, scenario, 0.0, seed)
                   for seed in seeds)

    def first_hit(self, test: str, scenario: str, sizes: Sequence[float], seeds: Sequence[int]) -> float | None:
        """The first of the increasing `sizes` that alarms with every seed (None: none)."""
        return next((v for v in sizes if self.hit(test, scenario, v, seeds)), None)


def sweep_scenarios(tests: Sequence[tuple[Generator, float]], gate: float, fault: str, lo: float, limit: float,
                    drive: ScenarioDrive, seeds: Sequence[int], scenarios: Sequence[str],
                    dt: float = 0.01, warmup: int = 300,
                    log: Callable[[str], None] | None = None) -> dict[str, ScenarioLimit]:
    """Per test of `tests` (pairs of `fault` without a stated size in the primary sweep): its stated size in
    the scenario that detects it first (module docstring); tests detected in no scenario are left out."""
    say = log or (lambda _s: None)
    levels = capped_grid(lo, limit)
    decades = sorted({*(v for v in levels if abs(math.log10(v) - round(math.log10(v))) < 1e-9), levels[-1]})
    alarms = _Alarms(tests, gate, fault, drive, dt, warmup)
    more = [*seeds, *(seed + k for k in CONFIRM_SEED_OFFSETS for seed in seeds)]
    out: dict[str, ScenarioLimit] = {}
    for g, _ in tests:
        coarse = {sc: alarms.first_hit(g.name, sc, decades, seeds) for sc in scenarios}
        first: dict[str, float] = {}
        for sc, top in coarse.items():
            if top is not None:
                below = [v for v in decades if v < top]
                finer = [v for v in levels if (not below or v > below[-1]) and v < top]
                first[sc] = alarms.first_hit(g.name, sc, finer, seeds) or top
        say(f"{fault} {g.name}: first alarm " +
            ", ".join(f"in {sc} at {first[sc]:g}" if sc in first else f"none in {sc}" for sc in scenarios))
        for sc in sorted(first, key=lambda sc: (first[sc], scenarios.index(sc))):
            size = levels[min(levels.index(first[sc]) + 1, len(levels) - 1)]
            while not alarms.hit(g.name, sc, size, more) and size < levels[-1]:
                say(f"{fault} {g.name} in {sc}: {size:g} not confirmed with every seed, raised")
                size = levels[levels.index(size) + 1]
            if alarms.hit(g.name, sc, size, more):
                out[g.name] = ScenarioLimit(fault, g.name, sc, first[sc], size)
                say(f"{fault} {g.name}: stated {size:g} in {sc} (first alarm at {first[sc]:g})")
                break
            say(f"{fault} {g.name} in {sc}: no size up to the limit {limit:g} confirmed with every seed")
    return out
