"""``fdi-replay``: a recorded CAN log (any format python-can reads) back onto a bus, or straight through the ECU.

Logs: candump ``.log``, Vector ``.asc`` and ``.blf``, PEAK ``.trc``, ``.csv``, ``.mf4`` (with asammdf) and SQLite
``.db``, the text formats also gzip-compressed (``.log.gz``), read through python-can's readers
(`fdi_host.can.logs`). A malformed line (garbage, a last line cut off) is counted, reported with its line number
and skipped, as the ECU skips a bad frame; ``--strict`` makes it an error naming the file and the line.

On a bus the frames keep their relative timing, at ``--speed`` times real time (``max``: as fast as
python-can sends). ``--offline`` skips the bus: every frame goes through the ECU bindings with its log
timestamp on the time base of `fdi_host.ecu.session` (the one ``fdi-ecu`` uses live), as fast as possible, and
the speed against real time is printed. By default in one C call (`fdi_host.ecu.bindings.Ecu.process_arrays`,
`Ecu.process` on the log's columns: rx then poll per frame; the C core runs the steps due before a frame inside
rx, so this equals EcuSession's poll-then-rx order, tested); with ``--ecu-log`` frame by frame through
`EcuSession`, recording every step's residuals.
With ``--truth`` the offline diagnosis is scored and reported like ``fdi-monitor`` does.

Many logs (several files, a folder, a glob pattern) are a fleet (`fdi_host.fleet`): each log offline through
its own ECU on local processes, or on a Dask cluster with ``--scheduler``, scored against the truth file beside
it, into one table per fault and per log (fleet.json, fleet.md in ``--out-dir``).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from fdi_analysis.cli.common import EXIT_ERROR, INPUT_ERRORS, add_version, fail, one_line, run, use_file_backend
from fdi_host import fleet
from fdi_host.can.dbc import CanDatabase
from fdi_host.can.frame import Frame
from fdi_host.can.log_columns import FrameColumns, frame_columns, read_columns_checked
from fdi_host.can.logs import LogError, LogIssues, formats_text, is_log, read_log_checked
from fdi_host.ecu.records import DiagRecord
from fdi_host.ecu.session import ORIGIN_LEAD, EcuSession, table_classes
from fdi_host.live.bus import BusOptions, StopFlag, add_bus_arguments, open_cli_bus
from fdi_host.live.sender import send_paced
from fdi_host.monitor.report import plot_diagnosis, plot_residuals, score_table, write_reports
from fdi_host.monitor.score import score_run, windows_from_truth
from fdi_host.vehicle import add_vehicle_argument

EPILOG = """\
examples:
  fdi-replay drive.blf --speed 1 --interface udp_multicast          (real time onto the bus)
  fdi-replay drive.log --speed 10 --interface socketcan --channel vcan0
  fdi-replay drive.trc --interface pcan --channel PCAN_USBBUS1 --bitrate 500000   (onto a real bus, PEAK adapter)
  fdi-replay drive.asc --can-config bus.ini --can-context bench     (the bus in a python-can configuration file)
  fdi-replay drive.log.gz --offline --vehicle kin --strict          (a malformed line is an error, not skipped)
  fdi-replay drive.blf --offline --vehicle kin                      (through the bindings, prints x real time)
  fdi-replay drive.blf --offline --vehicle kin --truth drive.truth.json --out-dir out/replay --ecu-log out/ecu.json
  fdi-replay fleet/ --out-dir out/fleet                             (every log below fleet/, one process per core)
  fdi-replay 'fleet/**/*.blf' --scheduler tcp://10.0.0.5:8786       (on a Dask cluster; quote the pattern)
