"""`fdi-tune calibrate MODEL`: residual noise levels from fault-free simulated drives -> thresholds file."""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fdi_analysis.cli.common import EXIT_ERROR
from fdi_analysis.errors import InputError
from fdi_analysis.names import in_order
from fdi_host.tuning.seeds import CALIBRATION_SEEDS, CONFIRM_SEED_OFFSETS, SWEEP_SEEDS
from fdi_host.vehicle import resolve, vehicle_arg

if TYPE_CHECKING:
    from fdi_analysis.export.thresholds import Thresholds
    from fdi_analysis.model import Model
    from fdi_analysis.residuals.evaluate import FilterDesign
    from fdi_analysis.residuals.generator import Generator

EXAMPLE = ("example: fdi-tune calibrate analysis/models/romo_grouped.toml --thresholds "
           "analysis/models/romo_thresholds.toml --fleet 12   (the shipped calibration: 12 truth-plant vehicles, "
           "with estimators and adaptive thresholds; ~7 min)")

# All five scenarios of host_tools/scenarios; near standstill (low_speed) the tyre-law residuals are outside
# their operating domain (Generator.min_speed) and not evaluated, as on the vehicle.
DEFAULT_SCENARIOS = ("cornering", "fig6", "low_speed", "slalom", "straight")
# Each drive as long as its scenario (as the quality suite's fault-free drives): a shorter drive would miss the
# end of a profile, e.g. fig6's hardest transient at 34 s (sawtooth yaw-rate reset with a side-slip step).
CALIBRATION_DURATION: float | None = None
CALIBRATION_WARMUP = 3.0  # s ignored at the start
SWEEP_SCENARIO = "cornering"  # fault-sizes: the fault-free drive the step faults are injected in


