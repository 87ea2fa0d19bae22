"""``fdi-sim live``: the simulated vehicle's frames sent on a python-can bus in real time.

The drive is simulated first (about 10x faster than real time), then its frames (dbc/romo.dbc, E2E
protected, each message at its DBC cycle time and start delay, faults injected on the schedule) are sent
at their times by `fdi_host.live.sender`. Written on request: the frames as a CAN log (``--out``, what an
offline replay of the same drive uses), the ground truth (``--truth``) and the send times (``--send-log``,
``.npz``: per frame its time on the drive, wall-clock send time, ID and E2E counter, for latency
measurements).

Other ECUs' traffic (``--bus-load HZ``): frames of IDs the diagnosis does not subscribe to
(`fdi_host.can.background`: a deterministic mix of cycle times, payload lengths 0..8, standard and extended
IDs), sent by the same process in time order with the drive's, up to HZ frames/s in total (a full 500 kbit/s
bus carries about 4,000); ``--out`` and ``--send-log`` then hold them too.

Restart (``--resume``, used by ``fdi-live --restart-sim-at``): a simulator started while the drive is under
way reads the drive's t = 0 from ``--origin-file`` (instead of writing it), simulates the same drive (same
scenario, faults and seed: the same frames), and sends only the frames not yet due, at their times on the
drive's clock, with every message's alive counter starting again at ``--counter-start``. With
``--frames-from drive.blf`` (the first simulator's ``--out``) it sends the recorded drive instead of
simulating it again: the same frames, back on the bus in about a second instead of several.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path

import can

from fdi_analysis.cli.common import EXIT_ERROR
from fdi_host.can import background
from fdi_host.can.dbc import CanDatabase
from fdi_host.can.frame import Frame
from fdi_host.can.logs import formats_text, is_log, read_log, write_log
from fdi_host.live.bus import BusOptions, StopFlag, add_bus_arguments, open_cli_bus, try_realtime
from fdi_host.live.sender import SendLog, resume_frames, send_paced
from fdi_host.sim.options import add_drive_arguments
from fdi_host.vehicle import add_vehicle_argument, resolve

EPILOG = """\
examples:
  fdi-sim live --scenario fig6 --fault f4@5s:0.5 --interface udp_multicast --channel 239.74.163.2
  fdi-sim live --scenario straight --duration 10 --speed 10 --out sent.blf --truth sent.truth.json
  fdi-sim live --scenario fig6 --interface socketcan --channel vcan0
  fdi-sim live --scenario fig6 --can-config bus.ini            (the bus in a python-can configuration file)
  fdi-sim live --scenario slalom --bus-load 4000     (other ECUs' frames up to 4,000 frames/s in total)
  fdi-sim live --scenario fig6 --resume --origin-file out/live/origin.txt --counter-start 9
      (a restarted simulator: joins the drive whose t = 0 is in origin.txt, counters restart at 9)

Start the receivers (fdi-ecu, fdi-monitor) first: frames sent before they listen are lost for them.
fdi-live starts all three in the right order (in a private network namespace when needed).
"""


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="fdi-sim live", description=__doc__.splitlines()[0] if __doc__ else None,
                                 epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_drive_arguments(ap)
    ap.add_argument("--speed", type=float, default=1.0, help="times real time (default 1)")
    add_bus_arguments(ap)
    ap.add_argument("--out", type=Path, help="also write the frames sent as a CAN log (.log, .asc, .blf, .trc, .csv, "
                    ".db, ...)")
    ap.add_argument("--truth", type=Path, help="ground-truth JSON (default <out>.truth.json when --out is given)")
    ap.add_argument("--send-log", type=Path, help="send times of every frame (.npz)")
    ap.add_argument("--origin-file", type=Path, help="write the wall-clock time of the drive's t = 0 here before "
                    "sending (fdi-ecu --origin-file aligns its step schedule to it)")
    ap.add_argument("--resume", action="store_true", help="join a drive under way (a restarted simulator): read "
                    "its t = 0 from --origin-file and send only the frames not yet due")
    ap.add_argument("--frames-from", type=Path, metavar="LOG",
                    help="with --resume: send the drive recorded in LOG (the --out of the first simulator: the "
                    "vehicle drove on, only the sender restarted) instead of simulating it again (seconds)")
    ap.add_argument("--counter-start", type=int, default=0, metavar="N",
                    help="with --resume: alive counter of every message's first frame (0..14, default 0)")
    ap.add_argument("--bus-load", type=float, default=0.0, metavar="HZ",
                    help="add other ECUs' frames (IDs not in the DBC) up to HZ frames/s in total (default 0: none)")
    ap.add_argument("--bus-load-seed", type=int, default=background.DEFAULT_SEED,
                    help="seed of the other ECUs' traffic")
    ap.add_argument("--realtime", action="store_true", help="SCHED_FIFO priority while sending (root)")
    ap.add_argument("--quiet", action="store_true", help="no progress bar")
    add_vehicle_argument(ap, "the vehicle whose drive is sent (romo, kin: ROMO's simulators; another: the model "
                             "plant of its model over its DBC)")
    return ap


def _send_resumed(bus: can.BusABC, frames: Sequence[Frame], args: argparse.Namespace,
                  stop: StopFlag, lead: float = 0.3) -> SendLog:
    """Join the running drive: the frames due from `lead` after now on the drive's clock (time to restamp the
    counters and start sending), counters restarted."""
    try:
        origin = float(args.origin_file.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise SystemExit(f"fdi-sim live: cannot read the drive's t = 0 from {args.origin_file}: {exc}") from exc
    t0 = frames[0].timestamp if frames else 0.0
    t_from = t0 + (time.time() + lead - origin) * args.speed
    todo = resume_frames(frames, t_from, args.counter_start)
    if not todo:
        print(f"resume: the drive ended before t = {t_from - t0:.2f} s, nothing to send", flush=True)
        return SendLog()
    print(f"resume at t = {todo[0].timestamp - t0:.3f} s of the drive ({len(todo)} frames left), alive counters "
          f"from {args.counter_start}", flush=True)
    log = send_paced(bus, todo, args.speed, stop, first_wall=origin + (todo[0].timestamp - t0) / args.speed)
    log.sim_t = [x + todo[0].timestamp - t0 for x in log.sim_t]  # on the drive's clock, as a full run's log
    return log


def _drive_frames(ap: argparse.ArgumentParser, args: argparse.Namespace) -> Sequence[Frame]:
    """The drive's frames: simulated (and written to --out / --truth), or read from --frames-from."""
    if args.frames_from is not None:
        try:
            return read_log(args.frames_from)
        except (OSError, ValueError) as exc:
            raise SystemExit(f"fdi-sim live: cannot read --frames-from {args.frames_from}: {exc}") from exc
    from fdi_host.can import traffic  # the simulator: seconds of imports, not needed with --frames-from
    from fdi_host.sim.drive import simulate_from_args, simulate_vehicle_from_args, write_truth, write_vehicle_truth

    vehicle = resolve(args.vehicle)
    truth = args.truth or (args.out.with_suffix(".truth.json") if args.out else None)
    if vehicle.simulator == "generic":
        if vehicle.dbc is None:
            ap.error(f"vehicle {vehicle.name} has no DBC: nothing to send on a bus")
        vdrive = simulate_vehicle_from_args(ap, args, vehicle)
        duration = float(vdrive.t[-1])
        frames = traffic.frames_from_columns(vdrive.signals, vdrive.dt, duration, CanDatabase(vehicle.dbc))
        if truth is not None:
            print(f"wrote {write_vehicle_truth(vdrive, vehicle, 0.0, truth)}")
    else:
        drive = simulate_from_args(ap, args)
        duration = drive.duration
        frames = traffic.build_frames(drive.result, CanDatabase())
        if truth is not None:
            print(f"wrote {write_truth(drive.result, drive.plant, duration, 0.0, not args.no_noise, truth)}")
    if args.bus_load > 0.0:
        bg = background.for_drive(frames, args.bus_load, duration, args.bus_load_seed)
        print(f"other ECUs' traffic: {len(bg)} frames ({len(bg) / duration:.0f}/s, "
              f"{len({f.frame_id for f in bg})} IDs), {(len(frames) + len(bg)) / duration:.0f} frames/s in total")
        frames = background.merge_frames(frames, bg)
    if args.out is not None:
        print(f"wrote {args.out} ({write_log(frames, args.out)} frames)")
    return frames


