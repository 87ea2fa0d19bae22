"""A fleet's recorded drives through the ECU at once: the logs spread over local processes or a Dask cluster,
and one quality table over all of them (per fault, per log).

What validating a diagnosis on a fleet takes: thousands of logs, each replayed through a fresh ECU as fast as
the C core runs (``fdi-replay --offline``'s one-call path) and scored against its ground truth where there is
one (``<log>.truth.json`` beside the log, as ``fdi-sim`` writes it). A log is one task; this module
distributes the tasks and aggregates their `LogResult`; the task itself is given by the caller
(`fdi_host.replay.replay_log`, one log), so the distribution knows nothing of how a log is replayed.

Executors:

* one process (``workers=1``): the tasks in a loop (the reference of the throughput benchmark);
* local processes (default): `concurrent.futures.ProcessPoolExecutor` with one worker per core;
* a Dask cluster (``scheduler="tcp://host:8786"``, the ``fleet`` extra: ``pip install 'romo-fdi[fleet]'``):
  `distributed.Client.map`, one task per log. The workers need romo-fdi installed and the logs at the same
  paths (a shared file system); only the small `LogResult` comes back.

A log that cannot be read, or whose truth file is malformed, is a row with its one-line error, never the end of
the run; the command line exits 1 when any log failed. A log with malformed lines (garbage, a last line cut off)
is replayed without them, as the ECU skips a bad frame; its row counts them (`LogResult.skipped`) and the summary
lists those logs (`skipped_lines`); with ``strict`` such a log fails instead, naming the file and the line.

    logs = find_logs(["fleet/2026-06/"])                       # folders, files, glob patterns
    report = run_fleet(partial(replay_log, table="romo"), logs, scheduler="tcp://10.0.0.5:8786")
    print(markdown(report))
"""

from __future__ import annotations

import glob
import json
import statistics
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from fdi_analysis.names import in_order
from fdi_host.can.logs import LogError, formats_text, is_log, looks_like_log
from fdi_host.errors import FdiHostError
from fdi_host.executors import ExecutorError, run_tasks
from fdi_host.monitor.score import FaultScore
from fdi_host.sim.faults import FAULT_IDS

GLOB_CHARS = frozenset("*?[")


class FleetError(FdiHostError, ValueError):
    """A fleet that cannot be run: no log found, a missing path, no Dask, a scheduler that cannot be reached."""


@dataclass(frozen=True)
class LogResult:
    """One log through the ECU: what it held, what the diagnosis said, and its score when it has a truth file.
    `error` is the one-line reason when the log could not be replayed (every other field is then empty)."""

    log: str
    frames: int = 0
    duration: float = 0.0  # s of drive (last minus first frame)
    wall: float = 0.0  # s to read, replay and score it
    steps: int = 0  # diagnosis steps
    alarm_steps: int = 0  # steps with any test in alarm
    truth: str | None = None  # the truth file it was scored against
    faults: tuple[FaultScore, ...] = ()
    false_alarms: int = 0
    false_alarm_time: float = 0.0  # s
    error: str | None = None
    skipped: int = 0  # malformed lines (or records) skipped while reading the log
    skipped_note: str | None = None  # which, as one line (`fdi_host.can.logs.LogIssues.summary`)


@dataclass(frozen=True)
class FaultRow:
    """One fault over the fleet: its injected cases in the logs with a truth file."""

    fault: str
    expected_class: str  # the table's structural isolability class ("-": not detectable by the table)
    cases: int
    detected: int
    missed: int
    not_evaluable: int  # missed while its window overlapped a gap
    correct: int  # isolated as its structural class
    wrong: int  # isolated as a class without the fault
    delay_median: float | None  # s, of the detected cases
    delay_max: float | None


@dataclass(frozen=True)
class FleetReport:
    logs: tuple[LogResult, ...]  # sorted by path
    faults: tuple[FaultRow, ...]  # in Table I order
    wall: float  # s, the whole run (from the first task sent to the last result)
    executor: str  # "one process", "4 local processes", "Dask tcp://...: 8 threads on 4 workers"
    table: str = ""
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def failed(self) -> list[LogResult]:
        return [r for r in self.logs if r.error is not None]

    @property
    def replayed(self) -> list[LogResult]:
        return [r for r in self.logs if r.error is None]

    @property
    def drive_hours(self) -> float:
        return sum(r.duration for r in self.replayed) / 3600.0

    @property
    def logs_per_minute(self) -> float:
        return 60.0 * len(self.replayed) / self.wall if self.wall > 0 else float("inf")

    @property
    def drive_hours_per_minute(self) -> float:
        return 60.0 * self.drive_hours / self.wall if self.wall > 0 else float("inf")

    @property
    def fault_free_hours(self) -> float:
        """Drive time of the scored logs without an injected fault (where every alarm is false)."""
        return sum(r.duration for r in self.replayed if r.truth is not None and not r.faults) / 3600.0

    @property
    def false_alarms(self) -> int:
        return sum(r.false_alarms for r in self.replayed)

    @property
    def with_skipped(self) -> list[LogResult]:
        """The logs replayed without some of their lines (malformed: garbage, a last line cut off)."""
        return [r for r in self.replayed if r.skipped]