def register(sub: Any) -> None:
    p = sub.add_parser(
        "calibrate",
        help="calibrate the variances of the generated residual generators on fault-free simulated drives",
        description="Synthesise the residual generators of the selection (as export-c does), run them on "
        "fault-free simulated drives of several scenarios and noise seeds, as the ECU sees them (the drives' "
        "CAN frames at their cycle times, held at the diagnosis steps, DBC quantisation; fdi_host.can.ecu_view), "
        "and write each residual's sigma (no raw alarm of the gate or the CUSUM in any drive inside each test's "
        "operating domain after the warm-up, times a 25 %% margin) into the [generated] table of the "
        "thresholds file, and, where the file defines an operating envelope ([envelope]: signals, votes, margin), "
        "each envelope signal's limit, the margin times its largest magnitude in the drives after the warm-up (with "
        "--fleet: its 99.5th percentile over the fleet), into "
        "its [envelope_limits] table (the rest of the file is kept).",
        epilog=EXAMPLE,
    )
    p.add_argument("model", type=Path, nargs="?", help="model file (.toml); or give --vehicle")
    p.add_argument("--thresholds", type=Path, help="thresholds file to update (with MODEL)")
    _add_vehicle(p)
    p.add_argument("--scenarios", nargs="+", default=list(DEFAULT_SCENARIOS), help="fault-free drives")
    p.add_argument("--duration", type=float, default=CALIBRATION_DURATION,
                   help="seconds per drive (default: each scenario's own duration)")
    p.add_argument("--seeds", type=int, nargs="*", default=list(CALIBRATION_SEEDS),
                   help="noise seeds of further drives per scenario besides the scenario's own (default 1001 ... 1012)")
    p.add_argument("--warmup", type=float, default=CALIBRATION_WARMUP, help="seconds ignored at the start (default 3)")
    p.add_argument("--workers", type=int, default=2, help="worker processes of the MSO search (default 2)")
    p.add_argument("--fleet", type=int, default=0, metavar="N",
                   help="calibrate on the truth plant instead: the fault-free drives of calibration vehicles 1 .. N "
                   "(never an evaluation vehicle) in every fleet scenario, each test with its on-line estimator and "
                   "adaptive threshold as the diagnoser runs them: writes what each test estimates ([estimation]) "
                   "and its sigma (fdi_host.tuning.fleet_calibration); --scenarios, --seeds and --duration do not "
                   "apply")
    p.add_argument("--check", action="store_true",
                   help="do not write: exit 1 when the file's [generated] table differs from the calibration now")
    p.set_defaults(func=run)

    q = sub.add_parser(
        "fault-sizes",
        help="sweep step faults on a simulated drive: the stated fault size of every (fault, test) pair",
        description="For every fault and every test of its signature, the smallest size on a 1-1.5-2-3-5-7 "
        "grid at which the test raises a raw alarm (gate or CUSUM, inside its operating domain) within 3 s of "
        "the step (the drive as the ECU sees it, as for calibrate); the stated size is the next grid value. "
        "Written below a marker line of the fault-size file as [per_test.<fault>] tables (the hand-written "
        "[requirement] and [limits] above are kept). Pairs that "
        "the sweep leaves without a stated size are then swept in the other scenarios, each driven whole with the "
        "fault from 4 s on, one drive per size (up to the fault's [limits] value, the limit included), and "
        "written as [per_test_scenario.<fault>] tables (scenario, size); pairs no scenario detects within the "
        "limit are written as 'not detectable by this test in practice'.",
        epilog="example: fdi-tune fault-sizes analysis/models/romo_grouped.toml --thresholds "
        "analysis/models/romo_thresholds.toml --sizes host_tools/scenarios/fault_sizes.toml",
    )
    q.add_argument("model", type=Path, nargs="?", help="model file (.toml); or give --vehicle")
    q.add_argument("--thresholds", type=Path, help="thresholds file (gate, sigmas) (with MODEL)")
    q.add_argument("--sizes", type=Path, help="fault-size file with [requirement] and [limits] (with MODEL)")
    _add_vehicle(q)
    q.add_argument("--check", action="store_true",
                   help="a vehicle on the generic simulator: do not write, exit 1 when the file's per-test tables "
                        "differ from the sweep now")
    q.add_argument("--scenario", default=SWEEP_SCENARIO, help="fault-free scenario the faults are injected in")
    q.add_argument("--seeds", type=int, nargs="+", default=list(SWEEP_SEEDS),
                   help="noise seeds of the sweep drives; an alarm counts when every seed alarms (default 777 778)")
    q.add_argument("--other-scenarios", nargs="*", default=None,
                   help="scenarios driven whole for the pairs the --scenario sweep leaves without a stated size "
                   "(default: the other four of host_tools/scenarios, in that order for ties; none given: no such "
                   "sweep)")
    q.add_argument("--faults", nargs="*", help="only these faults (default: all of the selection)")
    q.add_argument("--workers", type=int, default=2, help="worker processes of the MSO search (default 2)")
    q.set_defaults(func=run_sizes)


def round_up(x: float, digits: int = 3) -> float:
    """x rounded up to `digits` significant digits (a limit written as text never below the value it covers)."""
    if x <= 0.0 or not math.isfinite(x):
        return x
    scale = 10.0 ** (math.floor(math.log10(x)) - digits + 1)
    return math.ceil(x / scale - 1e-9) * scale


Row = tuple[str, float, str]  # a [generated] or [envelope_limits] entry: key, value, comment
EstimationRow = tuple[str, tuple[tuple[str, ...], ...], str]  # an [estimation] entry: equations, groups, comment


@dataclass(frozen=True)
class Tables:
    """What a calibration writes into the thresholds file (besides the [observer] table)."""

    generated: list[Row]
    provenance: str
    envelope: list[Row]
    estimation: list[EstimationRow]


def _add_vehicle(p: argparse.ArgumentParser) -> None:
    p.add_argument("--vehicle", type=vehicle_arg, metavar="NAME|PATH",
                   help="instead of MODEL, --thresholds and --sizes: a vehicle's files (fdi_host.vehicle); one on the "
                        "generic simulator (three_tank, a vehicle folder) is tuned on drives of its scenario "
                        "(fdi_host.tuning.generic; the ROMO options do not apply)")