"""


@dataclass
class OfflineResult:
    session: EcuSession
    frames: int
    log_duration: float  # s, last minus first timestamp
    wall: float  # s, processing time (frames already in memory)

    @property
    def speed(self) -> float:
        return self.log_duration / self.wall if self.wall > 0 else float("inf")


def replay_offline(frames: Sequence[Frame], table: str, step: float = 0.01,
                   t0: float | None = None) -> OfflineResult:
    """All frames through a fresh ECU as fast as possible; then one more poll `step` after the last frame.

    `t0`: the time of the drive's t = 0 on the log's clock (as ``fdi-ecu --origin-file``); default: the first
    frame's timestamp."""
    session = EcuSession(table)
    if t0 is not None:
        session.anchor(t0)
    t_start = time.perf_counter()
    session.feed_many((f.frame_id, f.data, f.timestamp) for f in frames)
    if frames:
        session.finish(frames[-1].timestamp + step)
    wall = time.perf_counter() - t_start
    dur = frames[-1].timestamp - frames[0].timestamp if frames else 0.0
    return OfflineResult(session, len(frames), dur, wall)


@dataclass
class FastResult:
    records: list[DiagRecord]
    ecu: Any
    frames: int
    log_duration: float
    wall: float
    c_wall: float = 0.0  # s, of `wall` in the one C call (the rest: frames to arrays, diagnosis frames to records)

    @property
    def speed(self) -> float:
        return self.log_duration / self.wall if self.wall > 0 else float("inf")


def _diag_decoder(db: CanDatabase) -> Callable[[bytes], list[list[int]]]:
    """Alarm masks, candidates, isolation classes and statuses of FDI_Diagnosis payloads (8 bytes each,
    concatenated), one list per field; bit positions from the DBC (little-endian unsigned signals; the frame is the
    C ECU core's, the same on every vehicle's bus: dbc/romo.dbc describes it), extracted
    with numpy shifts on all payloads at once (cantools' decode is 20x slower per frame)."""
    msg = db.message("FDI_Diagnosis")
    fields = []
    for name in ("FDI_AlarmMask", "FDI_CandidateFaults", "FDI_IsolationClass", "FDI_Status"):
        sig = msg.get_signal_by_name(name)
        if sig.byte_order != "little_endian" or sig.is_signed or int(sig.start) + int(sig.length) > 64:
            raise ValueError(f"{name}: the fast decoder handles unsigned little-endian signals of 8 bytes only")
        fields.append((np.uint64(sig.start), np.uint64((1 << int(sig.length)) - 1)))

    def decode(payloads: bytes) -> list[list[int]]:
        v = np.frombuffer(payloads, dtype="<u8")
        return [(v >> start & mask).tolist() for start, mask in fields]

    return decode


def replay_columns(columns: FrameColumns, table: str) -> FastResult:
    """A whole log, as columns in file order, through the ECU in one C call
    (`fdi_host.ecu.bindings.Ecu.process_arrays`: rx then poll per frame), same time base as `EcuSession` (first
    frame at 0.5 ms after a step boundary); the ECU's own diagnosis frames in the log are left out. Only the
    diagnosis frames come back (no residuals): the fast path for scoring and for measuring speed. `wall` runs from
    the columns to the records."""
    session = EcuSession(table)
    ecu = session.ecu
    decode = _diag_decoder(CanDatabase())
    t_start = time.perf_counter()
    records: list[DiagRecord] = []
    c_wall = 0.0
    n = len(columns)
    if n:
        ecu.poll(0.0)  # anchors the step schedule, as EcuSession.anchor
        keep = columns.frame_id != session.diag_id
        sent = columns if keep.all() else columns.select(keep)
        t = sent.t - (columns.t[0] - ORIGIN_LEAD)
        t_c = time.perf_counter()
        idx, payloads = ecu.process_arrays(t, sent.frame_id, sent.dlc, sent.data)
        c_wall = time.perf_counter() - t_c
        records = list(map(DiagRecord, (t[idx] - ORIGIN_LEAD).tolist(), *decode(payloads)))
    wall = time.perf_counter() - t_start
    dur = float(columns.t[-1] - columns.t[0]) if n else 0.0
    return FastResult(records, ecu, n, dur, wall, c_wall)


