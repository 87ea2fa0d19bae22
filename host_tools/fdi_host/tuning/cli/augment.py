"""`fdi-tune augment MODEL`: tests added to the structural selection for practical detectability."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from fdi_host.tuning.cli.calibrate import (
    CALIBRATION_DURATION,
    CALIBRATION_SEEDS,
    CALIBRATION_WARMUP,
    DEFAULT_SCENARIOS,
    SWEEP_SCENARIO,
    SWEEP_SEEDS,
)

EXAMPLE = ("example: fdi-tune augment analysis/models/romo_grouped.toml --thresholds "
           "analysis/models/romo_thresholds.toml --sizes host_tools/scenarios/fault_sizes.toml")


def register(sub: Any) -> None:
    p = sub.add_parser(
        "augment",
        help="add tests to the structural selection for faults no selected test detects in practice",
        description="Read the fault-size file's [per_test] tables (fdi-tune fault-sizes) for the faults that "
        "no test of the optimal structural selection detects within the fault's [limits]; for each, try the "
        "realizable candidate MSO sets holding it in candidate order (fewest unknowns first): synthesise, "
        "calibrate on the fault-free drives of fdi-tune calibrate, sweep the fault as fdi-tune fault-sizes "
        "does, and add the first one with a stated size within the limit. Written as the [augment] table of "
        "the thresholds file (the rest of the file is kept); calibrate, fault-sizes and export-c then use the "
        "selection followed by these tests. Run calibrate and fault-sizes again afterwards (scripts/generate.sh "
        "with FDI_SWEEP_SIZES=1 does).",
        epilog=EXAMPLE,
    )
    p.add_argument("model", type=Path, help="model file (.toml)")
    p.add_argument("--thresholds", type=Path, required=True, help="thresholds file to update ([augment])")
    p.add_argument("--sizes", type=Path, required=True, help="fault-size file with [sizes], [limits], [per_test.*]")
    p.add_argument("--tries", type=int, default=6, help="candidates tried per undetected fault (default 6)")
    p.add_argument("--workers", type=int, default=2, help="worker processes of the MSO search (default 2)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from fdi_analysis.export.thresholds import Thresholds, with_augment
    from fdi_analysis.model_loader import load_model
    from fdi_analysis.residuals.evaluate import FilterDesign
    from fdi_analysis.residuals.generator import Generator
    from fdi_analysis.residuals.selected import generators, realizable, structural_selection
    from fdi_analysis.residuals.solvability import Solver
    from fdi_host.tuning import sweep
    from fdi_host.tuning.augment import augment, undetected_faults
    from fdi_host.tuning.calibrate import calibrate
    from fdi_host.tuning.drives import fault_free_drives, observer_reference, residual_segments

    def say(s: str) -> None:
        print(s, file=sys.stderr, flush=True)

    th = Thresholds.load(args.thresholds)
    design = FilterDesign(th.design[0], th.design[1], th.design[2])
    size_file = sweep.SizeFile.load(args.sizes)
    model = load_model(args.model)
    say(f"structural selection of {model.name} ...")
    solver = Solver(model)
    keep = realizable(model, args.workers, solver=solver)
    selection = structural_selection(model, keep)
    reference = observer_reference(th)
    undetected = undetected_faults(size_file.per_test, generators(model, selection, reference, solver))
    missing = size_file.lacking(undetected)
    if missing:
        print(f"error: {args.sizes} lacks [sizes] or [limits] for {', '.join(missing)}", file=sys.stderr)
        return 2
    say("not detected in practice by the selection: " + (", ".join(undetected) or "none"))
    signals = fault_free_drives(DEFAULT_SCENARIOS, [None, *CALIBRATION_SEEDS], CALIBRATION_DURATION, design.dt,
                                log=say) if undetected else []
    skip = round(CALIBRATION_WARMUP / design.dt)

    def sigma_of(g: Generator) -> float:
        return calibrate(residual_segments(g, signals, skip, design), th.gate).sigma

    run_drive = sweep.scenario_drive(SWEEP_SCENARIO)

    def sweep_one(g: Generator, sigma: float, fault: str) -> sweep.PairLimit:
        (p,) = size_file.detection_limits([g], [sigma], th.gate, fault, run_drive, SWEEP_SEEDS)
        return p

    added, left = augment(model, keep, selection, undetected, sigma_of, sweep_one, reference, args.tries, say, solver)
    provenance = (f"fdi-tune augment {args.model.as_posix()} --sizes {args.sizes.as_posix()} --tries {args.tries}: "
                  f"not detected in practice by the structural selection: {', '.join(undetected) or 'none'};\n"
                  "each test below is the first realizable candidate (fewest unknowns first) that detects them "
                  "within their [limits] (calibrated and swept as calibrate and fault-sizes do)"
                  + (f";\nstill undetected (none of the first {args.tries} candidates): {', '.join(left)}"
                     if left else ""))
    rows = [(" ".join(a.generator.equations), a.comment()) for a in added]
    args.thresholds.write_text(with_augment(args.thresholds.read_text(encoding="utf-8"), rows, provenance),
                               encoding="utf-8")
    still = f", still undetected: {', '.join(left)}" if left else ""
    print(f"wrote {args.thresholds}: {len(added)} tests added{still}")
    return 0
