"""Closed-loop tuning of any model without a vehicle simulator of its own: drives from the generic simulator
(fdi_host.sim.generic) described by a scenario file (e.g. host_tools/scenarios/three_tank.toml), the observer
generators' reference (c_ref) and the variance calibration of the generated residuals, written to the thresholds
file as `fdi-tune calibrate` does for ROMO (same rule: no raw alarm of the gate or the CUSUM in any fault-free
drive after the warm-up, sigma times the margin; `fdi_host.tuning.calibrate`), and the fault-size sweep: per
(fault, test) the smallest size on the sweep grid (`fdi_host.tuning.sweep.grid`) at which the test raises a raw
alarm within RESPONSE_S of a step fault, stated as the next grid value (as `fdi-tune fault-sizes`), written to the
[per_test.<fault>] tables of the fault-size file (its hand-written [requirement] and [limits] above are kept);
they decide which quiet test may exonerate which fault (fdi_analysis.export.fault_sizes).

    python -m fdi_host.tuning.generic calibrate analysis/models/three_tank.toml \\
        --thresholds analysis/models/three_tank_thresholds.toml --scenario host_tools/scenarios/three_tank.toml
    python -m fdi_host.tuning.generic fault-sizes analysis/models/three_tank.toml \\
        --thresholds analysis/models/three_tank_thresholds.toml --scenario host_tools/scenarios/three_tank.toml \\
        --sizes host_tools/scenarios/three_tank_fault_sizes.toml
    (add --check to exit 1 when the file's generated tables are stale; scripts/generate.sh runs both)
"""

from __future__ import annotations

import argparse
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
from fdi_host.sim.faults import FaultSpec
from fdi_host.sim.generic import FaultRun, GenericPlant, Scenario, drive
from fdi_host.tuning.calibrate import MARGIN, calibrate, first_alarm
from fdi_host.tuning.sweep import grid, next_grid

RESPONSE_S = REACTION_WINDOW_S  # a test reacts to a step fault when it raises a raw alarm within this time
SWEEP_LEAD_S = 12.0  # fault-free seconds of each sweep drive before the step (the warm-up, the filters settle)
SWEEP_DECADES = 2.0  # the sweep starts at the fault's limit / 10^SWEEP_DECADES
SIZES_MARKER = ("# ---- per-test sizes: written by `python -m fdi_host.tuning.generic fault-sizes`, "
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


def calibration(model: Model, th: Thresholds, sc: Scenario, model_path: Path, workers: int = 2,
                log: Callable[[str], None] = lambda s: None) -> Calibrated:
    plant = GenericPlant(model)
    ref = reference(plant, sc)
    gens = generators(model, th, ref, workers)
    design = FilterDesign(th.design[0], th.design[1], th.design[2])
    drives = [drive(plant, sc, s) for s in sc.seeds]
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
    provenance = (f"python -m fdi_host.tuning.generic calibrate {model_path.as_posix()} --scenario {sc.source}: "
                  f"fault-free drives of the generic simulator (seeds {' '.join(map(str, sc.seeds))}, "
                  f"{sc.duration:g} s, warm-up {sc.warmup:g} s); no raw alarm (|r| > gate sigma or CUSUM k = 1.5, "
                  f"h = 150) in any of them, sigma times {MARGIN}; observer reference: seed {sc.reference_seed}")
    return Calibrated(rows, observer_rows, provenance)


def sweep(model: Model, th: Thresholds, sc: Scenario, limits: Mapping[str, float], seed: int, workers: int = 2,
          log: Callable[[str], None] = lambda s: None) -> dict[str, dict[str, float | str]]:
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
            raise ValueError(f"{sc.source}: no [limits] value for fault {f}")
        found: dict[str, float] = {}
        for size in grid(limits[f] / 10.0**SWEEP_DECADES, limits[f]):
            todo = [(g, s) for g, s in tests if g.name not in found]
            if not todo:
                break
            sig = drive(plant, short, seed, [FaultSpec(f, SWEEP_LEAD_S, size)])
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
    head = text.split(SIZES_MARKER)[0].rstrip("\n") + "\n\n"
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
            print(f"{path} is stale: run scripts/generate.sh", file=sys.stderr)
            return 1
        print(f"{path} is up to date")
        return 0
    path.write_text(new, encoding="utf-8")
    print(f"wrote {path}")
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m fdi_host.tuning.generic", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("calibrate", help="write the [generated] and [observer] tables of the thresholds file",
                       description="Calibrate the variances of the generated residuals of MODEL on the fault-free "
                       "drives of the scenario file, and the observers' reference, into the thresholds file.")
    c.add_argument("model", type=Path)
    c.add_argument("--thresholds", type=Path, required=True)
    c.add_argument("--scenario", type=Path, required=True)
    c.add_argument("--workers", type=int, default=2)
    c.add_argument("--check", action="store_true", help="do not write: exit 1 when the file is stale")
    z = sub.add_parser("fault-sizes", help="write the [per_test.<fault>] tables of the fault-size file",
                       description="Sweep step faults in short drives of the scenario (one seed): per fault and test "
                       "of its signature the stated reaction size (see the module doc).")
    z.add_argument("model", type=Path)
    z.add_argument("--thresholds", type=Path, required=True)
    z.add_argument("--scenario", type=Path, required=True)
    z.add_argument("--sizes", type=Path, required=True, help="fault-size file with [requirement] and [limits]")
    z.add_argument("--workers", type=int, default=2)
    z.add_argument("--check", action="store_true", help="do not write: exit 1 when the file is stale")
    args = ap.parse_args(argv)
    model = load_model(args.model)
    th = Thresholds.load(args.thresholds)
    sc = Scenario.load(args.scenario)
    log = lambda s: print(s, file=sys.stderr)  # noqa: E731
    if args.cmd == "calibrate":
        cal = calibration(model, th, sc, args.model, args.workers, log=log)
        new = with_generated(args.thresholds.read_text(encoding="utf-8"), cal.rows, cal.provenance, cal.observer_rows)
        return _write_or_check(args.thresholds, new, args.check)
    limits = FaultSizes.load(args.sizes).limits
    per_test = sweep(model, th, sc, limits, sc.sweep_seed, args.workers, log=log)
    provenance = (f"python -m fdi_host.tuning.generic fault-sizes {args.model.as_posix()} --scenario {sc.source}: "
                  f"a step fault after {SWEEP_LEAD_S:g} s fault-free (seed {sc.sweep_seed}), sizes on the grid from "
                  f"the limit / {10**SWEEP_DECADES:g} up to it; the size at which the test raises a raw alarm "
                  f"within {RESPONSE_S:g} s of the step, stated as the next grid value")
    return _write_or_check(args.sizes, with_sizes(args.sizes.read_text(encoding="utf-8"), per_test, provenance),
                           args.check)


if __name__ == "__main__":
    raise SystemExit(main())