def _files(args: argparse.Namespace, command: str) -> int | None:
    """--vehicle: a generic vehicle tuned here (its exit code), or ROMO's files filled into args (None); without
    it, MODEL and the files must be given."""
    if args.vehicle is None:
        missing = [o for o, v in (("MODEL", args.model), ("--thresholds", args.thresholds),
                                  ("--sizes", getattr(args, "sizes", True))) if v is None]
        if missing:
            raise InputError(f"fdi-tune {command}: give {', '.join(missing)}, or --vehicle NAME|PATH")
        if command == "fault-sizes" and args.check:
            raise InputError("fdi-tune fault-sizes --check: for a vehicle on the generic simulator only")
        return None
    v = resolve(args.vehicle)
    if v.simulator == "generic":
        from fdi_host.tuning.generic import tune_vehicle

        return tune_vehicle(v, command, args.workers, args.check)
    if command == "fault-sizes" and args.check:
        raise InputError("fdi-tune fault-sizes --check: for a vehicle on the generic simulator only")
    if v.thresholds is None or (command == "fault-sizes" and v.fault_sizes is None):
        raise InputError(f"vehicle {v.name}: its manifest {v.manifest} names no thresholds or fault-size file")
    args.model, args.thresholds = v.model, v.thresholds
    if command == "fault-sizes":
        args.sizes = v.fault_sizes
    return None


def run(args: argparse.Namespace) -> int:
    done = _files(args, "calibrate")
    if done is not None:
        return done
    from fdi_analysis.export.thresholds import Thresholds, with_generated
    from fdi_analysis.model_loader import load_model
    from fdi_analysis.residuals.evaluate import FilterDesign
    from fdi_analysis.residuals.selected import selected_generators
    from fdi_host.tuning.drives import observer_reference

    th = Thresholds.load(args.thresholds)
    design = FilterDesign(th.design[0], th.design[1], th.design[2])
    model = load_model(args.model)
    print(f"synthesising the generators of {model.name} ...", file=sys.stderr)
    reference = observer_reference()  # c_ref measured now on the reference drive (written to [observer])
    _, gens = selected_generators(model, reference, workers=args.workers, selection=th.selection,
                                  max_tyre_accel=th.max_tyre_accel, uncertainty=args.fleet > 0)
    skip = round(args.warmup / design.dt)
    tables = (_fleet_tables(args, th, model, gens, design, skip) if args.fleet > 0
              else _model_plant_tables(args, th, gens, design, skip))
    observer_rows = []
    for g in gens:
        if g.observer is not None and g.observer.c.free_symbols:
            c_ref = reference.sensitivity(g)
            assert c_ref is not None
            observer_rows.append((" ".join(g.equations), c_ref, f"{g.name}: observer for {g.observer.state}, "
                                  f"residual {g.residual_equation}"))
    old = args.thresholds.read_text(encoding="utf-8")
    new = with_generated(old, tables.generated, tables.provenance, observer_rows, tables.envelope, tables.estimation)
    if args.check:
        if new != old:
            print(f"{args.thresholds} is stale: run scripts/generate.sh (fdi-tune calibrate)", file=sys.stderr)
            return 1
        print(f"{args.thresholds} is up to date")
        return 0
    args.thresholds.write_text(new, encoding="utf-8")
    print(f"wrote {args.thresholds}")
    return 0