def main(argv: Sequence[str] | None = None) -> int:
    ap = build_parser()
    args = ap.parse_args(argv)
    if args.out is not None and not is_log(args.out):
        ap.error(f"--out {args.out}: unsupported extension; use {formats_text()}")
    if not args.speed > 0.0:
        ap.error("--speed must be > 0")
    if args.resume and args.origin_file is None:
        ap.error("--resume needs --origin-file (the running drive's t = 0)")
    if args.frames_from is not None and not args.resume:
        ap.error("--frames-from is for --resume (a restarted simulator joining a drive under way)")
    if args.frames_from is not None and (args.out is not None or args.truth is not None):
        ap.error("--frames-from sends a recorded drive: --out and --truth belong to the simulating run")
    if args.frames_from is not None and args.bus_load > 0.0:
        ap.error("--frames-from sends a recorded drive as it is (with its other ECUs' frames): no --bus-load")
    if args.bus_load < 0.0:
        ap.error("--bus-load must be >= 0 frames/s")
    if not 0 <= args.counter_start <= 14:
        ap.error("--counter-start must be in 0..14 (E2E profile 11 alive counter)")
    stop = StopFlag()
    frames = _drive_frames(ap, args)
    if not frames:
        print("fdi-sim live: the drive has no frames", file=sys.stderr)
        return EXIT_ERROR
    opened = open_cli_bus("fdi-sim live", BusOptions.from_args(args))
    if opened is None:
        return EXIT_ERROR
    bus, bus_config = opened
    try:
        print(f"sending {len(frames)} frames over {frames[-1].timestamp:.1f} s at {args.speed:g}x real time "
              f"on {bus_config.describe()}", flush=True)
        if args.realtime:
            print(f"sender: {try_realtime()}", flush=True)

        def announce(wall: float) -> None:
            if args.origin_file is not None:
                tmp = args.origin_file.with_suffix(".tmp")
                tmp.write_text(f"{wall!r}\n", encoding="utf-8")
                tmp.replace(args.origin_file)

        if args.resume:
            log = _send_resumed(bus, frames, args, stop)
        else:
            log = send_paced(bus, frames, args.speed, stop, on_start=announce)
    finally:
        bus.shutdown()
    if args.send_log is not None:
        log.save(args.send_log)
    state = "interrupted after" if log.interrupted else "sent"
    print(f"{state} {len(log.wall)} frames; largest delay behind schedule {log.max_behind * 1e3:.2f} ms", flush=True)
    return 130 if log.interrupted else 0


if __name__ == "__main__":
    raise SystemExit(main())
