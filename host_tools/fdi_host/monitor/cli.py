"""``fdi-monitor``: listens to the bus, shows the diagnosis live and scores it against the ground truth.

Every frame on the bus is accounted per message ID (`fdi_host.monitor.frames`: received, lost, late, E2E
errors); FDI_Diagnosis frames (ID 512, decoded with cantools from dbc/romo.dbc) become `DiagRecord`s on the
drive's clock: t = receive time minus the receive time of the first sensor frame (the simulator's first
frames are at t = 0), so the monitor must be listening before the drive starts (``fdi-live`` does that).
At the end (SIGINT/SIGTERM, ``--duration`` or ``--idle-exit``) the run is scored (`fdi_host.monitor.score`) and
report.md, report.json, diagnosis.png and, with ``--ecu-log``, residuals.png are written.

Gaps (`fdi_host.monitor.gaps`): a silence of the FDI_Diagnosis stream (the ECU is down) or of the sensor
frames (the simulator is down) longer than ``--gap-threshold`` is printed when it ends (and shown in the live
table while it lasts), listed with start, end and duration in report.md/json, counted per stream, and
passed to the scoring (a gap is never a detection; a fault missed while a gap overlapped its window is
"not evaluable").
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fdi_analysis.cli.common import EXIT_ERROR, add_version, fail, one_line, run, use_file_backend
from fdi_analysis.errors import FdiError
from fdi_host.can.dbc import CanDatabase
from fdi_host.ecu.records import DiagRecord, TableClasses
from fdi_host.ecu.session import ORIGIN_LEAD, load_steps
from fdi_host.errors import FdiHostError
from fdi_host.live.bus import BusOptions, StopFlag, add_bus_arguments, open_cli_bus, signal_ready
from fdi_host.monitor.frames import FrameStats
from fdi_host.monitor.gaps import Gap, GapTracker, gap_summary
from fdi_host.monitor.report import frame_table, plot_diagnosis, plot_residuals, score_table, write_reports
from fdi_host.monitor.score import Score, score_run, windows_from_truth
from fdi_host.sim.faults import FAULT_IDS
from fdi_host.vehicle import add_vehicle_argument, resolve

EPILOG = """\
examples:
  fdi-monitor --interface udp_multicast --vehicle kin --truth out/live/truth.json --out-dir out/live
  fdi-monitor --interface udp_multicast --vehicle kin --truth t.json --ecu-log out/ecu.json --idle-exit 2
  fdi-monitor --interface kvaser --channel 0 --bitrate 500000 --vehicle romo     (a Kvaser adapter)
  fdi-monitor --classes classes.json ...     (signatures given as JSON instead of from the ECU bindings:
                                              {"signature": [13, 14, 15, 7, 11], "test_names": ["r1", ...]})
