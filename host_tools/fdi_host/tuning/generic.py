"""Closed-loop tuning of any model without a vehicle simulator of its own: drives from the generic simulator
(fdi_host.sim.generic) described by a scenario file (e.g. host_tools/scenarios/three_tank.toml), the observer
generators' reference (c_ref) and the variance calibration of the generated residuals, written to the thresholds
file as `fdi-tune calibrate` does for ROMO (same rule: no raw alarm of the gate or the CUSUM in any fault-free
drive after the warm-up, sigma times the margin; `fdi_host.tuning.calibrate`), and the fault-size sweep: per
(fault, test) the smallest size on the sweep grid (`fdi_host.tuning.sweep.grid`) at which the test raises a raw
alarm within RESPONSE_S of a step fault, stated as the next grid value (as `fdi-tune fault-sizes`), written to the
[per_test.<fault>] tables of the fault-size file (its hand-written [requirement] and [limits] above are kept);
they decide which quiet test may exonerate which fault (fdi_analysis.export.fault_sizes).

    fdi-tune calibrate --vehicle three_tank      (a vehicle's model, thresholds file and scenario: fdi_host.vehicle)
    fdi-tune fault-sizes --vehicle three_tank    (and its fault-size file)
    (add --check to exit 1 when the file's generated tables are stale; scripts/generate.sh runs both)
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from fdi_analysis.export.fault_sizes import REACTION_WINDOW_S, FaultSizes
from fdi_analysis.export.thresholds import Thresholds, with_generated
from fdi_analysis.model import Model
from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.evaluate import FilterDesign, evaluable_segments
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.observer import ObserverReference
from fdi_analysis.residuals.selected import selected_generators
from fdi_host.can.dbc import CanDatabase
from fdi_host.can.ecu_view import ecu_view
from fdi_host.can.traffic import frames_from_columns
from fdi_host.errors import FdiHostError
from fdi_host.sim.faults import FaultSpec
from fdi_host.sim.generic import FaultRun, GenericPlant, Scenario, drive
from fdi_host.tuning.calibrate import MARGIN, calibrate, first_alarm
from fdi_host.tuning.sweep import grid, next_grid
from fdi_host.vehicle import Vehicle


class GenericTuningError(FdiHostError, ValueError):
    """A vehicle or a fault-size file the generic tuning cannot work with."""


RESPONSE_S = REACTION_WINDOW_S  # a test reacts to a step fault when it raises a raw alarm within this time
SWEEP_LEAD_S = 12.0  # fault-free seconds of each sweep drive before the step (the warm-up, the filters settle)
SWEEP_DECADES = 2.0  # the sweep starts at the fault's limit / 10^SWEEP_DECADES
SIZES_MARKER = ("# ---- per-test sizes: written by `fdi-tune fault-sizes --vehicle`, "
                "do not edit below ----")
NOT_DETECTED = "not detectable by this test up to the limit"

FloatArray = NDArray[np.float64]


def fault_run_signals(plant: GenericPlant, sc: Scenario, run: FaultRun) -> dict[str, FloatArray]:
    return drive(plant, sc, run.seed, [FaultSpec(run.fault, run.onset, run.size)])


def reference(plant: GenericPlant, sc: Scenario) -> ObserverReference:
    """The observer generators' reference: the fault-free drive of the reference seed."""
    return ObserverReference(signals=drive(plant, sc, sc.reference_seed))


def generators(model: Model, th: Thresholds, ref: ObserverReference, workers: int = 2) -> list[Generator]:
    """The generators of the selection (the thresholds file's [selection], else the optimal structural one)."""
    return selected_generators(model, ref, workers=workers, selection=th.selection, max_tyre_accel=th.max_tyre_accel)[1]


@dataclass(frozen=True)
class Calibrated:
    rows: list[tuple[str, float, str]]  # [generated]: equation set, variance, comment
    observer_rows: list[tuple[str, float, str]]  # [observer]: equation set, c_ref, comment
    provenance: str