# ---------------------------------------------------------------------------------------------- the logs
_NONE_FOUND = ".log/.asc/.blf log"  # the common formats, in "no ... log" messages (every other is looked for too)


def find_logs(specs: Sequence[str | Path]) -> list[Path]:
    """The CAN logs named by `specs`: files, folders (searched recursively for every log format python-can reads:
    .log, .asc, .blf, .trc, .csv, .mf4, .db, the text formats also .gz; a .csv or .db only with python-can's
    header, `looks_like_log`) and glob patterns (``**`` crosses folders), each log once, sorted. FleetError when a
    spec names nothing or no log is found."""
    out: set[Path] = set()
    for spec in specs:
        text = str(spec)
        p = Path(text)
        if p.is_dir():
            found = [q for q in p.rglob("*") if q.is_file() and looks_like_log(q)]
        elif GLOB_CHARS & set(text):
            found = [Path(q) for q in glob.glob(text, recursive=True) if Path(q).is_file() and looks_like_log(q)]
            if not found:
                raise FleetError(f"{text}: no {_NONE_FOUND} matches (nor any other format: {formats_text()})")
        elif p.is_file():
            if not is_log(p):
                raise FleetError(f"{p}: unsupported log format {''.join(p.suffixes[-2:]) or p.name!r}; use one of "
                                 f"{formats_text()}")
            found = [p]
        else:
            raise FleetError(f"{p}: no such file or folder")
        out.update(found)
    if not out:
        raise FleetError(f"no {_NONE_FOUND} log in {', '.join(str(s) for s in specs)} (nor any other format: "
                         f"{formats_text()})")
    return sorted(out)


def is_fleet(specs: Sequence[str | Path]) -> bool:
    """More than one log, a folder or a glob pattern: what ``fdi-replay`` replays as a fleet."""
    return len(specs) > 1 or any(Path(str(s)).is_dir() or GLOB_CHARS & set(str(s)) for s in specs)


def truth_file(log: Path) -> Path:
    """The ground truth ``fdi-sim`` writes beside a log: ``drive.blf`` -> ``drive.truth.json``."""
    return log.with_suffix(".truth.json")


def read_truth(path: Path) -> dict[str, Any]:
    """A truth file's content; LogError naming the file when it is not one."""
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise LogError(f"{path}: not a readable truth file ({type(exc).__name__}: {exc})") from exc
    if not isinstance(doc, dict) or not isinstance(doc.get("faults", []), list):
        raise LogError(f"{path}: not a truth file (expected an object with a 'faults' list)")
    return doc


# ---------------------------------------------------------------------------------------------- running
Task = Callable[[str], LogResult]
Progress = Callable[[LogResult], None]


def run_fleet(task: Task, logs: Sequence[Path], *, workers: int | None = None, scheduler: str | None = None,
              progress: Progress | None = None, table: str = "") -> FleetReport:
    """`task` on every log: in this process (``workers=1``), on local processes (default: one per core) or on
    the Dask cluster at `scheduler` (`fdi_host.executors`); `progress` is called with each result as it arrives."""
    try:
        source = run_tasks(task, [str(p) for p in logs], _failed, workers=workers, scheduler=scheduler)
    except ExecutorError as exc:
        raise FleetError(str(exc)) from exc
    return _collect(source, progress, table)


def _collect(source: tuple[str, Iterator[LogResult]], progress: Progress | None, table: str) -> FleetReport:
    executor, results = source
    t0 = time.perf_counter()
    out = []
    for r in results:
        out.append(r)
        if progress is not None:
            progress(r)
    wall = time.perf_counter() - t0
    return aggregate(out, wall, executor, table)


def _failed(log: str, exc: BaseException) -> LogResult:
    """A task that raised instead of returning its error (a bug, or a worker lost): still one row."""
    return LogResult(log, error=f"{type(exc).__name__}: {' '.join(str(exc).split())}")


# ---------------------------------------------------------------------------------------------- the table
def aggregate(results: Sequence[LogResult], wall: float, executor: str, table: str = "") -> FleetReport:
    """The per-fault rows over all scored logs, and the logs sorted by path."""
    by_fault: dict[str, list[FaultScore]] = {}
    for r in results:
        for f in r.faults:
            by_fault.setdefault(f.fault, []).append(f)
    rows = []
    for fault in in_order(by_fault, FAULT_IDS):
        cases = by_fault[fault]
        delays = [c.detection_delay for c in cases if c.detected and c.detection_delay is not None]
        classes = {c.expected_class for c in cases}
        rows.append(FaultRow(
            fault=fault,
            expected_class=classes.pop() if len(classes) == 1 else "/".join(sorted(classes)),
            cases=len(cases),
            detected=sum(c.detected for c in cases),
            missed=sum(not c.detected and not c.not_evaluable for c in cases),
            not_evaluable=sum(c.not_evaluable for c in cases),
            correct=sum(c.isolation_correct is True for c in cases),
            wrong=sum(c.wrong_isolation for c in cases),
            delay_median=statistics.median(delays) if delays else None,
            delay_max=max(delays) if delays else None,
        ))
    return FleetReport(tuple(sorted(results, key=lambda r: r.log)), tuple(rows), wall, executor, table)


