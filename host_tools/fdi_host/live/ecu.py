"""``fdi-ecu``: the C diagnoser (through the ctypes bindings `fdi_host.ecu.bindings`) on any python-can bus.

Receives the sensor frames, feeds them to the ECU core (E2E check, decoding, timeouts, fixed-step
diagnosis; see `fdi_host.ecu.session` for the time base and call order), sends an FDI_Diagnosis frame per
diagnosis step, and polls on a timer so that silent messages time out. Stops on SIGINT/SIGTERM (or after
``--duration`` / ``--idle-exit``), prints the ECU's frame counters and writes the ECU log (every step's
masks, candidates, residuals and test ratios) if ``--log`` is given.

Every frame goes to the C core, whatever its ID: other ECUs' frames (a real bus carries up to ~4,000
frames/s) are counted there as unknown IDs and ignored, as in the SocketCAN program and in an offline replay
(the same calls); a 29-bit ID carries SocketCAN's EFF flag, so it never matches a subscribed 11-bit ID.
The per-frame path is kept short (`fdi_host.live.bus.frame_reader`: python-can's ``bus.recv``, then every
frame already queued with ``bus.recv(timeout=0)``, per wake-up) and nothing but the C calls runs between the
frame that completes
a step and its diagnosis frame: the frame is handed to the bus as soon as the C core returns it, before the
step is recorded (`SendFirst`). The garbage collector runs only right after a diagnosis frame was sent (the
quiet part of a step), never between a frame and its diagnosis: its full collections over the recorded
steps took milliseconds. A larger socket receive buffer (``--rcvbuf``) rides out pauses of the process
without losing frames; ``--realtime`` (SCHED_FIFO, root) keeps it scheduled, ``--cpu-latency 0`` (PM QoS) keeps
idle CPUs awake for it (`fdi_host.live.bus.CpuLatencyRequest`), ``--cpu`` pins it.
"""

from __future__ import annotations

import argparse
import gc
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import can

from fdi_analysis.cli.common import EXIT_ERROR, add_version, fail, one_line
from fdi_analysis.cli.common import run as run_main
from fdi_analysis.errors import FdiError
from fdi_host.can.frame import Frame
from fdi_host.can.logs import write_log
from fdi_host.ecu.session import EcuSession
from fdi_host.live.bus import (
    CAN_EFF_FLAG,
    CAN_EFF_MASK,
    CAN_ERR_FLAG,
    CAN_RTR_FLAG,
    BusOptions,
    BusReader,
    CpuLatencyRequest,
    StopFlag,
    add_bus_arguments,
    frame_reader,
    open_cli_bus,
    set_affinity,
    set_receive_buffer,
    signal_ready,
    try_realtime,
)
from fdi_host.vehicle import add_vehicle_argument

DEFAULT_RCVBUF = 4 * 1024 * 1024  # bytes: ~1 s of a full bus in python-can's udp_multicast datagrams