def replay_offline_fast(frames: Sequence[Frame], table: str) -> FastResult:
    """`replay_columns` of frame objects; their conversion into columns counts in `wall`."""
    t0 = time.perf_counter()
    columns = frame_columns(frames)
    convert = time.perf_counter() - t0
    res = replay_columns(columns, table)
    return replace(res, wall=res.wall + convert)


# A bad log, truth file or table: the project's typed errors (LogError, EcuError, ...: FdiError) and a file that
# cannot be read, as a command line reports them (`fdi_analysis.cli.common.INPUT_ERRORS`)
LOG_ERRORS: tuple[type[BaseException], ...] = INPUT_ERRORS


def no_frames(issues: LogIssues) -> LogError:
    """The error for a log without a data frame (with what was skipped, if anything)."""
    return LogError(f"{issues.path}: holds no data frames{f' ({issues.summary()})' if issues else ''}")


def replay_log(path: str, table: str = "romo", grace: float = 3.0, strict: bool = False) -> fleet.LogResult:
    """One log of a fleet: read, through a fresh ECU in one C call, scored against ``<log>.truth.json`` when it
    exists. Never raises for a bad log or truth file: the result then carries the one-line error. Malformed lines
    are skipped and counted in the result (`strict`: the log fails at the first one)."""
    t0 = time.perf_counter()
    p = Path(path)
    try:
        read = read_columns_checked(p, strict)
        if not len(read.columns):
            raise no_frames(read.issues)
        result = _scored(p, replay_columns(read.columns, table), grace)
    except LOG_ERRORS as exc:
        return fleet.LogResult(str(p), wall=time.perf_counter() - t0, error=one_line(exc))
    return replace(result, wall=time.perf_counter() - t0, skipped=read.issues.skipped,
                   skipped_note=read.issues.summary() if read.issues else None)


def _scored(p: Path, res: FastResult, grace: float) -> fleet.LogResult:
    """A replayed log's row: what the diagnosis said, scored against ``<log>.truth.json`` when it exists."""
    steps = len(res.records)
    alarms = sum(1 for r in res.records if r.alarm_mask)
    truth = fleet.truth_file(p)
    if not truth.is_file():
        return fleet.LogResult(str(p), res.frames, res.log_duration, 0.0, steps, alarms)
    doc = fleet.read_truth(truth)
    try:
        windows = windows_from_truth(doc)
    except (KeyError, TypeError, ValueError) as exc:
        raise LogError(f"{truth}: a fault entry without {exc}") from exc
    score = score_run(res.records, windows, table_classes(res.ecu), grace)
    return fleet.LogResult(str(p), res.frames, res.log_duration, 0.0, steps, alarms, str(truth), tuple(score.faults),
                           len(score.false_alarms), score.false_alarm_time)


def replay_fleet(logs: Sequence[str | Path], table: str = "romo", grace: float = 3.0, *, workers: int | None = None,
                 scheduler: str | None = None, progress: fleet.Progress | None = None,
                 strict: bool = False) -> fleet.FleetReport:
    """Every log of `logs` (files, folders, glob patterns) through the ECU with `replay_log`, on local processes
    (`workers`, default one per core) or the Dask cluster at `scheduler`; one report over all of them."""
    return fleet.run_fleet(partial(replay_log, table=table, grace=grace, strict=strict), fleet.find_logs(logs),
                           workers=workers, scheduler=scheduler, progress=progress, table=table)