def seen_by_ecu(signals: dict[str, FloatArray], dt: float, db: CanDatabase | None) -> dict[str, FloatArray]:
    """A drive's signals as the ECU's steps see them on the vehicle's bus (its DBC: frames at their cycle times,
    quantised, held at the steps; fdi_host.can.ecu_view), or as they are for a vehicle without a bus."""
    if db is None:
        return signals
    n = len(next(iter(signals.values())))
    _, view = ecu_view(frames_from_columns(signals, dt, (n - 1) * dt, db), dt, db)
    return view


def calibration(model: Model, th: Thresholds, sc: Scenario, vehicle: str, workers: int = 2,
                log: Callable[[str], None] = lambda s: None, db: CanDatabase | None = None) -> Calibrated:
    plant = GenericPlant(model)
    ref = reference(plant, sc)
    gens = generators(model, th, ref, workers)
    design = FilterDesign(th.design[0], th.design[1], th.design[2])
    drives = [seen_by_ecu(drive(plant, sc, s), sc.dt, db) for s in sc.seeds]
    skip = round(sc.warmup / design.dt)
    rows = []
    for g in gens:
        segments = [r for sig in drives for _, r in evaluable_segments(g, sig, skip, design)]
        c = calibrate(segments, th.gate)
        rows.append((" ".join(g.equations), c.variance,
                     f"{g.name}: sigma {c.sigma:.3g} (fault-free RMS {c.rms:.3g}, peak {c.peak:.3g})"))
        log(f"{g.name}: sigma {c.sigma:.3g}  fault-free RMS {c.rms:.3g}  peak {c.peak:.3g}")
    observer_rows = []
    for g in gens:
        if g.observer is not None and g.observer.c.free_symbols:
            c_ref = ref.sensitivity(g)
            assert c_ref is not None
            observer_rows.append((" ".join(g.equations), c_ref,
                                  f"{g.name}: observer for {g.observer.state}, residual {g.residual_equation}"))
    provenance = (f"fdi-tune calibrate --vehicle {vehicle}: "
                  f"fault-free drives of the generic simulator{' as its ECU sees them on its bus' if db else ''} "
                  f"(seeds {' '.join(map(str, sc.seeds))}, "
                  f"{sc.duration:g} s, warm-up {sc.warmup:g} s); no raw alarm (|r| > gate sigma or CUSUM k = 1.5, "
                  f"h = 150) in any of them, sigma times {MARGIN}; observer reference: seed {sc.reference_seed}")
    return Calibrated(rows, observer_rows, provenance)


def sweep(model: Model, th: Thresholds, sc: Scenario, limits: Mapping[str, float], seed: int, workers: int = 2,
          log: Callable[[str], None] = lambda s: None, db: CanDatabase | None = None
          ) -> dict[str, dict[str, float | str]]:
    """Per fault of the selection and test of its signature: the stated size (next grid value above the first
    alarming one) or why there is none (see the module doc)."""
    plant = GenericPlant(model)
    gens = generators(model, th, reference(plant, sc), workers)
    design = FilterDesign(th.design[0], th.design[1], th.design[2])
    sigmas = th.sigmas(gens)
    short = replace(sc, duration=SWEEP_LEAD_S + RESPONSE_S)
    skip = round(sc.warmup / design.dt)
    onset = round(SWEEP_LEAD_S / design.dt)
    out: dict[str, dict[str, float | str]] = {}
    for f in [f.name for f in model.faults]:
        tests = [(g, s) for g, s in zip(gens, sigmas, strict=True) if f in g.faults]
        if not tests:
            continue
        if f not in limits:
            raise GenericTuningError(f"the fault-size file has no [limits] value for fault {f} (the largest size "
                                     "the sweep goes up to)")
        found: dict[str, float] = {}
        for size in grid(limits[f] / 10.0**SWEEP_DECADES, limits[f]):
            todo = [(g, s) for g, s in tests if g.name not in found]
            if not todo:
                break
            sig = seen_by_ecu(drive(plant, short, seed, [FaultSpec(f, SWEEP_LEAD_S, size)]), sc.dt, db)
            for g, s in todo:
                for start, r in evaluable_segments(g, sig, skip, design):
                    k = first_alarm(r, s, th.gate)
                    if k >= 0 and start + k >= onset:
                        found[g.name] = size
                        break
        out[f] = {g.name: (next_grid(found[g.name]) if g.name in found else NOT_DETECTED) for g, _ in tests}
        log(f"{f}: " + ", ".join(f"{t} {v}" for t, v in out[f].items()))
    return out


