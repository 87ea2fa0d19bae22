"""``fdi-sim``: simulate a ROMO drive with faults and write the sensor CAN traffic as a log file.

The top of the host tools: ``fdi-sim fig6 ...`` dispatches to `fdi_host.paper.fig6` and ``fdi-sim live ...``
to `fdi_host.live.sim`, so this one entry point spans the simulator, the paper and the live bus.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from tqdm import tqdm

from fdi_analysis.cli.common import add_version, run, use_file_backend
from fdi_host.can import traffic
from fdi_host.can.dbc import CanDatabase
from fdi_host.can.frame import Frame
from fdi_host.can.logs import formats_text, is_log, write_log
from fdi_host.live import sim as live_sim
from fdi_host.paper import fig6
from fdi_host.sim.drive import simulate_from_args, simulate_vehicle_from_args, write_truth, write_vehicle_truth
from fdi_host.sim.options import add_drive_arguments
from fdi_host.sim.scenario import available, load_scenario
from fdi_host.vehicle import Vehicle, add_vehicle_argument, resolve

EPILOG = """\
examples:
  fdi-sim --scenario fig6 --fault f4@5s:0.5 --out drive.blf
  fdi-sim --scenario cornering --fault f6@10s:0.02:ramp=2s --out drive.asc --out drive.log --plot drive.png
  fdi-sim --scenario slalom --fault f10@3s:-80:end=9s --fault f22@4s:2:intermittent=1s/0.3 --npz raw.npz
  fdi-sim --scenario straight --no-scenario-faults --no-noise --out clean.blf
  fdi-sim --list
  fdi-sim fig6 --out-dir out/fig6        (the paper's Fig. 6, see fdi-sim fig6 --help)
  fdi-sim live --scenario fig6 --fault f4@5s:0.5 --interface udp_multicast    (real time on a bus)

fault syntax: fID@ONSET:MAGNITUDE[:ramp=T][:end=T][:for=T][:intermittent=PERIOD[/DUTY]]
  magnitude in the fault's unit (Table I): m/s^2, rad/s, m/s, rad, N m, N. Faults given here are added to
  the scenario's own faults unless --no-scenario-faults is set.
outputs: every --out gets a ground-truth file <out>.truth.json next to it (unless --truth is given).
"""


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="fdi-sim",
        description="Simulate the ROboMObil: the model plant (the dual-track model of "
        "analysis/models/romo_quasistatic.toml) or, with --truth-vehicle, the truth plant (vehicle-dynamics physics "
        "with suspension, Magic-Formula tyres, road grade, bank and friction, sensor biases and lags) "
        "driven by a geometric controller, inject Table I faults, and write the sensor CAN frames "
        "(dbc/romo.dbc) as candump .log, Vector .asc or .blf.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_drive_arguments(ap)
    ap.add_argument("--out", action="append", default=[], type=Path, metavar="FILE",
                    help="CAN log to write; format from the extension: .log .asc .blf .trc .csv .db, .mf4 (with "
                    "asammdf), the text formats also .gz (repeatable)")
    ap.add_argument("--truth", type=Path, help="ground-truth JSON (default: <first out>.truth.json)")
    ap.add_argument("--npz", type=Path, help="also write true and measured signals at 1 kHz as .npz")
    ap.add_argument("--plot", type=Path, help="PNG with the signals and the fault windows")
    ap.add_argument("--start-time", type=float, default=0.0, help="timestamp of t = 0 in the logs [s]")
    ap.add_argument("--list", action="store_true", help="list the scenarios and exit")
    ap.add_argument("--quiet", action="store_true", help="no progress bars")
    add_vehicle_argument(ap, "the vehicle to simulate: ROMO's simulators for romo and kin, the model plant of its "
                             "model (fdi_host.sim.generic) for another")
    return add_version(ap)


def main(argv: Sequence[str] | None = None) -> int:
    args_list = list(sys.argv[1:] if argv is None else argv)
    if args_list and args_list[0] == "fig6":
        use_file_backend()
        return run("fdi-sim fig6", lambda: fig6.main(args_list[1:]))
    if args_list and args_list[0] == "live":
        return run("fdi-sim live", lambda: live_sim.main(args_list[1:]))
    ap = build_parser()
    args = ap.parse_args(args_list)
    use_file_backend()
    return run("fdi-sim", lambda: simulate_command(ap, args))


def simulate_command(ap: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """``fdi-sim`` after its options are parsed: list, or simulate and write the outputs."""
    if args.list:
        for name in available():
            print(f"{name:12s} {load_scenario(name).description}")
        return 0
    for out in args.out:
        if not is_log(out):
            ap.error(f"--out {out}: unsupported extension; use {formats_text()}")
    vehicle = resolve(args.vehicle)
    if vehicle.simulator == "generic":
        return simulate_vehicle(ap, args, vehicle)
    try:
        drive = simulate_from_args(ap, args)
        result, plant, duration = drive.result, drive.plant, drive.duration
        frames: list[Frame] = []
        if args.out:
            db = CanDatabase()
            with tqdm(desc="encode frames", unit="frame", disable=args.quiet) as bar:
                frames = traffic.build_frames(result, db, t0=args.start_time, progress=bar.update)
            for out in args.out:
                n = write_log(frames, out)
                load = 100 * traffic.bus_load(frames, db.baudrate(), duration)
                print(f"wrote {out} ({n} frames, bus load {load:.1f} %)")
    except KeyboardInterrupt:
        print("interrupted, nothing written after this point", file=sys.stderr)
        return 130
    truth_path = args.truth or (args.out[0].with_suffix(".truth.json") if args.out else None)
    if truth_path is not None:
        write_truth(result, plant, duration, args.start_time, not args.no_noise, truth_path)
        print(f"wrote {truth_path}")
    if args.npz:
        args.npz.parent.mkdir(parents=True, exist_ok=True)
        arrays = {"t": result.t, "faults": result.fault_values}
        arrays |= {f"true_{k}": v for k, v in result.true.items()}
        arrays |= {f"meas_{k}": v for k, v in result.measured.items()}
        np.savez_compressed(args.npz, **arrays)  # type: ignore[arg-type]
        print(f"wrote {args.npz}")
    if args.plot:
        from fdi_host.sim.plots import plot_drive

        print(f"wrote {plot_drive(result, args.plot)}")
    return 0


def simulate_vehicle(ap: argparse.ArgumentParser, args: argparse.Namespace, vehicle: Vehicle) -> int:
    """``fdi-sim --vehicle`` of a vehicle on the generic simulator: a drive of its scenario on its model plant,
    with faults of its model, written as CAN logs through its DBC, as truth and as arrays."""
    if args.out and vehicle.dbc is None:
        ap.error(f"--out: vehicle {vehicle.name} has no DBC, so no bus to log; write --npz instead")
    if args.plot:
        ap.error("--plot: ROMO's drives only")
    drive = simulate_vehicle_from_args(ap, args, vehicle)
    if args.out and vehicle.dbc is not None:
        db = CanDatabase(vehicle.dbc)
        frames = traffic.frames_from_columns(drive.signals, drive.dt, float(drive.t[-1]), db, t0=args.start_time)
        for out in args.out:
            n = write_log(frames, out)
            print(f"wrote {out} ({n} frames, bus load "
                  f"{100 * traffic.bus_load(frames, db.baudrate(), float(drive.t[-1])):.1f} %)")
    truth_path = args.truth or (args.out[0].with_suffix(".truth.json") if args.out else None)
    if truth_path is not None:
        print(f"wrote {write_vehicle_truth(drive, vehicle, args.start_time, truth_path)}")
    if args.npz:
        args.npz.parent.mkdir(parents=True, exist_ok=True)
        arrays = {"t": drive.t} | {f"meas_{k}": v for k, v in drive.signals.items()}
        np.savez_compressed(args.npz, **arrays)  # type: ignore[arg-type]
        print(f"wrote {args.npz}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
