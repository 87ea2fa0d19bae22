"""Scoring a diagnosis run against the ground truth of the drive.

Input: the sequence of diagnosis results (one `DiagRecord` per diagnosis step, from the bus or from an
offline replay), the fault windows of the drive (``<log>.truth.json`` written by ``fdi-sim``) and the
structural isolability classes of the diagnosis table (`TableClasses`). Per injected fault:

* detected / detection delay: the first step with any test in alarm in ``[start, end + grace)`` (the grace
  period stops where the next fault starts);
* isolation delay: the first step whose candidate set isolates the fault to its structural isolability class
  (the set of faults not isolable from it, a single fault if it is uniquely isolable): it holds the fault and
  lies within the class (`isolates_fault`, the diagnosis library's `isolated` to that class, as the quality
  suite counts it), and the fraction of the alarmed steps with such a candidate set;
* isolation: the candidate set that holds for most of the alarmed steps in that window ("verdict"); it is
  correct iff it isolates the fault so. A non-empty verdict that does not contain the fault is a wrong
  isolation; an empty one means the alarm pattern fits no single fault ("unexplained");
* a fault that no test of the table is sensitive to is "not detectable" by the table (expected: no alarm;
  alarms in its window are reported, its isolation is not judged).

Gaps (`fdi_host.monitor.gaps`: the ECU's diagnosis stream or the simulator's sensor frames silent): a
gap is never a detection (there are no diagnosis frames in a diagnosis gap, and the frames of a sensor gap,
where the ECU's inputs time out, are not used to detect); a fault whose window overlaps a gap and that was
not detected is "not evaluable" (its missed detection is explained by the gap, and reported as such), and
each fault records how long its window ``[start, end + grace)`` was inside gaps.

Recovery: an alarm run (consecutive alarmed steps) that holds in a fault's window and goes on past it without
a test joining that had not alarmed in the window is the fault's (typically the transient of the fault's
removal through a filtered derivative, then the CUSUM's return below its threshold); each fault records how
long after its end the alarm still held (``alarm_after_end``), and the report names the faults that held it
longer than the grace.

False alarms: alarm episodes (steps with a non-empty alarm mask, consecutive steps merged) that start
outside every ``[start, end + grace)`` window and are not such a continued run (or where a test joins
it that had not alarmed in the window); their count and the total time in false alarm.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from itertools import pairwise
from typing import Any

from fdi_host.ecu.records import DiagRecord, TableClasses, isolates_fault
from fdi_host.monitor.gaps import Gap, overlap


@dataclass(frozen=True)
class FaultWindow:
    fault: str  # the fault's name ("f4"), as the table names it
    start: float
    end: float  # the drive's duration if the fault stays


def windows_from_truth(truth: Mapping[str, Any]) -> list[FaultWindow]:
    """Fault windows of a ``truth.json`` (times relative to the drive's start, ``start_time`` removed)."""
    t0 = float(truth.get("start_time", 0.0))
    out = []
    for f in truth.get("faults", []):
        for iv in f.get("intervals", []):
            out.append(FaultWindow(str(f["fault"]), float(iv["start"]) - t0, float(iv["end"]) - t0))
    return sorted(out, key=lambda w: (w.start, w.fault))


@dataclass
class FaultScore:
    fault: str
    start: float
    end: float
    detectable: bool  # structurally, by this table
    expected_class: str  # faults not isolable from it ("-" if not detectable)
    detected: bool = False
    detection_delay: float | None = None
    isolation_delay: float | None = None  # first step whose candidates isolate the fault to its class
    isolated_fraction: float = 0.0  # of the alarmed steps in the window, those whose candidates do so
    verdict: str = "-"  # majority candidate set while in alarm
    isolation_correct: bool | None = None  # None: nothing to judge (not detected)
    wrong_isolation: bool = False  # the verdict is not empty and does not contain the fault
    gap_overlap: float = 0.0  # time of [start, end + grace) inside gaps [s]
    not_evaluable: bool = False  # not detected, and the window overlaps a gap: the miss is not a verdict
    alarm_after_end: float = 0.0  # how long after `end` an alarm of this fault still held [s]


@dataclass
class FalseAlarm:
    start: float
    end: float
    tests: str  # alarmed tests (union over the episode)


@dataclass
class Score:
    faults: list[FaultScore]
    false_alarms: list[FalseAlarm] = field(default_factory=list)
    steps: int = 0
    duration: float = 0.0
    gaps: list[Gap] = field(default_factory=list)
    grace: float = 0.0  # [s] after a fault's end that its alarms may take to clear

    @property
    def false_alarm_time(self) -> float:
        return sum(fa.end - fa.start for fa in self.false_alarms)

    @property
    def held_beyond_grace(self) -> list[FaultScore]:
        """The faults whose alarm held longer after their end than the grace (slow recovery)."""
        return [f for f in self.faults if f.alarm_after_end > self.grace]

    def to_json(self) -> dict[str, Any]:
        return {
            "steps": self.steps,
            "duration": self.duration,
            "faults": [asdict(f) for f in self.faults],
            "false_alarms": [asdict(f) for f in self.false_alarms],
            "false_alarm_count": len(self.false_alarms),
            "false_alarm_time": self.false_alarm_time,
            "grace": self.grace,
            "held_beyond_grace": [f.fault for f in self.held_beyond_grace],
            "gaps": [g.to_json() for g in self.gaps],
            "gap_count": {s: sum(1 for g in self.gaps if g.stream == s) for s in ("diagnosis", "sensors")},
        }


def _step_time(records: Sequence[DiagRecord]) -> float:
    if len(records) < 2:
        return 0.0
    gaps = sorted(b.t - a.t for a, b in pairwise(records))
    return gaps[len(gaps) // 2]


def score_run(
    records: Sequence[DiagRecord],
    windows: Sequence[FaultWindow],
    classes: TableClasses,
    grace: float = 1.0,
    gaps: Sequence[Gap] = (),
) -> Score:
    """Score `records` (time ordered) against `windows`; `grace` [s] after a fault's end still counts;
    `gaps`: silences of the diagnosis or sensor stream seen by the monitor."""
    recs = sorted(records, key=lambda r: r.t)
    dt = _step_time(recs)
    out = Score([], [], len(recs), (recs[-1].t - recs[0].t + dt) if recs else 0.0, list(gaps), grace)
    sensor_gaps = [g for g in gaps if g.stream == "sensors"]

    def in_sensor_gap(t: float) -> bool:
        return any(g.start < t < g.end for g in sensor_gaps)

    for w in windows:
        det = classes.detectable(w.fault)
        fs = FaultScore(w.fault, w.start, w.end, det, classes.fault_names(classes.class_of(w.fault)) if det else "-")
        # The grace period ends where the next fault (starting after this one ended) begins.
        until = min([w.end + grace, *(o.start for o in windows if o.start >= w.end)])
        fs.gap_overlap = overlap(w.start, until, gaps)
        inside = [r for r in recs if w.start <= r.t < until and not in_sensor_gap(r.t)]
        alarmed = [r for r in inside if r.alarm_mask != 0]
        if alarmed:
            fs.detected = True
            fs.detection_delay = alarmed[0].t - w.start
            votes = Counter(r.candidates for r in alarmed)
            verdict, _ = max(votes.items(), key=lambda kv: (kv[1], kv[0] != 0))
            fs.verdict = classes.fault_names(verdict)
            if det:  # a fault no test can see has no isolation to judge (alarms then come from elsewhere)
                cls, bit = classes.class_of(w.fault), classes.bit(w.fault)
                hits = [r for r in alarmed if isolates_fault(r.candidates, cls, bit)]
                fs.isolated_fraction = len(hits) / len(alarmed)
                fs.isolation_delay = hits[0].t - w.start if hits else None
                fs.isolation_correct = isolates_fault(verdict, cls, bit)
                fs.wrong_isolation = verdict != 0 and not verdict & bit
        else:
            fs.not_evaluable = fs.gap_overlap > 0.0
        out.faults.append(fs)

    def owner(t: float) -> int | None:
        """The window whose [start, end + grace) holds t (the latest started, where they overlap)."""
        held = [k for k, w in enumerate(windows) if w.start <= t < w.end + grace]
        return max(held, key=lambda k: windows[k].start) if held else None

    diag_gaps = [g for g in gaps if g.stream == "diagnosis"]
    episode: FalseAlarm | None = None
    tests = 0
    run_owner: int | None = None  # the window the current alarm run started or went on in
    run_tests = 0  # the tests that alarmed in that window during the run

    def close() -> None:
        """End the current alarm run (and its false alarm episode, if it is one)."""
        nonlocal episode, run_owner, run_tests
        if episode is not None:
            episode.tests = _test_list(tests, classes)
            out.false_alarms.append(episode)
        episode, run_owner, run_tests = None, None, 0

    prev_t = -math.inf
    for r in recs:
        if any(prev_t <= g.start and g.end <= r.t for g in diag_gaps):
            close()  # the ECU was down in between: nothing carries over
        prev_t = r.t
        if r.alarm_mask == 0:
            close()
            continue
        k = owner(r.t)
        if episode is None and k is not None:
            run_owner, run_tests = k, run_tests | r.alarm_mask
        elif episode is None and run_owner is not None and r.alarm_mask & ~run_tests == 0:
            k = run_owner  # the run goes on past the window with the window's tests: still the fault's
        else:
            if episode is None:
                episode, tests = FalseAlarm(r.t, r.t + dt, ""), 0
            run_owner, run_tests, k = None, 0, None
            episode.end = r.t + dt
            tests |= r.alarm_mask
        if k is not None:
            fs = out.faults[k]
            fs.alarm_after_end = max(fs.alarm_after_end, r.t + dt - windows[k].end)
    close()
    return out


def _test_list(mask: int, classes: TableClasses) -> str:
    return ",".join(classes.test_name(i) for i in range(32) if mask >> i & 1) or "-"