def _fleet_tables(args: argparse.Namespace, th: Thresholds, model: Model, gens: list[Generator],
                  design: FilterDesign, skip: int) -> Tables:
    """The calibration on truth-plant calibration vehicles 1 .. args.fleet (fdi_host.tuning.fleet_calibration)."""
    from fdi_analysis.residuals.uncertainty_sensitivity import uncertainties
    from fdi_host.sim.scenario import FLEET_SCENARIOS
    from fdi_host.tuning.calibrate import MARGIN
    from fdi_host.tuning.fleet_calibration import (
        ENVELOPE_PERCENTILE,
        KAPPA,
        calibrate_fleet,
        envelope_limits,
        fleet_drives,
        inside_envelope,
    )

    signals = fleet_drives(range(1, args.fleet + 1), FLEET_SCENARIOS, design.dt,
                           progress=lambda s: print(s, file=sys.stderr))
    inside = None
    envelope: list[Row] = []
    if th.envelope is not None:
        limits = {k: round_up(v) for k, v in
                  envelope_limits(signals, th.envelope.signals, th.envelope.margin, skip).items()}
        inside = [inside_envelope(d, limits, th.envelope.votes) for d in signals]
        for sig in th.envelope.signals:
            envelope.append((sig, limits[sig], f"{sig}: {th.envelope.margin:g} x the {ENVELOPE_PERCENTILE:g}th "
                             "percentile of its magnitude over the calibration fleet"))
            print(f"envelope {sig}: limit {limits[sig]:.3g}")
    cals = calibrate_fleet(gens, signals, {u.name: u for u in uncertainties(model)}, th.gate, design, skip,
                           progress=lambda s: print(s, file=sys.stderr), inside=inside)
    generated: list[Row] = []
    estimation: list[EstimationRow] = []
    for tc in cals:
        generated.append((tc.equations, tc.sigma.sigma**2, f"{tc.generator}: sigma {tc.sigma.sigma:.3g} (innovation "
                          f"RMS {tc.sigma.rms:.3g}, peak {tc.sigma.peak:.3g}; adaptive part {tc.sigma.share:.2f} gates "
                          "at the median)"))
        if tc.groups:
            estimation.append((tc.equations, tc.groups, tc.generator))
    provenance = (f"fdi-tune calibrate {args.model.as_posix()} --fleet {args.fleet}: truth-plant calibration "
                  f"vehicles 1 .. {args.fleet} (fdi_host.tuning.seeds), every scenario of the fleet "
                  f"({' '.join(FLEET_SCENARIOS)}), fault-free, the drives' CAN frames as the ECU's steps see them, "
                  f"--warmup {args.warmup:g}: each test with its on-line estimator (what it estimates: the "
                  "quantities of largest median spread share, constants lumped) and adaptive threshold (kappa "
                  f"{KAPPA:g}), in its operating domain, no raw alarm (|innovation| beyond gate sigma plus the "
                  f"adaptive part, or CUSUM k = 1.5, h = 150) in any drive, sigma times {MARGIN}")
    return Tables(generated, provenance, envelope, estimation)


def _model_plant_tables(args: argparse.Namespace, th: Thresholds, gens: list[Generator], design: FilterDesign,
                        skip: int) -> Tables:
    """The calibration on the model plant's fault-free drives of args.scenarios and args.seeds (fixed gates)."""
    import numpy as np

    from fdi_host.tuning.calibrate import MARGIN, calibrate
    from fdi_host.tuning.drives import fault_free_drives, residual_segments

    signals = fault_free_drives(args.scenarios, [None, *args.seeds], args.duration, design.dt,
                                log=lambda s: print(s, file=sys.stderr))
    generated: list[Row] = []
    for g in gens:
        c = calibrate(residual_segments(g, signals, skip, design), th.gate)
        generated.append((" ".join(g.equations), c.variance, f"{g.name}: sigma {c.sigma:.3g} (fault-free RMS "
                          f"{c.rms:.3g}, peak {c.peak:.3g})"))
        print(f"{g.name}: sigma {c.sigma:.3g}  fault-free RMS {c.rms:.3g}  peak {c.peak:.3g}")
    provenance = (f"fdi-tune calibrate {args.model.as_posix()} --scenarios {' '.join(args.scenarios)} "
                  f"--seeds {' '.join(map(str, args.seeds))} (and each scenario's own seed) "
                  + ("(each scenario's own duration)" if args.duration is None else f"--duration {args.duration:g}")
                  + f" --warmup {args.warmup:g}, the drives' CAN frames as the ECU's steps see "
                  f"them: in each test's operating domain, no raw alarm (|r| > gate sigma or CUSUM k = 1.5, "
                  f"h = 150) in any fault-free drive, sigma times {MARGIN}")
    envelope: list[Row] = []
    if th.envelope is not None:
        for sig in th.envelope.signals:
            if any(sig not in d for d in signals):
                raise InputError(f"{th.source}: [envelope] signal {sig!r} is not a measured signal of the drives")
            peak = max(float(np.max(np.abs(np.asarray(d[sig], dtype=float)[skip:]))) for d in signals)
            limit = round_up(th.envelope.margin * peak)
            envelope.append((sig, limit, f"{sig}: largest |value| {peak:.3g} in the calibration drives, times "
                                         f"{th.envelope.margin:g}"))
            print(f"envelope {sig}: largest |value| {peak:.3g}, limit {limit:.3g}")
    return Tables(generated, provenance, envelope, [])


