"""`fdi-tune residuals MODEL --log LOG`: the generated residuals computed offline on a CAN log."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fdi_analysis.cli.common import EXIT_ERROR
from fdi_analysis.errors import FdiError

if TYPE_CHECKING:
    from fdi_host.can.frame import Frame
    from fdi_host.tuning.on_log import LogResiduals

EXAMPLE = ("example: fdi-sim --scenario cornering --out out/drive.blf && fdi-tune residuals "
           "analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml --log out/drive.blf "
           "--csv out/residuals.csv --plot out/residuals.png --compare-ecu")
ECU_TOLERANCE_SIGMA = 1e-2  # float C against double Python, in fault-free standard deviations (gate: 5)


def register(sub: Any) -> None:
    p = sub.add_parser(
        "residuals",
        help="compute the generated residuals offline on a CAN log (and compare them with the C ECU)",
        description="Synthesise the residual generators of the selection (as export-c does) and run them on "
        "a CAN log (candump .log, Vector .asc or .blf) as the ECU does: the signals its 10 ms steps see "
        "(last frame of each message, DBC scaling, bad-CRC frames dropped), each test inside its operating "
        "domain after the diagnoser's warm-up. Prints per test the share of evaluated steps, RMS and peak in "
        "fault-free sigmas and the first raw alarm; writes the residuals as CSV and a plot on request. With "
        "--compare-ecu the same frames go through the C ECU core with the committed generated table and the "
        f"largest deviation per test is checked against {ECU_TOLERANCE_SIGMA:g} sigma (exit 1 beyond).",
        epilog=EXAMPLE,
    )
    p.add_argument("model", type=Path, help="model file (.toml)")
    p.add_argument("--thresholds", type=Path, required=True, help="thresholds file (design, gate, sigmas)")
    p.add_argument("--log", type=Path, required=True, help="CAN log: .log (candump), .asc or .blf")
    p.add_argument("--csv", type=Path, help="write t and every residual per step here")
    p.add_argument("--plot", type=Path, help="write a PNG of |r|/sigma per test here")
    p.add_argument("--compare-ecu", action="store_true",
                   help="replay the log through the C ECU core (generated table) and compare per step")
    p.add_argument("--align", type=float, default=0.0,
                   help="seconds behind each step at which the signals are taken, each linear between its "
                   "message's frames (the ECU's align_us; 0.02 brings every ROMO message to one instant); default "
                   "0: each message's last frame, as the committed table is calibrated")
    p.add_argument("--warmup", type=float, default=3.0, help="seconds not evaluated after each (re)start "
                   "of a test (default 3, the diagnoser's)")
    p.add_argument("--workers", type=int, default=2, help="worker processes of the MSO search (default 2)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from fdi_analysis.export.thresholds import MissingSigmaError, Thresholds
    from fdi_analysis.model_loader import load_model
    from fdi_analysis.residuals.evaluate import FilterDesign
    from fdi_analysis.residuals.selected import selected_generators
    from fdi_host.can.ecu_view import ecu_view
    from fdi_host.can.logs import read_log
    from fdi_host.tuning.on_log import LogError, log_residuals, plot, write_csv

    if not args.align >= 0.0:
        print(f"fdi-tune: error: --align {args.align} is not a time >= 0", file=sys.stderr)
        return EXIT_ERROR
    if args.compare_ecu:
        from fdi_host.ecu.bindings import Ecu, EcuError, bus_align

        try:
            Ecu("romo", align_s=args.align)
        except EcuError:
            print(f"fdi-tune: error: the ECU core refuses --align {args.align}: a message's kept frames do not "
                  f"reach back that far ({bus_align('romo'):g} s takes every message at one instant)",
                  file=sys.stderr)
            return EXIT_ERROR
    th = Thresholds.load(args.thresholds)
    design = FilterDesign(th.design[0], th.design[1], th.design[2])
    try:
        frames = sorted(read_log(args.log), key=lambda f: f.timestamp)
    except (OSError, FdiError) as exc:  # fdi_host.can.logs.LogError names the file and what is wrong
        print(f"fdi-tune: error: cannot read {args.log}: {exc}", file=sys.stderr)
        return EXIT_ERROR
    if len(frames) < 2:
        print(f"fdi-tune: error: {args.log} holds {len(frames)} frame(s); nothing to evaluate", file=sys.stderr)
        return EXIT_ERROR
    model = load_model(args.model)
    print(f"synthesising the generators of {model.name} ...", file=sys.stderr)
    _, gens = selected_generators(model, th.observer_reference(), workers=args.workers, selection=th.selection,
                                  max_tyre_accel=th.max_tyre_accel)
    try:
        sigmas = th.sigmas(gens)
    except MissingSigmaError as exc:
        print(f"fdi-tune: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    t, sig = ecu_view(frames, design.dt, align=args.align)
    warmup = round(args.warmup / design.dt)
    try:
        res = log_residuals(gens, sigmas, th.gate, t, sig, design, warmup)
    except LogError as exc:
        print(f"fdi-tune: error: {args.log}: {exc}", file=sys.stderr)
        return EXIT_ERROR
    print(f"{args.log}: {len(frames)} frames, {t.size} steps of {design.dt * 1e3:g} ms, gate {th.gate:g} sigma")
    print(f"{'test':10} {'evaluated':>9} {'RMS/sigma':>9} {'peak/sigma':>10}  first raw alarm")
    for tr in res.tests:
        alarm = "none" if tr.first_alarm_s is None else f"{tr.first_alarm_s:.2f} s"
        print(f"{tr.name:10} {tr.evaluated / max(t.size, 1):9.0%} {tr.rms_ratio:9.2f} {tr.peak_ratio:10.2f}  {alarm}")
    if args.csv is not None:
        write_csv(res, args.csv)
        print(f"wrote {args.csv}")
    if args.plot is not None:
        plot(res, args.plot, args.log.name)
        print(f"wrote {args.plot}")
    return _compare(res, frames, warmup, args.align) if args.compare_ecu else 0


def _compare(res: LogResiduals, frames: Sequence[Frame], warmup: int, align: float) -> int:
    """Replay the frames through the C ECU core (generated table) and compare per step; 1 beyond tolerance."""
    import numpy as np

    from fdi_host.ecu.bindings import table_info
    from fdi_host.ecu.offline import replay
    from fdi_host.tuning.on_log import compare_with_ecu

    info = table_info("romo")
    labels = [f"MSO{m}" for m in info.mso_ids]
    if labels != [tr.name for tr in res.tests]:
        print(f"fdi-tune: error: the ECU's generated table holds {labels}, the model's selection "
              f"{[tr.name for tr in res.tests]}: regenerate (scripts/generate.sh) and rebuild", file=sys.stderr)
        return EXIT_ERROR
    ecu = replay("romo", frames, align_s=align)
    steps = np.asarray([r.step for r in ecu])
    if steps.size and not np.array_equal(steps, np.arange(1, steps.size + 1)):
        print("fdi-tune: error: the ECU skipped steps (a gap in the log); compare on a gap-free log",
              file=sys.stderr)
        return EXIT_ERROR
    # the generators' residuals: what a test evaluates (its estimator's innovation) plus what its estimate removed
    r_ecu = (np.asarray([r.residuals for r in ecu], dtype=float).reshape(len(ecu), len(labels))
             + np.asarray([r.offsets for r in ecu], dtype=float).reshape(len(ecu), len(labels)))
    ev = np.asarray([[s != "not_evaluable" for s in r.test_status] for r in ecu], dtype=bool).reshape(r_ecu.shape)
    worst = 0.0
    print(f"C ECU core ({len(ecu)} steps) against the offline residuals, on the steps both evaluate:")
    for d in compare_with_ecu(res, r_ecu, ev, warmup):
        print(f"  {d.name:10} {d.compared:7} steps  max |deviation| {d.max_dev_sigma:.2e} sigma")
        worst = max(worst, d.max_dev_sigma)
    ok = worst <= ECU_TOLERANCE_SIGMA
    print(f"{'agree' if ok else 'DISAGREE'}: largest deviation {worst:.2e} sigma (tolerance {ECU_TOLERANCE_SIGMA:g})")
    return 0 if ok else 1