def _speed(text: str) -> float | None:
    if text == "max":
        return None
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--speed {text!r}: a number > 0 or 'max'") from None
    if not v > 0.0:
        raise argparse.ArgumentTypeError(f"--speed {text!r}: must be > 0")
    return v


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="fdi-replay", description=__doc__.splitlines()[0] if __doc__ else None,
                                 epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("logs", nargs="+", metavar="LOG",
                    help="CAN log: .log (candump), .asc, .blf, .trc, .csv, .mf4 (with asammdf), .db, the text formats "
                    "also .gz; several logs, a folder or a glob pattern: a fleet (offline, scored against each log's "
                    ".truth.json)")
    ap.add_argument("--speed", type=_speed, default=1.0, help="times real time: 1, 10, ... or max (default 1)")
    add_bus_arguments(ap)
    ap.add_argument("--offline", action="store_true", help="no bus: through the ECU bindings as fast as possible")
    add_vehicle_argument(ap, "the ECU of --offline")
    ap.add_argument("--truth", type=Path, help="with --offline: score against this truth.json")
    ap.add_argument("--out-dir", type=Path, default=Path("out/replay"), help="with --offline --truth: reports")
    ap.add_argument("--ecu-log", type=Path, help="with --offline: write the ECU log (every step)")
    ap.add_argument("--grace", type=float, default=3.0, help="scoring grace after a fault's end [s] (default 3)")
    ap.add_argument("--workers", type=int, default=None,
                    help="fleet: local processes (default: one per core; 1: in this process)")
    ap.add_argument("--scheduler", metavar="ADDRESS",
                    help="fleet: the Dask scheduler to run on, e.g. tcp://10.0.0.5:8786 (pip install romo-fdi[fleet])")
    ap.add_argument("--strict", action="store_true",
                    help="a malformed line (garbage, a last line cut off) is an error naming the file and the line "
                    "(default: counted, reported and skipped, as the ECU skips a bad frame)")
    ap.add_argument("--quiet", action="store_true", help="fleet: no progress bar")
    return add_version(ap)


def main(argv: Sequence[str] | None = None) -> int:
    ap = build_parser()
    args = ap.parse_args(argv)
    if args.workers is not None and args.workers < 1:
        ap.error("--workers must be >= 1")
    use_file_backend()
    if fleet.is_fleet(args.logs) or args.scheduler is not None or args.workers is not None:
        if args.truth is not None or args.ecu_log is not None:
            ap.error("--truth and --ecu-log are for one log (a fleet's truth files lie beside its logs)")
        return run("fdi-replay", lambda: _fleet(args))
    args.log = Path(args.logs[0])
    if not is_log(args.log):
        ap.error(f"{args.log}: unsupported extension; use {formats_text()}")
    if not args.log.is_file():  # a runtime error, not a usage error: one line, exit 1
        return fail("fdi-replay", f"{args.log}: no such file")
    return run("fdi-replay", lambda: _one_log(args))


def _one_log(args: argparse.Namespace) -> int:
    """One log onto the bus, or offline through the ECU (in one C call the log read as columns, no frame objects)."""
    if args.offline:  # a LogError names the file and what is wrong
        source: list[Frame] | FrameColumns
        if args.ecu_log is None:
            cols = read_columns_checked(args.log, args.strict)
            source, issues = cols.columns, cols.issues
        else:
            read = read_log_checked(args.log, args.strict)
            source, issues = read.frames, read.issues
        _report_skipped(issues)
        return _offline(args, source) if len(source) else fail("fdi-replay", no_frames(issues))
    read = read_log_checked(args.log, args.strict)
    frames = read.frames
    _report_skipped(read.issues)
    if not frames:
        return fail("fdi-replay", no_frames(read.issues))
    stop = StopFlag()
    opened = open_cli_bus("fdi-replay", BusOptions.from_args(args))
    if opened is None:
        return EXIT_ERROR
    bus, bus_config = opened
    try:
        t0 = time.perf_counter()
        log = send_paced(bus, frames, args.speed, stop)
        wall = time.perf_counter() - t0
    finally:
        bus.shutdown()
    dur = frames[-1].timestamp - frames[0].timestamp
    print(f"replayed {len(log.wall)} of {len(frames)} frames ({dur:.2f} s of log) onto {bus_config.describe()} in "
          f"{wall:.2f} s ({dur / wall if wall > 0 else float('inf'):.1f}x real time); "
          f"largest delay behind schedule {log.max_behind * 1e3:.2f} ms")
    return 130 if log.interrupted else 0


def _report_skipped(issues: LogIssues) -> None:
    """The malformed lines skipped, as one line (nothing for a clean log)."""
    if issues:
        print(f"skipped: {issues.summary()}", flush=True)


