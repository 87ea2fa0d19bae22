"""Derivative against integral causality for the tests whose sequence differentiates a state twice.

For every test of the exported table that has an observer alternative to a second derivative
(`Generator.note`: ROMO's MSO3/MSO4, the paper's ARR3/ARR4), both generators are calibrated on the same
fault-free drives as `fdi-tune calibrate` (as the ECU sees them) and swept with the same step faults as
`fdi-tune fault-sizes` (cornering, 3 s steps, an alarm with every seed). Prints, per variant, the fault-free
sigma, RMS and peak, and the smallest detected size of every fault of the signature. Nothing is hard-coded.

    python host_tools/bench/compare_causality.py                      # ~5 min on 2 cores
    python host_tools/bench/compare_causality.py --seeds 777 --calibration-seeds   # quicker, fewer drives
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

from fdi_analysis.export.thresholds import Thresholds
from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.causality import synthesize
from fdi_analysis.residuals.evaluate import FilterDesign
from fdi_analysis.residuals.selected import selected_generators
from fdi_host.tuning import sweep
from fdi_host.tuning.calibrate import calibrate
from fdi_host.tuning.cli.calibrate import CALIBRATION_SEEDS, DEFAULT_SCENARIOS, SWEEP_SCENARIO, SWEEP_SEEDS
from fdi_host.tuning.drives import fault_free_drives, observer_reference, residual_segments

ROOT = Path(__file__).resolve().parents[2]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("--model", type=Path, default=ROOT / "analysis/models/romo_grouped.toml")
    ap.add_argument("--thresholds", type=Path, default=ROOT / "analysis/models/romo_thresholds.toml")
    ap.add_argument("--sizes", type=Path, default=ROOT / "host_tools/scenarios/fault_sizes.toml")
    ap.add_argument("--seeds", type=int, nargs="+", default=list(SWEEP_SEEDS), help="noise seeds of the sweep")
    ap.add_argument("--calibration-seeds", type=int, nargs="*", default=list(CALIBRATION_SEEDS),
                    help="noise seeds of the calibration drives besides each scenario's own")
    args = ap.parse_args()

    def say(text: str) -> None:
        print(text, file=sys.stderr)

    th = Thresholds.load(args.thresholds)
    design = FilterDesign(*th.design[:3])
    model = load_model(args.model)
    say(f"synthesising the generators of {model.name} ...")
    reference = observer_reference(th)
    _, gens = selected_generators(model, reference, selection=th.selection, max_tyre_accel=th.max_tyre_accel)
    pairs = [(g, synthesize(model, g.equations, g.name, reference=reference, causality="integral"))
             for g in gens if g.note]
    if not pairs:
        print("no test of the table has an observer alternative to a second derivative")
        return 0
    signals = fault_free_drives(DEFAULT_SCENARIOS, [None, *args.calibration_seeds], None, design.dt, log=say)
    size_file = sweep.SizeFile.load(args.sizes)
    warmup = round(3.0 / design.dt)
    print(f"calibration: {len(signals)} fault-free drives ({', '.join(DEFAULT_SCENARIOS)}); sweep: {SWEEP_SCENARIO}, "
          f"3 s steps, seeds {' '.join(map(str, args.seeds))}; gate {th.gate:g} sigma")
    for derivative, integral in pairs:
        print(f"\n{derivative.name}: {' '.join(derivative.equations)}")
        variants = [("derivative", derivative), ("integral", integral)]
        sigmas = []
        for label, g in variants:
            c = calibrate(residual_segments(g, signals, warmup, design), th.gate)
            sigmas.append(c.sigma)
            print(f"  {label:10s} {g.causality()}")
            print(f"  {'':10s} sigma {c.sigma:.3g}, fault-free RMS {c.rms:.3g}, peak {c.peak:.3g} "
                  f"(peak / RMS {c.peak / c.rms:.1f})")
        named = [replace(g, name=label) for label, g in variants]
        print(f"  {'fault':6s} {'limit':>8s} {'derivative':>11s} {'integral':>9s}   smallest detected size")
        for f in derivative.faults:
            found = size_file.detection_limits(named, sigmas, th.gate, f, sweep.scenario_drive(SWEEP_SCENARIO),
                                               args.seeds, log=say)
            got = {p.test: p.detected_at for p in found}
            cells = [f"{got[label]:g}" if got.get(label) is not None else "-" for label, _ in variants]
            print(f"  {f:6s} {size_file.limits[f]:8g} {cells[0]:>11s} {cells[1]:>9s}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