def run_sizes(args: argparse.Namespace) -> int:
    done = _files(args, "fault-sizes")
    if done is not None:
        return done
    from fdi_analysis.export.thresholds import Thresholds
    from fdi_analysis.model_loader import load_model
    from fdi_analysis.residuals.selected import selected_generators
    from fdi_host.tuning import sweep, sweep_manoeuvres
    from fdi_host.tuning.drives import observer_reference

    def say(text: str) -> None:
        print(text, file=sys.stderr)

    th = Thresholds.load(args.thresholds)
    size_file = sweep.SizeFile.load(args.sizes)
    model = load_model(args.model)
    print(f"synthesising the generators of {model.name} ...", file=sys.stderr)
    _, gens = selected_generators(model, observer_reference(th), workers=args.workers, selection=th.selection,
                                  max_tyre_accel=th.max_tyre_accel)
    sigmas = th.sigmas(gens)
    model_faults = [f.name for f in model.faults]
    faults = in_order({f for g in gens for f in g.faults}, model_faults)
    if args.faults:
        faults = [f for f in faults if f in set(args.faults)]
    missing = size_file.lacking(faults)
    if missing:
        print(f"fdi-tune: error: {args.sizes} lacks [requirement] or [limits] for {', '.join(missing)}",
              file=sys.stderr)
        return EXIT_ERROR
    run_drive = sweep.scenario_drive(args.scenario)
    others = [s for s in (DEFAULT_SCENARIOS if args.other_scenarios is None else args.other_scenarios)
              if s != args.scenario]
    whole_drive = sweep_manoeuvres.scenario_drive()
    pairs: list[sweep.PairLimit] = []
    elsewhere: list[sweep.ScenarioLimit] = []
    for f in faults:
        mine = size_file.detection_limits(gens, sigmas, th.gate, f, run_drive, args.seeds, log=say)
        pairs.extend(mine)
        pending = [(g, s) for g, s in zip(gens, sigmas, strict=True)
                   if any(p.test == g.name and p.stated is None for p in mine)]
        if pending and others:
            found = sweep_manoeuvres.sweep_scenarios(pending, th.gate, f, size_file.sizes[f] / 10.0,
                                                     size_file.limits[f], whole_drive, args.seeds, others, log=say)
            elsewhere.extend(found.values())
    provenance = (f"fdi-tune fault-sizes {args.model.as_posix()} --scenario {args.scenario} "
                  f"--seeds {' '.join(map(str, args.seeds))} (CAN frames as the ECU's steps see them)\n"
                  f"steps of {sweep.ON:g} s (then {sweep.OFF:g} s off) "
                  f"from {sweep.START:g} s, "
                  "sizes from [requirement] / 10 up to [limits] on the grid 1, 1.5, 2, 3, 5, 7 x 10^k;\n"
                  "raw alarm of the diagnoser with every seed (|r| > gate sigma or CUSUM k = 1.5, h = 150 from the "
                  "onset, sigma of "
                  f"{args.thresholds.as_posix()}) inside the test's operating domain;\n"
                  "stated size = the grid value above the first alarm, confirmed (raised along the grid until it "
                  "alarms in a drive of its own with every seed and every seed + "
                  f"{', '.join(map(str, CONFIRM_SEED_OFFSETS))});\n"
                  "pairs without a stated size there: swept in "
                  f"{', '.join(others) if others else '(no other scenario)'}, each driven whole with the fault from "
                  f"{sweep_manoeuvres.ONSET:g} s on (an alarm after the onset with every seed, none in the seed's "
                  "fault-free drive), sizes up to the limit included, the scenario of the first alarm refined and "
                  "confirmed alike -> [per_test_scenario.<fault>];\n"
                  "tests/analysis/test_residual_faults.py checks every pair at it with another noise seed.")
    section = sweep.render_section(pairs, provenance, [g.name for g in gens], args.scenario, elsewhere, others,
                                   model_faults)
    if args.faults:
        print(section)
        return 0
    args.sizes.write_text(sweep.write_section(args.sizes.read_text(encoding="utf-8"), section), encoding="utf-8")
    n_primary = sum(p.stated is not None for p in pairs)
    print(f"wrote {args.sizes}: {n_primary} pairs with a stated size in {args.scenario}, {len(elsewhere)} in another "
          f"scenario, {len(pairs) - n_primary - len(elsewhere)} not detectable in practice")
    return 0