EPILOG = """\
examples:
  fdi-ecu --interface udp_multicast --vehicle kin --log out/ecu.json
  fdi-ecu --interface socketcan --channel vcan0 --vehicle romo
  fdi-ecu --interface pcan --channel PCAN_USBBUS1 --bitrate 500000 --vehicle romo     (a PEAK adapter)
  fdi-ecu --can-config bus.ini --can-context vehicle --vehicle romo   (python-can's configuration file)
  fdi-ecu --interface udp_multicast --vehicle kin --idle-exit 2     (exit 2 s after the traffic stops)
"""


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="fdi-ecu", description=__doc__.splitlines()[0] if __doc__ else None,
                                 epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_bus_arguments(ap)
    add_vehicle_argument(ap)
    ap.add_argument("--log", type=Path, help="ECU log to write at exit (JSON: every diagnosis step)")
    ap.add_argument("--duration", type=float, help="stop after this many seconds")
    ap.add_argument("--idle-exit", type=float, help="stop when no frame arrived for this many seconds "
                    "(after the first frame)")
    ap.add_argument("--rx-log", type=Path, help="CAN log of every frame received, with receive times (.log, .asc, "
                    ".blf, .trc, .csv, .db, ...)")
    ap.add_argument("--origin-file", type=Path, help="wall-clock time of the drive's t = 0 (written by fdi-sim "
                    "live --origin-file): steps are aligned to it instead of to the first frame")
    ap.add_argument("--realtime", action="store_true", help="SCHED_FIFO priority (root)")
    ap.add_argument("--cpu-latency", type=int, metavar="US",
                    help="hold a PM QoS request for this CPU wake-up latency while running (root; 0: idle CPUs "
                    "poll, no wake-up delay from sleep states or, in a VM, from a halted vCPU)")
    ap.add_argument("--cpu", type=int, action="append", metavar="N",
                    help="run on CPU N only (repeatable; default: any)")
    ap.add_argument("--rcvbuf", type=int, default=DEFAULT_RCVBUF, metavar="BYTES",
                    help=f"socket receive buffer (default {DEFAULT_RCVBUF}; 0: the kernel's default)")
    ap.add_argument("--rx", choices=("auto", "recv"), default="auto",
                    help="auto: bus.recv, then every frame already queued (bus.recv with timeout 0) per wake-up; "
                    "recv: one bus.recv per loop")
    ap.add_argument("--ready-file", type=Path, help="file created once the bus is open (for orchestration)")
    ap.add_argument("--quiet", action="store_true", help="print only the final counters")
    return add_version(ap)


def counter_summary(c: Any) -> str:
    """The ECU counters in one line: steps, rejected frames by reason, message timeouts (non-zero only)."""
    rej = {k: v for k, v in c.rejected.items() if v}
    tmo = {k: m.timeouts for k, m in c.messages.items() if m.timeouts}
    return (f"steps {c.steps} (skipped {c.steps_skipped}), rejected {sum(rej.values())} {rej or ''}, "
            f"message timeouts {sum(tmo.values())} {tmo or ''}").replace("  ", " ").strip()


class SendFirst:
    """The bindings' `Ecu` whose ``poll`` hands the diagnosis frame to the bus as soon as the C core returns it,
    before `EcuSession` reads the step's result and records it (~20 us the frame no longer waits for);
    everything else is the wrapped ECU's. `last_tx_wall`: wall-clock time just before the last send."""

    def __init__(self, ecu: Any, bus: can.BusABC) -> None:
        self._ecu = ecu
        self._bus = bus
        self.last_tx_wall = 0.0
        self.sent = 0

    def poll(self, t: float) -> list[tuple[int, bytes]]:
        frames: list[tuple[int, bytes]] = self._ecu.poll(t)
        for fid, data in frames:
            self.last_tx_wall = time.time()
            self._bus.send(can.Message(arbitration_id=fid, data=data, is_extended_id=fid > 0x7FF, dlc=len(data)))
            self.sent += 1
        return frames

    @property
    def wrapped(self) -> Any:
        return self._ecu

    def __getattr__(self, name: str) -> Any:
        return getattr(self._ecu, name)


def _log_frame(can_id: int, data: bytes, ts: float, rx_log: list[tuple[float, int, bytes]], own: int) -> None:
    """A received data frame for the --rx-log file (IDs above 0x7FF are extended there: `Frame`); not the ECU's
    own diagnosis frame `own`."""
    if can_id & (CAN_RTR_FLAG | CAN_ERR_FLAG) or can_id == own:
        return
    rx_log.append((ts, can_id & CAN_EFF_MASK if can_id & CAN_EFF_FLAG else can_id, data))