def with_sizes(text: str, per_test: Mapping[str, Mapping[str, float | str]], provenance: str) -> str:
    """The fault-size file's text with its [per_test.<fault>] tables replaced (the part above the marker kept)."""
    head = text.split(SIZES_MARKER.split(":")[0])[0].rstrip("\n") + "\n\n"  # the marker's text may have changed
    lines = [SIZES_MARKER, *(f"# {x}" for x in provenance.splitlines())]
    for f, row in per_test.items():
        lines += ["", f"[per_test.{f}]"]
        for test, v in row.items():
            lines.append(f'{test} = "{v}"' if isinstance(v, str) else f"{test} = {v:.6g}")
    return head + "\n".join(lines) + "\n"


def _write_or_check(path: Path, new: str, check: bool) -> int:
    old = path.read_text(encoding="utf-8")
    if check:
        if new != old:
            print(f"{path} is stale: run the command without --check to rewrite it", file=sys.stderr)
            return 1
        print(f"{path} is up to date")
        return 0
    path.write_text(new, encoding="utf-8")
    print(f"wrote {path}")
    return 0


def tune_vehicle(vehicle: Vehicle, command: str, workers: int = 2, check: bool = False) -> int:
    """``fdi-tune calibrate|fault-sizes --vehicle`` of a vehicle on the generic simulator: its thresholds file's
    [generated] and [observer] tables, or its fault-size file's per-test tables, from drives of its scenario."""
    if vehicle.thresholds is None or vehicle.scenario is None:
        raise GenericTuningError(f"vehicle {vehicle.name}: tuning needs its thresholds and scenario files "
                                 f"(thresholds = ..., scenario = ... in {vehicle.manifest})")
    model = load_model(vehicle.model)
    th = Thresholds.load(vehicle.thresholds)
    sc = Scenario.load(vehicle.scenario)
    log = lambda s: print(s, file=sys.stderr)  # noqa: E731
    db = CanDatabase(vehicle.dbc) if vehicle.dbc is not None else None
    if command == "calibrate":
        cal = calibration(model, th, sc, vehicle.spec, workers, log=log, db=db)
        new = with_generated(vehicle.thresholds.read_text(encoding="utf-8"), cal.rows, cal.provenance,
                             cal.observer_rows)
        return _write_or_check(vehicle.thresholds, new, check)
    if vehicle.fault_sizes is None:
        raise GenericTuningError(f"vehicle {vehicle.name}: no fault-size file (fault_sizes = ... in "
                                 f"{vehicle.manifest})")
    limits = FaultSizes.load(vehicle.fault_sizes).limits
    per_test = sweep(model, th, sc, limits, sc.sweep_seed, workers, log=log, db=db)
    provenance = (f"fdi-tune fault-sizes --vehicle {vehicle.spec}: a step fault after {SWEEP_LEAD_S:g} s "
                  f"fault-free (seed {sc.sweep_seed}), sizes on the grid from the limit / {10**SWEEP_DECADES:g} up "
                  f"to it; the size at which the test raises a raw alarm within {RESPONSE_S:g} s of the step, "
                  "stated as the next grid value")
    text = vehicle.fault_sizes.read_text(encoding="utf-8")
    return _write_or_check(vehicle.fault_sizes, with_sizes(text, per_test, provenance), check)
