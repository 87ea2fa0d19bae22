"""`fdi-tune screen MODEL`: the practical detectability of every realizable candidate test -> screening file."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

from fdi_host.tuning.cli.calibrate import DEFAULT_SCENARIOS
from fdi_host.tuning.seeds import CALIBRATION_SEEDS

EXAMPLE = ("example: fdi-tune screen analysis/models/romo_grouped.toml --thresholds "
           "analysis/models/romo_thresholds.toml --sizes host_tools/scenarios/fault_sizes.toml "
           "--out analysis/models/romo_screening.json.gz")
# Noise seeds of the screening's sigma drives besides each scenario's own: the calibration's, so that the selection
# judges a test by the sigma it ships with (`fdi-tune calibrate` of the selected tests). With two seeds the sigmas
# came out up to 46 % smaller than the calibration's, and tests were selected for faults they then saw only near
# their gate (MSO59 and f12/f16).
SCREENING_SEEDS = CALIBRATION_SEEDS


def register(sub: Any) -> None:
    p = sub.add_parser(
        "screen",
        help="measure every realizable candidate test: sigma and, per fault and manoeuvre, the share of operating "
        "points where its fault-to-noise ratio at the required fault size clears the gate with margin",
        description="Synthesise the residual generator of every realizable candidate MSO set, calibrate its sigma "
        "on fault-free drives as `fdi-tune calibrate` does (every scenario, its own and the calibration's twelve "
        "noise seeds, as the ECU sees them), and along each scenario's fault-free drive evaluate the effect of "
        "every fault of its signature at the required size ([requirement] of --sizes; the residual computed with "
        "the faults kept, no simulation per fault): the share of operating points where the fault-to-noise ratio "
        "clears gate x margin, and its median. Written as JSON for `fdi-analyze practical`. About 25 minutes for "
        "the 580 ROMO candidates on 2 workers.",
        epilog=EXAMPLE,
    )
    p.add_argument("model", type=Path, help="model file (.toml)")
    p.add_argument("--thresholds", type=Path, required=True, help="thresholds file (gate, design point, c_ref)")
    p.add_argument("--sizes", type=Path, required=True, help="fault-size file with the [requirement] table")
    p.add_argument("--out", type=Path, required=True, help="screening file to write (.json)")
    p.add_argument("--workers", type=int, default=2, help="worker processes (default 2)")
    p.add_argument("--only", nargs="*", default=None, help="screen only these candidates (labels, e.g. MSO7)")
    p.add_argument("--scenarios", nargs="+", default=list(DEFAULT_SCENARIOS),
                   help="manoeuvres to screen in (default: all five; sigma from their drives only)")
    p.add_argument("--domain-factor", type=float, default=None,
                   help="a study, not the selection's input: tyre-law tests evaluable from this multiple of the slip "
                   "floor v_eps on (the generators' own factor by default; 0: everywhere, standstill included)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from fdi_analysis.export.fault_sizes import FaultSizes
    from fdi_analysis.export.thresholds import Thresholds
    from fdi_analysis.model_loader import load_model
    from fdi_analysis.residuals.evaluate import FilterDesign
    from fdi_analysis.residuals.generator import DOMAIN_FACTOR
    from fdi_analysis.residuals.selected import realizable
    from fdi_analysis.selection.practical import DETECT_S, MARGIN, SHARE, Screening
    from fdi_host.tuning.drives import fault_free_drives, observer_reference
    from fdi_host.tuning.screening import ScreenSetup, screen

    th = Thresholds.load(args.thresholds)
    design = FilterDesign(th.design[0], th.design[1], th.design[2])
    model = load_model(args.model)
    size_file = FaultSizes.load(args.sizes)
    size_file.check_faults([f.name for f in model.faults])
    sizes = dict(size_file.requirement)
    seeds = [None, *SCREENING_SEEDS]
    names = tuple(args.scenarios)
    factor = DOMAIN_FACTOR if args.domain_factor is None else args.domain_factor
    if factor < 0.0:
        raise SystemExit(f"fdi-tune screen: --domain-factor must be >= 0, not {factor:g}")
    drives = fault_free_drives(names, seeds, None, design.dt, log=lambda s: print(s, file=sys.stderr))
    scenarios = {sc: i * len(seeds) for i, sc in enumerate(names)}  # each scenario's own drive
    setup = ScreenSetup(model, observer_reference(th), th.gate, design, sizes, drives, scenarios, MARGIN, factor)
    print(f"realizable candidates of {model.name} ...", file=sys.stderr)
    cands = realizable(model, args.workers)
    if args.only:
        cands = [c for c in cands if c.label in set(args.only)]
    t0 = time.monotonic()

    def progress(done: int, total: int) -> None:
        print(f"  screened {done}/{total} ({time.monotonic() - t0:.0f} s)", file=sys.stderr, flush=True)

    results = screen(setup, cands, args.workers, progress)
    provenance = (f"fdi-tune screen {args.model.as_posix()} --thresholds {args.thresholds.as_posix()} --sizes "
                  f"{args.sizes.as_posix()}: fault-free drives of {', '.join(names)} (their own seeds and "
                  f"{', '.join(map(str, SCREENING_SEEDS))}) as the ECU sees them")
    if factor != DOMAIN_FACTOR:
        provenance += f"; tyre-law tests evaluable from |vx| >= {factor:g} x v_eps (a study: the generators use " \
                      f"{DOMAIN_FACTOR:g})"
    Screening(model.name, provenance, th.gate, MARGIN, SHARE, sizes, names,
              tuple(results), DETECT_S, tuple(SCREENING_SEEDS)).dump(args.out)
    print(f"wrote {args.out}: {len(results)} candidates ({sum(1 for r in results if r.rejected)} without a generator)")
    return 0