def _offline(args: argparse.Namespace, source: list[Frame] | FrameColumns) -> int:
    """Through the bindings: per frame with the ECU log (residuals) from frame objects if --ecu-log is given, else
    in one C call from the columns."""
    try:
        if isinstance(source, FrameColumns):
            fast = replay_columns(source, args.vehicle)
            ecu, records, steps, speed, wall = fast.ecu, fast.records, [], fast.speed, fast.wall
            n, dur = fast.frames, fast.log_duration
        else:
            res = replay_offline(source, args.vehicle)
            ecu, records, steps, speed, wall = res.session.ecu, res.session.records(), res.session.steps, \
                res.speed, res.wall
            n, dur = len(source), source[-1].timestamp - source[0].timestamp
    except (ImportError, OSError) as exc:  # not built (an EcuError, an FdiError, goes to `run`: one line too)
        return fail("fdi-replay", f"cannot load the ECU bindings ({one_line(exc)}); build them with `pip install -e .`")
    mode = "per frame, with ECU log" if args.ecu_log is not None else "one C call (Ecu.process_arrays)"
    print(f"offline ({mode}): {n} frames, {dur:.2f} s of log in {wall:.3f} s = {speed:.0f}x real time; "
          f"{len(records)} diagnosis steps; {sum(1 for r in records if r.alarm_mask)} with an alarm")
    c = ecu.counters()
    print(f"ECU counters: frames {c.frames}, steps {c.steps}, rejected {c.rejected_total}")
    if args.ecu_log is not None:
        print(f"wrote {res.session.write(args.ecu_log)}")
    if args.truth is not None:
        truth = fleet.read_truth(args.truth)
        classes = table_classes(ecu)
        windows = windows_from_truth(truth)
        score = score_run(records, windows, classes, args.grace)
        print(score_table(score))
        paths = write_reports(args.out_dir, score, None, {"table": args.vehicle, "log": str(args.log),
                                                          "speed_vs_real_time": speed})
        for p in (plot_diagnosis(args.out_dir / "diagnosis.png", records, windows, classes),
                  plot_residuals(args.out_dir / "residuals.png", steps, windows, classes, ORIGIN_LEAD)):
            if p is not None:
                paths.append(p)
        print("wrote " + ", ".join(str(p) for p in paths))
    return 0


def _fleet(args: argparse.Namespace) -> int:
    """Many logs through the ECU (local processes or Dask), one quality table."""
    logs = fleet.find_logs(args.logs)
    where = f"Dask at {args.scheduler}" if args.scheduler else "local processes"
    print(f"fleet: {len(logs)} logs, table {args.vehicle}, on {where}", flush=True)
    with tqdm(total=len(logs), unit="log", desc="replay", disable=args.quiet, file=sys.stderr) as bar:
        def progress(r: fleet.LogResult) -> None:
            bar.update(1)
            if r.error is not None:
                bar.write(f"fdi-replay: {r.error}", file=sys.stderr)

        report = fleet.run_fleet(partial(replay_log, table=args.vehicle, grace=args.grace, strict=args.strict), logs,
                                 workers=args.workers, scheduler=args.scheduler, progress=progress, table=args.vehicle)
    print("\n".join(fleet.fault_table(report)))
    print(fleet.free_line(report))
    if len(report.logs) <= 20:
        print("\n".join(fleet.log_table(report)))
    skipped = fleet.skipped_lines(report)
    if skipped:
        print(f"logs with malformed lines (skipped): {len(skipped)}")
        print("\n".join(f"  {line}" for line in skipped[:20]))
        if len(skipped) > 20:
            print("  ... (every one in fleet.md)")
    print(fleet.summary_line(report))
    print("wrote " + ", ".join(str(p) for p in fleet.write_reports(args.out_dir, report)))
    if report.failed:
        first = report.failed[0].error or ""
        return fail("fdi-replay", f"{len(report.failed)} of {len(report.logs)} logs could not be replayed "
                    f"(first: {first})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
