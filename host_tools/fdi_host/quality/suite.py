"""Diagnosis quality suite: every fault of a diagnosis table x driving scenarios x fault sizes x step/ramp,
run offline through the C ECU core (fdi_host.ecu.bindings) on simulated CAN traffic, plus fault-free drives.

Per case (fault, scenario, shape, size): the fault starts at `onset_fraction` of the drive and stays; the
ECU replays the drive's CAN frames from `pre_onset_s` before the onset (enough for its warm-up). Measured:
  detected     a step after the onset with `detected` (any alarm) before the drive ends;
  delay        detection time minus the reference time: the onset for a step, the time the ramp reaches the
               stated minimal size for a ramp (goal < 300 ms);
  isolation    "exact": some step after the onset isolates exactly the structural isolability class of the
               fault (the table's iso_class, i.e. the faults with the same signature over the selected
               tests) and none isolates another class; the share of the steps after the detection with that
               exact isolation is reported too (`exact_share`);
               "wrong": some step after the onset isolates a class without the fault (goal: never);
               "not isolated": detected, but no step isolates a single class (several classes or none);
               "missed": never detected;
  false alarms any detection before the onset (fault-free part of the drive).
Fault-free drives: every scenario with successive noise seeds until `fault_free_minutes` of driving;
counted: detection events (rising edges of `detected`), alarm steps and isolation events.

Sensor faults (f1..f5, f22..f25) change only their own measured signal (the simulator's controller feeds
back true values), so their drives reuse the fault-free simulation of the same scenario and seed and only
recompute the measurement equations and the noise (same noise samples): `faulty_drive`, checked against a
full simulation in tests/host/test_quality_suite.py. Other faults are simulated.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fdi_host.can.dbc import RomoDatabase
from fdi_host.can.traffic import build_frames
from fdi_host.ecu.bindings import EcuResult, TableInfo, table_info
from fdi_host.ecu.offline import replay
from fdi_host.sim.faults import FAULT_IDS, FaultSpec
from fdi_host.sim.scenario import FAULT_SIZES_FILE, SCENARIOS, load_scenario
from fdi_host.sim.vehicle_sim import faulty_drive, simulate

DEFAULT_SIZES = FAULT_SIZES_FILE
DELAY_GOAL_S = 0.3


class QualityError(ValueError):
    """A suite configuration or data file that cannot be used."""


@dataclass(frozen=True)
class SuiteConfig:
    table: str = "kin"
    scenarios: tuple[str, ...] = SCENARIOS
    multipliers: tuple[float, ...] = (1.0, 2.0)
    shapes: tuple[str, ...] = ("step", "ramp")
    faults: tuple[str, ...] = ()  # default: every fault of the table
    ramp_s: float = 2.0  # a ramp reaches multiplier x size after ramp_s
    onset_fraction: float = 0.55
    pre_onset_s: float = 5.0
    fault_free_minutes: float = 30.0
    sizes_file: Path = DEFAULT_SIZES
    seed_offset: int = 0  # added to each scenario's seed for the fault cases

    def __post_init__(self) -> None:
        bad = [s for s in self.shapes if s not in ("step", "ramp")]
        if bad:
            raise QualityError(f"unknown fault shape(s) {bad}; use step, ramp")
        unknown = [f for f in self.faults if f not in FAULT_IDS]
        if unknown:
            raise QualityError(f"unknown fault(s) {unknown}; faults are f1..f25")
        if not self.multipliers or any(not m > 0 for m in self.multipliers):
            raise QualityError("multipliers must be positive")
        if not 0.0 < self.onset_fraction < 1.0:
            raise QualityError("onset_fraction must be in (0, 1)")


@dataclass(frozen=True)
class CaseResult:
    fault: str
    scenario: str
    shape: str
    multiplier: float
    magnitude: float
    onset: float
    t_ref: float  # reference time of the delay
    detected: bool
    delay_s: float | None
    outcome: str  # exact / wrong / not isolated / missed
    isolation_delay_s: float | None  # first exact isolation after the onset, from t_ref
    exact_share: float  # share of the steps after the detection that isolate exactly the fault's class
    final_candidates: tuple[str, ...]
    expected_class: tuple[str, ...]
    pre_onset_detections: int


@dataclass(frozen=True)
class FaultFreeResult:
    scenario: str
    seed: int
    duration_s: float
    detection_events: int
    alarm_steps: int
    isolation_events: int
    steps: int


@dataclass
class SuiteResult:
    config: SuiteConfig
    table: TableInfo
    sizes: dict[str, float]
    cases: list[CaseResult] = field(default_factory=list)
    fault_free: list[FaultFreeResult] = field(default_factory=list)
    not_in_table: list[str] = field(default_factory=list)


def load_fault_sizes(path: Path = DEFAULT_SIZES, tests: Sequence[str] = ()) -> dict[str, float]:
    """Minimal detectable size per fault id from a TOML file with a [sizes] table.

    With `tests` (the table's MSO labels, e.g. "MSO433"): where the file's `[per_test.<fault>]` tables (written
    by `fdi-tune fault-sizes` for the generated table) state sizes for some of those tests, the fault's
    minimal detectable size is the smallest of them (the size at which the most sensitive test reacts);
    [sizes] stays the value of faults without such a statement."""
    try:
        doc = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError as exc:
        raise QualityError(f"{path}: no such fault-size file") from exc
    except tomllib.TOMLDecodeError as exc:
        raise QualityError(f"{path}: not valid TOML: {exc}") from exc
    sizes = doc.get("sizes")
    if not isinstance(sizes, dict):
        raise QualityError(f"{path}: expected a [sizes] table (fault id = size)")
    out: dict[str, float] = {}
    for fid, v in sizes.items():
        if fid not in FAULT_IDS:
            raise QualityError(f"{path}: unknown fault {fid!r} (faults are f1..f25)")
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) or v <= 0:
            raise QualityError(f"{path}: size of {fid} must be a positive number, got {v!r}")
        out[fid] = float(v)
    per_test = doc.get("per_test", {})
    for fid, row in per_test.items() if tests else ():
        stated = [float(v) for t, v in row.items() if t in tests and isinstance(v, int | float) and v > 0]
        if fid in FAULT_IDS and stated:
            out[fid] = min(stated)
    return out


def _labels(mask: int) -> tuple[str, ...]:
    return tuple(f"f{j + 1}" for j in range(32) if mask >> j & 1)


def evaluate_case(
    results: Sequence[EcuResult], spec: FaultSpec, t_ref: float, expected_class: int
) -> tuple[bool, float | None, str, float | None, float, tuple[str, ...], int]:
    """(detected, delay, outcome, isolation delay, exact share, final candidates, detections before onset)."""
    j = FAULT_IDS.index(spec.fault)
    pre = 0
    prev = False
    detect_t: float | None = None
    iso_t: float | None = None
    wrong = False
    n_after = n_exact = 0
    for r in results:
        t = r.t_us * 1e-6
        if t < spec.onset:
            pre += int(r.detected and not prev)
            prev = r.detected
            continue
        if r.detected and detect_t is None:
            detect_t = t
        exact = r.isolated and r.class_mask == expected_class
        if detect_t is not None:
            n_after += 1
            n_exact += int(exact)
        if r.isolated and not r.class_mask >> j & 1:
            wrong = True
        if exact and iso_t is None:
            iso_t = t
    last = results[-1] if results else None
    if detect_t is None:
        outcome = "missed"
    elif wrong:
        outcome = "wrong"
    elif iso_t is not None:
        outcome = "exact"
    else:
        outcome = "not isolated"
    delay = None if detect_t is None else max(0.0, detect_t - t_ref)
    iso_delay = None if iso_t is None else max(0.0, iso_t - t_ref)
    final = _labels(last.candidates) if last is not None else ()
    share = n_exact / n_after if n_after else 0.0
    return detect_t is not None, delay, outcome, iso_delay, share, final, pre


def fault_cases(cfg: SuiteConfig, table: TableInfo, sizes: dict[str, float]) -> tuple[list[str], list[str]]:
    """(faults the suite runs, faults skipped because no test of the table with an on-board generator is
    sensitive to them)."""
    wanted = list(cfg.faults) or list(FAULT_IDS[: table.n_faults])
    covered = 0
    for m, has_gen in zip(table.test_fault_masks, table.has_generator, strict=True):
        covered |= m if has_gen else 0
    run, skipped = [], []
    for fid in wanted:
        j = FAULT_IDS.index(fid)
        if j >= table.n_faults or not covered >> j & 1:
            skipped.append(fid)
        else:
            if fid not in sizes:
                raise QualityError(f"no minimal size for {fid} in {cfg.sizes_file}")
            run.append(fid)
    return run, skipped


def run_suite(cfg: SuiteConfig, progress: Callable[[str], None] | None = None) -> SuiteResult:
    """Run every case and the fault-free drives of `cfg`; `progress(text)` after each unit of work."""
    table = table_info(cfg.table)
    sizes = load_fault_sizes(cfg.sizes_file, [f"MSO{m}" for m in table.mso_ids] if cfg.table != "kin" else ())
    faults, skipped = fault_cases(cfg, table, sizes)
    result = SuiteResult(cfg, table, sizes, not_in_table=skipped)
    db = RomoDatabase()
    for scen_name in cfg.scenarios:
        scen = load_scenario(scen_name)
        base = simulate(scen, [], seed=scen.seed + cfg.seed_offset)
        duration = float(base.t[-1])
        onset = round(cfg.onset_fraction * duration, 3)
        for fid in faults:
            j = FAULT_IDS.index(fid)
            for shape in cfg.shapes:
                for mult in cfg.multipliers:
                    mag = sizes[fid] * mult
                    if shape == "step":
                        spec = FaultSpec(fid, onset, mag)
                        t_ref = onset
                    else:
                        spec = FaultSpec(fid, onset, mag, shape="ramp", ramp=cfg.ramp_s)
                        t_ref = onset + cfg.ramp_s / mult  # the ramp reaches the minimal size
                    frames = build_frames(faulty_drive(base, spec), db)
                    res = replay(cfg.table, frames, t_start=max(0.0, onset - cfg.pre_onset_s))
                    det, delay, outcome, iso_delay, share, final, pre = evaluate_case(
                        res, spec, t_ref, table.iso_class[j])
                    result.cases.append(CaseResult(
                        fault=fid, scenario=scen_name, shape=shape, multiplier=mult, magnitude=mag, onset=onset,
                        t_ref=t_ref, detected=det, delay_s=delay, outcome=outcome, isolation_delay_s=iso_delay,
                        exact_share=share,
                        final_candidates=final, expected_class=_labels(table.iso_class[j]),
                        pre_onset_detections=pre,
                    ))
                    if progress is not None:
                        progress(f"{fid} {scen_name} {shape} x{mult:g}: {outcome}")
    result.fault_free.extend(fault_free_drives(cfg, db, progress))
    return result


def _fault_free_schedule(cfg: SuiteConfig) -> Iterator[tuple[str, int]]:
    """(scenario, seed) pairs, round robin over the scenarios with growing seeds, without end."""
    k = 0
    while True:
        for name in cfg.scenarios:
            yield name, 1000 + 17 * k + cfg.seed_offset
        k += 1


def fault_free_drives(
    cfg: SuiteConfig, db: RomoDatabase, progress: Callable[[str], None] | None = None
) -> list[FaultFreeResult]:
    out: list[FaultFreeResult] = []
    total = 0.0
    for name, seed in _fault_free_schedule(cfg):
        if total >= cfg.fault_free_minutes * 60.0:
            break
        scen = load_scenario(name)
        drive = simulate(scen, [], seed=seed)
        res = replay(cfg.table, build_frames(drive, db))
        ev = iso = 0
        prev_d = prev_i = False
        for r in res:
            ev += int(r.detected and not prev_d)
            iso += int(r.isolated and not prev_i)
            prev_d, prev_i = r.detected, r.isolated
        dur = float(drive.t[-1])
        total += dur
        out.append(FaultFreeResult(name, seed, dur, ev, sum(1 for r in res if r.alarm_mask), iso, len(res)))
        if progress is not None:
            progress(f"fault-free {name} seed {seed}: {ev} detections ({total / 60:.1f} min)")
    return out


def summary_rows(result: SuiteResult) -> list[dict[str, object]]:
    """One row per fault: detection rate, delays, isolation outcomes and which goals are met."""
    rows: list[dict[str, object]] = []
    for fid in dict.fromkeys(c.fault for c in result.cases):
        cs = [c for c in result.cases if c.fault == fid]
        det = [c for c in cs if c.detected]
        step_delays = [c.delay_s for c in det if c.shape == "step" and c.delay_s is not None]
        ramp_delays = [c.delay_s for c in det if c.shape == "ramp" and c.delay_s is not None]
        outcomes = {o: sum(1 for c in cs if c.outcome == o) for o in ("exact", "wrong", "not isolated", "missed")}
        all_delays = step_delays + ramp_delays
        iso_delays = [c.isolation_delay_s for c in cs if c.isolation_delay_s is not None]
        rows.append({
            "fault": fid,
            "size": result.sizes[fid],
            "cases": len(cs),
            "detected": len(det),
            "detection_rate": len(det) / len(cs) if cs else 0.0,
            "delay_step_median_s": float(np.median(step_delays)) if step_delays else None,
            "delay_step_max_s": max(step_delays) if step_delays else None,
            "delay_ramp_median_s": float(np.median(ramp_delays)) if ramp_delays else None,
            "delay_ramp_max_s": max(ramp_delays) if ramp_delays else None,
            "expected_class": list(cs[0].expected_class) if cs else [],
            "isolation_delay_median_s": float(np.median(iso_delays)) if iso_delays else None,
            "exact_share_mean": float(np.mean([c.exact_share for c in cs])) if cs else 0.0,
            **{f"isolation_{k.replace(' ', '_')}": v for k, v in outcomes.items()},
            "pre_onset_detections": sum(c.pre_onset_detections for c in cs),
            "goal_detection": len(det) == len(cs),
            "goal_delay": bool(all_delays) and len(det) == len(cs) and max(all_delays) < DELAY_GOAL_S,
            "goal_isolation_exact": outcomes["exact"] == len(cs),
            "goal_never_wrong": outcomes["wrong"] == 0,
        })
    return rows