def _ms(x: float | None) -> str:
    return "-" if x is None else f"{x * 1e3:.0f}"


def summary_line(report: FleetReport) -> str:
    n, ok = len(report.logs), len(report.replayed)
    skipped = report.with_skipped
    note = (f"; {len(skipped)} logs with malformed lines skipped ({sum(r.skipped for r in skipped)} lines)"
            if skipped else "")
    return (f"{ok} of {n} logs, {report.drive_hours:.2f} drive-hours in {report.wall:.1f} s on "
            f"{report.executor}: {report.logs_per_minute:.0f} logs/min, "
            f"{report.drive_hours_per_minute:.2f} drive-hours/min{note}")


def skipped_lines(report: FleetReport) -> list[str]:
    """One line per log replayed without some malformed lines: the log, how many, the first line numbers, why."""
    return [r.skipped_note or f"{r.log}: {r.skipped} malformed lines skipped" for r in report.with_skipped]


def fault_table(report: FleetReport) -> list[str]:
    lines = ["| fault | structural class | cases | detected | missed | not evaluable | isolated as class | wrong class "
             "| delay median / max [ms] |", "|---|---|---|---|---|---|---|---|---|"]
    for f in report.faults:
        lines.append(f"| {f.fault} | {{{f.expected_class.replace(',', ', ')}}} | {f.cases} | {f.detected} | "
                     f"{f.missed} | {f.not_evaluable} | {f.correct} | {f.wrong} | "
                     f"{_ms(f.delay_median)} / {_ms(f.delay_max)} |")
    return lines


def log_table(report: FleetReport) -> list[str]:
    lines = ["| log | drive [s] | frames | steps with alarm | injected | detected | isolated as class | "
             "false alarms | error |", "|---|---|---|---|---|---|---|---|---|"]
    for r in report.logs:
        scored = r.truth is not None
        lines.append(
            f"| {r.log} | {r.duration:.1f} | {r.frames} | {r.alarm_steps} | "
            f"{' '.join(f.fault for f in r.faults) if scored else 'no truth'} | "
            f"{sum(f.detected for f in r.faults) if scored else '-'} | "
            f"{sum(f.isolation_correct is True for f in r.faults) if scored else '-'} | "
            f"{r.false_alarms if scored else '-'} | {r.error or ''} |")
    return lines


def free_line(report: FleetReport) -> str:
    scored = [r for r in report.replayed if r.truth is not None]
    free = [r for r in scored if not r.faults]
    unscored = [r for r in report.replayed if r.truth is None]
    text = (f"false alarms: {report.false_alarms} in {len(scored)} scored logs; fault-free logs: {len(free)} "
            f"({60 * report.fault_free_hours:.1f} min), {sum(r.false_alarms for r in free)} false alarms")
    if unscored:
        text += (f"; {len(unscored)} logs without a truth file (not scored), "
                 f"{sum(r.alarm_steps > 0 for r in unscored)} of them with an alarm")
    return text


def markdown(report: FleetReport, per_log: bool = True) -> str:
    md = ["# Fleet replay", "", *([f"- table: {report.table}"] if report.table else []), f"- {summary_line(report)}",
          f"- {free_line(report)}", "", "## Per fault (the logs with a truth file)", "", *fault_table(report), ""]
    if report.failed:
        md += [f"{len(report.failed)} logs could not be replayed (see the table per log).", ""]
    if report.with_skipped:
        md += ["## Logs with malformed lines (skipped)", "", *(f"- {line}" for line in skipped_lines(report)), ""]
    if per_log:
        md += ["## Per log", "", *log_table(report), ""]
    return "\n".join(md)


def to_json(report: FleetReport) -> dict[str, Any]:
    return {
        "table": report.table,
        "executor": report.executor,
        "wall_s": report.wall,
        "logs_total": len(report.logs),
        "logs_failed": len(report.failed),
        "drive_hours": report.drive_hours,
        "logs_per_minute": report.logs_per_minute,
        "drive_hours_per_minute": report.drive_hours_per_minute,
        "fault_free_hours": report.fault_free_hours,
        "false_alarms": report.false_alarms,
        "logs_with_skipped_lines": len(report.with_skipped),
        "skipped_lines": sum(r.skipped for r in report.with_skipped),
        "faults": [asdict(f) for f in report.faults],
        "logs": [asdict(r) for r in report.logs],
        **report.extra,
    }


def write_reports(out_dir: Path, report: FleetReport) -> list[Path]:
    """fleet.json (every log and fault case) and fleet.md (the tables) in `out_dir`."""
    out_dir.mkdir(parents=True, exist_ok=True)
    pj, pm = out_dir / "fleet.json", out_dir / "fleet.md"
    pj.write_text(json.dumps(to_json(report), indent=2) + "\n", encoding="utf-8")
    pm.write_text(markdown(report), encoding="utf-8")
    return [pj, pm]