def run(bus: can.BusABC, session: EcuSession, stop: StopFlag, duration: float | None, idle_exit: float | None,
        rx_log: list[tuple[float, int, bytes]] | None = None, origin_file: Path | None = None,
        period: float = 0.005, reader: BusReader | None = None) -> None:
    """The receive / poll / send loop until `stop` (or the duration / idle limit).

    Timer polls run the steps due two steps before now: they only matter when traffic stops (timeouts), and
    they must not overtake a frame that was received but not yet read by this process.
    """
    grace = 2.0 * session.dt
    rd = reader if reader is not None else frame_reader(bus)
    tx = SendFirst(session.ecu, bus)
    session.ecu = tx
    t_start = time.monotonic()
    last_rx = t_start
    gc.collect()
    gc.freeze()  # what exists now (modules, tables) is never scanned again
    gc_was_on = gc.isenabled()
    gc.disable()
    try:
        while not stop():
            now_m = time.monotonic()
            if duration is not None and now_m - t_start >= duration:
                break
            if idle_exit is not None and session.origin is not None and now_m - last_rx >= idle_exit:
                break
            sent = tx.sent
            frames = rd.read(period)
            if frames:
                last_rx = time.monotonic()
                for fid, data, ts in frames:
                    if session.origin is None and fid != session.diag_id and origin_file is not None \
                            and origin_file.exists() \
                            and session.anchor(float(origin_file.read_text(encoding="utf-8")), 0.0, ts):
                        session.steps[-1].tx_wall = tx.last_tx_wall
                    if session.feed(fid, data, ts, 0.0):
                        session.steps[-1].tx_wall = tx.last_tx_wall
                    if rx_log is not None:
                        _log_frame(fid, data, ts, rx_log, session.diag_id)
            elif session.tick(time.time(), grace):
                session.steps[-1].tx_wall = tx.last_tx_wall
            if tx.sent != sent:  # a diagnosis frame went out: the quiet part of the step
                gc.collect(1)
    finally:
        gc.unfreeze()
        if gc_was_on:
            gc.enable()
        session.ecu = tx.wrapped


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return run_main("fdi-ecu", lambda: serve(args))


def serve(args: argparse.Namespace) -> int:
    """``fdi-ecu`` after its options are parsed: the ECU on the bus until the end of the drive or Ctrl-C."""
    stop = StopFlag()
    try:
        session = EcuSession(args.vehicle)
    except (ImportError, OSError, FdiError) as exc:  # not built, or the library lacks the table (EcuError)
        return fail("fdi-ecu", f"cannot load the ECU bindings ({one_line(exc)}); build them with `pip install -e .`")
    opened = open_cli_bus("fdi-ecu", BusOptions.from_args(args))
    if opened is None:
        return EXIT_ERROR
    bus, bus_config = opened
    reader: BusReader | None = None
    qos: CpuLatencyRequest | None = None
    try:
        rcvbuf = set_receive_buffer(bus, args.rcvbuf) if args.rcvbuf > 0 else 0
        reader = frame_reader(bus, drain=args.rx == "auto")
        setup = [f"receive bus.recv{', every queued frame per wake-up' if args.rx == 'auto' else ''}"]
        if rcvbuf:
            setup.append(f"socket buffer {rcvbuf // 1024} KiB")
        if args.cpu:
            setup.append(set_affinity(args.cpu))
        if args.realtime:
            setup.append(try_realtime())
        if args.cpu_latency is not None:
            qos = CpuLatencyRequest(args.cpu_latency)
            setup.append(qos.note)
        signal_ready(args.ready_file)
        if not args.quiet:
            print(f"fdi-ecu: table {args.vehicle} on {bus_config.describe()}; Ctrl-C to stop", flush=True)
        print(f"fdi-ecu: {', '.join(setup)}", flush=True)
        rx_log: list[tuple[float, int, bytes]] | None = [] if args.rx_log is not None else None
        run(bus, session, stop, args.duration, args.idle_exit, rx_log, args.origin_file, reader=reader)
    finally:
        if reader is not None:
            reader.close()
        if qos is not None:
            qos.close()
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
