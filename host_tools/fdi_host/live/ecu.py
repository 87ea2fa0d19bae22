"""``fdi-ecu``: the C diagnoser (through the ctypes bindings `fdi_host.ecu.bindings`) on any python-can bus.

Receives the sensor frames, feeds them to the ECU core (E2E check, decoding, timeouts, fixed-step
diagnosis; see `fdi_host.ecu.session` for the time base and call order), sends an FDI_Diagnosis frame per
diagnosis step, and polls on a timer so that silent messages time out. Stops on SIGINT/SIGTERM (or after
``--duration`` / ``--idle-exit``), prints the ECU's frame counters and writes the ECU log (every step's
masks, candidates, residuals and test ratios) if ``--log`` is given.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import can

from fdi_analysis.cli.common import EXIT_ERROR, add_version
from fdi_analysis.cli.common import run as run_main
from fdi_host.can.frame import Frame
from fdi_host.can.logs import write_log
from fdi_host.ecu.session import DIAG_ID, EcuSession
from fdi_host.live.bus import StopFlag, add_bus_arguments, open_bus, signal_ready, try_realtime

EPILOG = """\
examples:
  fdi-ecu --interface udp_multicast --table kin --log out/ecu.json
  fdi-ecu --interface socketcan --channel vcan0 --table romo
  fdi-ecu --interface udp_multicast --table kin --idle-exit 2     (exit 2 s after the traffic stops)
"""


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="fdi-ecu", description=__doc__.splitlines()[0] if __doc__ else None,
                                 epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_bus_arguments(ap)
    ap.add_argument("--table", choices=("romo", "kin"), default="romo", help="diagnosis table (default romo)")
    ap.add_argument("--log", type=Path, help="ECU log to write at exit (JSON: every diagnosis step)")
    ap.add_argument("--duration", type=float, help="stop after this many seconds")
    ap.add_argument("--idle-exit", type=float, help="stop when no frame arrived for this many seconds "
                    "(after the first frame)")
    ap.add_argument("--rx-log", type=Path, help="CAN log of every frame received, with receive times (.log/.asc/.blf)")
    ap.add_argument("--origin-file", type=Path, help="wall-clock time of the drive's t = 0 (written by fdi-sim "
                    "live --origin-file): steps are aligned to it instead of to the first frame")
    ap.add_argument("--realtime", action="store_true", help="SCHED_FIFO priority (root)")
    ap.add_argument("--ready-file", type=Path, help="file created once the bus is open (for orchestration)")
    ap.add_argument("--quiet", action="store_true", help="print only the final counters")
    return add_version(ap)


def counter_summary(c: Any) -> str:
    """The ECU counters in one line: steps, rejected frames by reason, message timeouts (non-zero only)."""
    rej = {k: v for k, v in c.rejected.items() if v}
    tmo = {k: m.timeouts for k, m in c.messages.items() if m.timeouts}
    return (f"steps {c.steps} (skipped {c.steps_skipped}), rejected {sum(rej.values())} {rej or ''}, "
            f"message timeouts {sum(tmo.values())} {tmo or ''}").replace("  ", " ").strip()


def run(bus: can.BusABC, session: EcuSession, stop: StopFlag, duration: float | None, idle_exit: float | None,
        rx_log: list[tuple[float, int, bytes]] | None = None, origin_file: Path | None = None,
        period: float = 0.005) -> None:
    """The receive / poll / send loop until `stop` (or the duration / idle limit).

    Timer polls run the steps due two steps before now: they only matter when traffic stops (timeouts), and
    they must not overtake a frame that was received but not yet read by this process.
    """
    grace = 2.0 * session.dt
    t_start = time.monotonic()
    last_rx = t_start
    while not stop():
        now_m = time.monotonic()
        if duration is not None and now_m - t_start >= duration:
            break
        if idle_exit is not None and session.origin is not None and now_m - last_rx >= idle_exit:
            break
        msg = bus.recv(timeout=period)
        if msg is not None and not (msg.is_error_frame or msg.is_remote_frame):
            last_rx = time.monotonic()
            fid, data, ts = int(msg.arbitration_id), bytes(msg.data), float(msg.timestamp)
            out_anchor: list[tuple[int, bytes]] = []
            if session.origin is None and fid != DIAG_ID and origin_file is not None and origin_file.exists():
                out_anchor = session.anchor(float(origin_file.read_text(encoding="utf-8")), 0.0, ts)
            out = out_anchor + session.feed(fid, data, ts, 0.0)
            if rx_log is not None and fid != DIAG_ID:
                rx_log.append((ts, fid, data))
        else:
            out = session.tick(time.time(), grace)
        for fid, data in out:
            if session.steps:
                session.steps[-1].tx_wall = time.time()
            bus.send(can.Message(arbitration_id=fid, data=data, is_extended_id=False, dlc=len(data)))


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return run_main("fdi-ecu", lambda: serve(args))


def serve(args: argparse.Namespace) -> int:
    """``fdi-ecu`` after its options are parsed: the ECU on the bus until the end of the drive or Ctrl-C."""
    stop = StopFlag()
    try:
        session = EcuSession(args.table)
    except (ImportError, OSError, RuntimeError, ValueError) as exc:
        print(f"fdi-ecu: cannot load the ECU bindings ({exc}); build them with `pip install -e .`", file=sys.stderr)
        return EXIT_ERROR
    try:
        bus = open_bus(args.interface, args.channel)
    except (OSError, ValueError, ImportError, can.CanError) as exc:
        print(f"fdi-ecu: cannot open {args.interface} bus: {exc}", file=sys.stderr)
        return EXIT_ERROR
    signal_ready(args.ready_file)
    if not args.quiet:
        print(f"fdi-ecu: table {args.table} on {args.interface}; Ctrl-C to stop", flush=True)
    try:
        rx_log: list[tuple[float, int, bytes]] | None = [] if args.rx_log is not None else None
        if args.realtime:
            print(f"fdi-ecu: {try_realtime()}", flush=True)
        run(bus, session, stop, args.duration, args.idle_exit, rx_log, args.origin_file)
    finally:
        bus.shutdown()
    print(f"fdi-ecu: {session.frames_in} frames in, {len(session.steps)} diagnosis frames out; "
          f"{counter_summary(session.ecu.counters())}", flush=True)
    if args.log is not None:
        print(f"wrote {session.write(args.log)}", flush=True)
    if args.rx_log is not None and rx_log is not None:
        # ECU must be back on the bus quickly

        write_log([Frame(*f) for f in rx_log], args.rx_log)
        print(f"wrote {args.rx_log} ({len(rx_log)} frames)", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
