"""``fdi-sim live``: the simulated vehicle's frames sent on a python-can bus in real time.

The drive is simulated first (about 10x faster than real time), then its frames (dbc/romo.dbc, E2E
protected, each message at its DBC cycle time and start delay, faults injected on the schedule) are sent
at their times by `fdi_host.live_sender`. Written on request: the frames as a CAN log (``--out``, what an
offline replay of the same drive uses), the ground truth (``--truth``) and the send times (``--send-log``,
``.npz``: per frame its time on the drive, wall-clock send time, ID and E2E counter, for latency
measurements).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from fdi_host import canlog
from fdi_host.dbc import RomoDatabase
from fdi_host.live_bus import StopFlag, add_bus_arguments, open_bus, try_realtime
from fdi_host.live_sender import send_paced

EPILOG = """\
examples:
  fdi-sim live --scenario fig6 --fault f4@5s:0.5 --interface udp_multicast --channel 239.74.163.2
  fdi-sim live --scenario straight --duration 10 --speed 10 --out sent.blf --truth sent.truth.json
  fdi-sim live --scenario fig6 --interface socketcan --channel vcan0

Start the receivers (fdi-ecu, fdi-monitor) first: frames sent before they listen are lost for them.
fdi-live starts all three in the right order (in a private network namespace when needed).
"""


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="fdi-sim live", description=__doc__.splitlines()[0] if __doc__ else None,
                                 epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenario", default="fig6", help="scenario name in host_tools/scenarios or a TOML path")
    ap.add_argument("--fault", action="append", default=[], metavar="SPEC", help="fault to inject (repeatable)")
    ap.add_argument("--no-scenario-faults", action="store_true", help="ignore the faults of the scenario file")
    ap.add_argument("--duration", type=float, help="override the scenario duration [s]")
    ap.add_argument("--seed", type=int, help="override the noise seed")
    ap.add_argument("--no-noise", action="store_true", help="switch sensor noise off")
    ap.add_argument("--speed", type=float, default=1.0, help="times real time (default 1)")
    add_bus_arguments(ap)
    ap.add_argument("--out", type=Path, help="also write the frames sent as a CAN log (.log/.asc/.blf)")
    ap.add_argument("--truth", type=Path, help="ground-truth JSON (default <out>.truth.json when --out is given)")
    ap.add_argument("--send-log", type=Path, help="send times of every frame (.npz)")
    ap.add_argument("--origin-file", type=Path, help="write the wall-clock time of the drive's t = 0 here before "
                    "sending (fdi-ecu --origin-file aligns its step schedule to it)")
    ap.add_argument("--realtime", action="store_true", help="SCHED_FIFO priority while sending (root)")
    ap.add_argument("--quiet", action="store_true", help="no progress bar")
    return ap


def main(argv: Sequence[str] | None = None) -> int:
    ap = build_parser()
    args = ap.parse_args(argv)
    if args.out is not None and args.out.suffix not in canlog.LOG_SUFFIXES:
        ap.error(f"--out {args.out}: unsupported extension; use {', '.join(canlog.LOG_SUFFIXES)}")
    if not args.speed > 0.0:
        ap.error("--speed must be > 0")
    from fdi_host.sim_cli import simulate_from_args, write_truth

    stop = StopFlag()
    drive = simulate_from_args(ap, args)
    result, plant, duration = drive.result, drive.plant, drive.duration
    db = RomoDatabase()
    frames = canlog.build_frames(result, db)
    truth = args.truth or (args.out.with_suffix(".truth.json") if args.out else None)
    if truth is not None:
        print(f"wrote {write_truth(result, plant, duration, 0.0, not args.no_noise, truth)}")
    if args.out is not None:
        print(f"wrote {args.out} ({canlog.write_log(frames, args.out)} frames)")
    try:
        bus = open_bus(args.interface, args.channel)
    except (OSError, ValueError, ImportError) as exc:
        print(f"fdi-sim live: cannot open {args.interface} bus: {exc}", file=sys.stderr)
        return 2
    try:
        print(f"sending {len(frames)} frames over {frames[-1].timestamp:.1f} s at {args.speed:g}x real time "
              f"on {args.interface}", flush=True)
        if args.realtime:
            print(f"sender: {try_realtime()}", flush=True)

        def announce(wall: float) -> None:
            if args.origin_file is not None:
                tmp = args.origin_file.with_suffix(".tmp")
                tmp.write_text(f"{wall!r}\n", encoding="utf-8")
                tmp.replace(args.origin_file)

        log = send_paced(bus, frames, args.speed, stop, on_start=announce)
    finally:
        bus.shutdown()
    if args.send_log is not None:
        log.save(args.send_log)
    state = "interrupted after" if log.interrupted else "sent"
    print(f"{state} {len(log.wall)} frames; largest delay behind schedule {log.max_behind * 1e3:.2f} ms", flush=True)
    return 130 if log.interrupted else 0
