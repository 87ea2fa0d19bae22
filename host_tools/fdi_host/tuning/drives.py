"""Simulated measured signals for the generators: the simulator's samples at the design dt, or (as_ecu_sees)
the signals the ECU's steps see on the drive's CAN frames (fdi_host.can.ecu_view: message cycle times and
offsets, sample-and-hold, DBC quantisation), which is what thresholds and fault sizes are calibrated on."""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from fdi_analysis.export.thresholds import Thresholds
from fdi_analysis.residuals.evaluate import FilterDesign, evaluable_segments
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.observer import ObserverReference

FloatArray = NDArray[np.float64]
# The observer generators' reference drive (their gain's regularisation, `ObserverReference`): steady
# cornering, where the residual equations see the estimated wheel speeds (a straight drive would leave d r /
# d x = 0 for some of them).
REFERENCE_SCENARIO = "cornering"
REFERENCE_DURATION = 12.0


def drive(scenario: str, faults: Sequence[tuple[str, float, float] | tuple[str, float, float, float]] = (),
          duration: float | None = None, dt: float = 0.01, seed: int | None = None,
          as_ecu_sees: bool = False) -> tuple[FloatArray, dict[str, FloatArray]]:
    """(t, measured signals at dt) of a scenario with step faults (fault, onset s, size[, end s]); no faults
    given means fault-free (the scenario's own faults are not used)."""
    from fdi_host.sim.faults import FaultSpec
    from fdi_host.sim.scenario import load_scenario
    from fdi_host.sim.vehicle_sim import simulate

    specs = [FaultSpec(f[0], f[1], f[2], end=f[3] if len(f) > 3 else None) for f in faults]
    res = simulate(load_scenario(scenario), specs, duration=duration, seed=seed)
    if as_ecu_sees:
        from fdi_host.can.ecu_view import ecu_view
        from fdi_host.can.traffic import build_frames

        t, view = ecu_view(build_frames(res), dt)
        return t, {k: view[k] for k in res.measured}
    step = max(1, round(dt / res.config.dt))
    return res.t[::step].copy(), {k: np.asarray(v[::step], dtype=float) for k, v in res.measured.items()}


def fault_free_drives(scenarios: Sequence[str], seeds: Sequence[int | None], duration: float | None, dt: float,
                      log: Callable[[str], None] | None = None) -> list[dict[str, FloatArray]]:
    """The measured signals, as the ECU sees them, of fault-free drives: every scenario with every seed (None:
    the scenario's own), `duration` seconds each (None: the scenario's own duration)."""
    runs = [(sc, seed) for sc in scenarios for seed in seeds]
    out = []
    for i, (sc, seed) in enumerate(runs):
        if log is not None:
            length = "its own duration" if duration is None else f"{duration:g} s"
            log(f"[{i + 1}/{len(runs)}] fault-free drive {sc} seed {seed or 'of the scenario'} ({length}) ...")
        out.append(drive(sc, duration=duration, dt=dt, seed=seed, as_ecu_sees=True)[1])
    return out


def residual_segments(g: Generator, drives: Sequence[dict[str, FloatArray]], warmup: int,
                      design: FilterDesign) -> list[FloatArray]:
    """The residual of `g` on every drive, in its operating domain after the warm-up (evaluable segments)."""
    return [r for sig in drives for _, r in evaluable_segments(g, sig, warmup, design)]


@functools.cache
def reference_signals(dt: float = 0.01) -> dict[str, FloatArray]:
    """The measured signals of the fault-free reference drive (the scenario's own seed), at dt."""
    return drive(REFERENCE_SCENARIO, duration=REFERENCE_DURATION, dt=dt)[1]


def observer_reference(thresholds: Thresholds | None = None) -> ObserverReference:
    """The observer generators' reference: the c_ref values of the thresholds file's [observer] table (what
    export-c compiles in) where it has them, else computed on the reference drive."""
    return ObserverReference(signals=reference_signals(), c_ref=dict(thresholds.observer) if thresholds else {})