"""


@dataclass
class Monitor:
    """Bus-independent core: feed frames with `on_frame`, read `records` and `stats`."""

    db: CanDatabase
    classes: TableClasses
    step: float = 0.01  # diagnosis step [s]: the diagnosis frame's cycle
    stats: FrameStats = field(init=False)
    records: list[DiagRecord] = field(default_factory=list)
    t0: float | None = None  # receive time of the first sensor frame
    last_rx: float = 0.0
    gap_threshold: float = 0.25  # s: a longer silence of a stream is a gap
    gaps: GapTracker = field(init=False)
    new_gaps: list[Gap] = field(default_factory=list)  # gaps ended since the caller last emptied this list

    def __post_init__(self) -> None:
        self.stats = FrameStats(self.db, {self.db.diag_id: self.step}, self.gap_threshold)
        self.gaps = GapTracker(self.gap_threshold)

    def on_frame(self, frame_id: int, data: bytes, t_rx: float) -> DiagRecord | None:
        self.last_rx = t_rx
        ok = self.stats.add(frame_id, data, t_rx)
        if frame_id != self.db.diag_id:
            if self.t0 is None and ok:
                self.t0 = t_rx
            if self.t0 is not None and frame_id in self.stats.messages:  # a known sensor message
                self._stream("sensors", t_rx - self.t0)
            return None
        if self.t0 is not None:
            self._stream("diagnosis", t_rx - self.t0)
        if not ok or self.t0 is None:
            return None
        sig = self.db.decode(frame_id, data, check_e2e=False).signals
        rec = DiagRecord(t_rx - self.t0, int(sig["FDI_AlarmMask"]), int(sig["FDI_CandidateFaults"]),
                         int(sig["FDI_IsolationClass"]), int(sig["FDI_Status"]))
        self.records.append(rec)
        return rec

    def _stream(self, stream: str, t: float) -> None:
        gap = self.gaps.frame(stream, t)
        if gap is not None:
            self.new_gaps.append(gap)

    def silence_note(self, now_wall: float) -> str:
        """Streams silent right now (wall time `now_wall`), for the live table; empty if none."""
        if self.t0 is None:
            return ""
        silent = self.gaps.silent(now_wall - self.t0)
        return "  ".join(f"{s.upper()} SILENT for {d:.1f} s" for s, d in sorted(silent.items()))

    def status_line(self, now_wall: float | None = None) -> str:
        if not self.records:
            return f"waiting for diagnosis frames ({sum(m.received for m in self.stats.messages.values())} frames)"
        r = self.records[-1]
        alarms = ",".join(self.classes.test_name(i) for i in range(32) if r.alarm_mask >> i & 1) or "-"
        lost = sum(m.lost for m in self.stats.messages.values())
        n = sum(m.received for m in self.stats.messages.values())
        note = self.silence_note(now_wall) if now_wall is not None else ""
        n_gaps = len(self.gaps.gaps)
        return (f"t={r.t:7.2f} s  frames {n:7d} lost {lost:3d}  diag {len(self.records):6d}  "
                f"alarm [{alarms}]  candidates [{self.classes.fault_names(r.candidates)}]"
                + (f"  gaps {n_gaps}" if n_gaps else "") + (f"  {note}" if note else ""))

    def table(self, now_wall: float | None = None) -> list[str]:
        """The live table: one row per test (alarm or quiet, alarmed steps so far), the candidates, the gaps."""
        r = self.records[-1] if self.records else None
        n = max(len(self.classes.test_names), 1)
        rows = [self.status_line(now_wall), f"{'test':8s} {'now':6s} {'alarmed steps':>13s}"]
        for i in range(n):
            on = r is not None and bool(r.alarm_mask >> i & 1)
            count = sum(1 for x in self.records if x.alarm_mask >> i & 1)
            rows.append(f"{self.classes.test_name(i):8s} {'ALARM' if on else 'ok':6s} {count:13d}")
        cls = "-" if r is None else ("isolated" if 0 < r.iso_class < 255 else "not isolated" if r.iso_class == 255
                                     else "nothing detected")
        rows.append(f"candidates: {self.classes.fault_names(r.candidates) if r else '-'}  ({cls})")
        note = self.silence_note(now_wall) if now_wall is not None else ""
        if self.gaps.gaps or note:  # gaps so far (the last three in full), and a silence going on now
            rows.append(gap_summary(self.gaps.gaps) + (f"; now: {note}" if note else ""))
            rows += [f"  {g.describe()}" for g in self.gaps.gaps[-3:]]
        return rows

    def finish_gaps(self, drive_end: float | None) -> list[Gap]:
        """Close the gap list at the end of the run (silences that never ended; see `GapTracker.finish`)."""
        return self.gaps.finish(drive_end)

    def score(self, truth: dict[str, Any], grace: float) -> Score:
        d = truth.get("duration")
        gaps = self.finish_gaps(float(d) if isinstance(d, int | float) else None)
        return score_run(self.records, windows_from_truth(truth), self.classes, grace, gaps)


class ClassesFileError(FdiHostError, ValueError):
    """A ``--classes`` file that is not fault signatures as JSON; the message names the file."""


CLASSES_FORMAT = '{"signature": [13, 14, ...], "test_names": ["r1", ...], "faults": ["f1", ...], "dt": 0.01}'


def read_classes(path: Path) -> tuple[TableClasses, float]:
    """Structural classes and step from a JSON file of fault signatures (``signature``: per fault the bitmask of
    the tests sensitive to it; optional ``test_names``, ``faults`` (their names, any identifiers; default the
    vehicle simulator's f1, f2, ...) and ``dt`` [s], default 0.01). `ClassesFileError` naming the file when it is
    not one; OSError when it cannot be read."""
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ClassesFileError(f"{path}: not a JSON file of fault signatures ({one_line(exc)})") from exc
    if not isinstance(doc, dict) or not isinstance(doc.get("signature"), list):
        raise ClassesFileError(f"{path}: expected an object with a 'signature' list, e.g. {CLASSES_FORMAT}")
    signature, names, dt = doc["signature"], doc.get("test_names", []), doc.get("dt", 0.01)
    faults = doc.get("faults", list(FAULT_IDS))
    if not all(isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in signature):
        raise ClassesFileError(f"{path}: 'signature' must list one test bitmask (an integer >= 0) per fault")
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise ClassesFileError(f"{path}: 'test_names' must be a list of names")
    if not (isinstance(faults, list) and all(isinstance(f, str) and f for f in faults)
            and len(set(faults)) == len(faults) >= len(signature)):
        raise ClassesFileError(f"{path}: 'faults' must name every fault of 'signature' once")
    if isinstance(dt, bool) or not isinstance(dt, int | float) or not dt > 0:
        raise ClassesFileError(f"{path}: 'dt' must be the diagnosis step in seconds (> 0), not {dt!r}")
    return TableClasses.from_signatures(signature, names, faults), float(dt)


def classes_for(table: str, classes_file: Path | None) -> tuple[TableClasses, float]:
    """Structural classes and step of the table: from a JSON file (`read_classes`), or from the ECU bindings'
    table."""
    if classes_file is not None:
        return read_classes(classes_file)
    from fdi_host.ecu.bindings import table_info
    from fdi_host.ecu.session import table_classes

    info = table_info(table)
    return table_classes(info), float(info.dt)


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="fdi-monitor", description=__doc__.splitlines()[0] if __doc__ else None,
                                 epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_bus_arguments(ap)
    add_vehicle_argument(ap)
    ap.add_argument("--classes", type=Path, help="fault signatures as JSON (instead of the ECU bindings)")
    ap.add_argument("--truth", type=Path, help="ground truth (truth.json of fdi-sim) to score against")
    ap.add_argument("--ecu-log", type=Path, help="ECU log (fdi-ecu --log) for the residual plot, read at the end")
    ap.add_argument("--out-dir", type=Path, default=Path("out/monitor"), help="report directory")
    ap.add_argument("--grace", type=float, default=3.0,
                    help="alarms up to this long after a fault's end count for it [s] (default 3: removing a fault "
                    "is a transient too, and an alarm clears only after the ECU's clear count)")
    ap.add_argument("--duration", type=float, help="stop after this many seconds")
    ap.add_argument("--idle-exit", type=float, help="stop when no frame arrived for this long (after the first)")
    ap.add_argument("--ecu-log-wait", type=float, default=5.0, help="wait this long for --ecu-log to appear [s]")
    ap.add_argument("--ready-file", type=Path, help="file created once the bus is open (for orchestration)")
    ap.add_argument("--origin-file", type=Path, help="wall-clock time of the drive's t = 0 (fdi-sim live "
                    "--origin-file); default: the first sensor frame's receive time")
    ap.add_argument("--gap-threshold", type=float, default=0.25,
                    help="a silence of the diagnosis or sensor frames longer than this is a gap [s] (default 0.25)")
    ap.add_argument("--refresh", type=float, default=1.0, help="live table refresh period [s]")
    ap.add_argument("--quiet", action="store_true", help="no live table")
    return add_version(ap)


def finish(mon: Monitor, args: argparse.Namespace) -> int:
    """Score, print and write the reports."""
    print(frame_table(mon.stats))
    if args.truth is None:
        gaps = mon.finish_gaps(None)
        print("\n".join([gap_summary(gaps), *(f"  {g.describe()}" for g in gaps)]))
        print("no --truth given: nothing to score")
        return 0
    try:
        truth = json.loads(args.truth.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError, UnicodeDecodeError) as exc:
        return fail("fdi-monitor", f"cannot read the truth file {args.truth}: {one_line(exc)}")
    score = mon.score(truth, args.grace)
    print(score_table(score), flush=True)
    windows = windows_from_truth(truth)
    paths = write_reports(args.out_dir, score, mon.stats, {"table": args.vehicle, "truth": str(args.truth),
                                                           "diagnosis_frames": len(mon.records)})
    p = plot_diagnosis(args.out_dir / "diagnosis.png", mon.records, windows, mon.classes, score.gaps)
    paths += [p] if p else []
    if args.ecu_log is not None:
        deadline = time.monotonic() + args.ecu_log_wait
        while not args.ecu_log.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        if args.ecu_log.exists():
            p = plot_residuals(args.out_dir / "residuals.png", load_steps(args.ecu_log), windows, mon.classes,
                               ORIGIN_LEAD)
            paths += [p] if p else []
        else:
            print(f"fdi-monitor: {args.ecu_log} did not appear, no residual plot", file=sys.stderr)
    print("wrote " + ", ".join(str(p) for p in paths), flush=True)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    ap = build_parser()
    args = ap.parse_args(argv)
    if args.truth is not None and not args.truth.parent.is_dir():
        ap.error(f"--truth {args.truth}: no such directory (the file itself may appear while the monitor runs)")
    if not args.gap_threshold > 0.0:
        ap.error("--gap-threshold must be > 0")
    use_file_backend()
    return run("fdi-monitor", lambda: monitor(args))


def monitor(args: argparse.Namespace) -> int:
    """``fdi-monitor`` after its options are parsed: listen, show, then score and report."""
    stop = StopFlag()
    try:
        classes, step = classes_for(args.vehicle, args.classes)
    except (ImportError, OSError, FdiError) as exc:
        if args.classes is not None:  # ClassesFileError or OSError: the message names the file
            return fail("fdi-monitor", f"--classes {one_line(exc)}")
        return fail("fdi-monitor", f"no fault signatures for table {args.vehicle}: {one_line(exc)}")
    dbc = resolve(args.vehicle).dbc if args.classes is None else None
    mon = Monitor(CanDatabase(dbc) if dbc is not None else CanDatabase(), classes, step,
                  gap_threshold=args.gap_threshold)
    opened = open_cli_bus("fdi-monitor", BusOptions.from_args(args))
    if opened is None:
        return EXIT_ERROR
    bus = opened[0]
    signal_ready(args.ready_file)
    tty = sys.stdout.isatty()
    shown = 0
    t_start = next_show = time.monotonic()
    last_rx = t_start
    try:
        while not stop():
            now = time.monotonic()
            if args.duration is not None and now - t_start >= args.duration:
                break
            if args.idle_exit is not None and mon.t0 is not None and now - last_rx >= args.idle_exit:
                break
            msg = bus.recv(timeout=0.05)
            if msg is not None and not (msg.is_error_frame or msg.is_remote_frame):
                last_rx = time.monotonic()
                if mon.t0 is None and args.origin_file is not None and args.origin_file.exists():
                    mon.t0 = float(args.origin_file.read_text(encoding="utf-8"))
                mon.on_frame(int(msg.arbitration_id), bytes(msg.data), float(msg.timestamp))
            for gap in mon.new_gaps:  # an event worth a line of its own, also with --quiet
                print(("\n" if tty and not args.quiet else "") + gap.describe(), flush=True)
                shown = 0
            mon.new_gaps.clear()
            if not args.quiet and now >= next_show:
                next_show = now + args.refresh
                if tty:  # redraw the table in place
                    rows = mon.table(time.time())
                    up = f"\x1b[{shown}F" if shown else ""
                    print(up + "".join(f"\x1b[K{row}\n" for row in rows), end="", flush=True)
                    shown = len(rows)
                else:
                    print(mon.status_line(time.time()), flush=True)
    finally:
        bus.shutdown()
    return finish(mon, args)


if __name__ == "__main__":
    raise SystemExit(main())
