"""`fdi-tune uncertainty MODEL`: how far the model's uncertainty envelope moves the residuals of the tests on
board, against their gates (`fdi_host.tuning.uncertainty_report`)."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

from fdi_analysis.cli.common import EXIT_ERROR
from fdi_host.tuning.cli.calibrate import DEFAULT_SCENARIOS

EXAMPLE = ("example: fdi-tune uncertainty analysis/models/romo_grouped.toml --thresholds "
           "analysis/models/romo_thresholds.toml --sizes host_tools/scenarios/fault_sizes.toml --out out/uncertainty")


def register(sub: Any) -> None:
    p = sub.add_parser(
        "uncertainty",
        help="the residual spread of every test on board over the model's uncertainty envelope, in gates, and "
        "its fault-to-uncertainty ratios",
        description="Synthesise the tests on board (the thresholds file's selection, as export-c does) and, along "
        "each scenario's fault-free drive (its operating points, model plant), compute every test's analytic "
        "sensitivity to each uncertain parameter and unknown parameter or input the model declares (ranges in "
        "the model file), its first-order worst-case spread over the envelope against its gate (gate x sigma of "
        "the thresholds file), the quantity that contributes most, and per fault at its required size the "
        "fault-to-noise and fault-to-uncertainty ratios. Writes uncertainty.md and uncertainty.json to --out. "
        "About 20 s per test (one symbolic pass per uncertain quantity).",
        epilog=EXAMPLE,
    )
    p.add_argument("model", type=Path, help="model file (.toml) that declares ranges or unknown parameters/inputs")
    p.add_argument("--thresholds", type=Path, required=True, help="thresholds file (design, gate, sigmas)")
    p.add_argument("--sizes", type=Path, required=True, help="fault-size file with the [requirement] table")
    p.add_argument("--out", type=Path, required=True, help="directory for uncertainty.md and uncertainty.json")
    p.add_argument("--scenarios", nargs="+", default=list(DEFAULT_SCENARIOS),
                   help="manoeuvres whose operating points are used (default: the calibration's five)")
    p.add_argument("--only", nargs="*", default=None, help="only these tests (labels, e.g. MSO7)")
    p.add_argument("--workers", type=int, default=2, help="worker processes of the candidate search (default 2)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from fdi_analysis.export.fault_sizes import FaultSizes
    from fdi_analysis.export.thresholds import MissingSigmaError, Thresholds
    from fdi_analysis.model_loader import load_model
    from fdi_analysis.residuals.evaluate import FilterDesign
    from fdi_analysis.residuals.selected import selected_generators
    from fdi_analysis.residuals.uncertainty_sensitivity import uncertainties
    from fdi_host.tuning.drives import drive
    from fdi_host.tuning.uncertainty_report import markdown, table_spread

    th = Thresholds.load(args.thresholds)
    design = FilterDesign(th.design[0], th.design[1], th.design[2])
    model = load_model(args.model)
    if not uncertainties(model):
        print(f"fdi-tune: error: {args.model} declares no uncertain parameter (range) and no unknown parameter "
              "or input: nothing to spread", file=sys.stderr)
        return EXIT_ERROR
    size_file = FaultSizes.load(args.sizes)
    size_file.check_faults([f.name for f in model.faults])
    print(f"synthesising the generators of {model.name} ...", file=sys.stderr)
    _, gens = selected_generators(model, th.observer_reference(), workers=args.workers, selection=th.selection,
                                  max_tyre_accel=th.max_tyre_accel, sensitivities=True)
    if args.only:
        unknown = sorted(set(args.only) - {g.name for g in gens})
        if unknown:
            print(f"fdi-tune: error: no test {', '.join(unknown)} on board (tests: "
                  f"{', '.join(g.name for g in gens)})", file=sys.stderr)
            return EXIT_ERROR
        gens = [g for g in gens if g.name in set(args.only)]
    try:
        sigmas = th.sigmas(gens)
    except MissingSigmaError as exc:
        print(f"fdi-tune: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    drives = {}
    for sc in args.scenarios:
        print(f"fault-free drive {sc} (model plant, its own seed) ...", file=sys.stderr)
        drives[sc] = drive(sc, dt=design.dt, as_ecu_sees=True)[1]
    t0 = time.monotonic()

    def progress(done: int, total: int, name: str) -> None:
        print(f"  {name}: {done}/{total} tests ({time.monotonic() - t0:.0f} s)", file=sys.stderr, flush=True)

    rows = table_spread(model, gens, sigmas, th.gate, dict(size_file.requirement), drives, design, progress)
    provenance = (f"`fdi-tune uncertainty {args.model.as_posix()} --thresholds {args.thresholds.as_posix()} --sizes "
                  f"{args.sizes.as_posix()}`: the {len(gens)} tests of the table, at the operating points of the "
                  f"model plant's fault-free drives {', '.join(args.scenarios)} (their own seeds, as the ECU sees "
                  "them); the spread is the model's first-order worst case, not a measurement.")
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "uncertainty.md").write_text(markdown(model, rows, provenance), encoding="utf-8")
    doc = {"model": model.name, "provenance": provenance,
           "uncertainties": [vars(u) | {"half_width": u.half_width} for u in uncertainties(model)],
           "tests": [r.to_dict() for r in rows]}
    (args.out / "uncertainty.json").write_text(json.dumps(doc, indent=1, allow_nan=True) + "\n", encoding="utf-8")
    print(f"wrote {args.out / 'uncertainty.md'} and {args.out / 'uncertainty.json'}")
    return 0
