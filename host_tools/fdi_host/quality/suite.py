"""Diagnosis quality suite: every fault of a diagnosis table x driving scenarios x noise seeds (x sizes x
step/ramp), run offline through the C ECU core (fdi_host.ecu.bindings) on simulated CAN traffic, plus
fault-free drives.

The fault sizes are the engineering requirement (the [requirement] table of the fault-size file), never what
the tests happen to see. Per case (fault, scenario, seed, shape, multiple of the required size): the fault
starts at `onset_fraction` of the drive and stays; the ECU replays the drive's CAN frames from the drive's start (an
ECU runs from the ignition on: its on-line estimators learn the vehicle before the fault), or from `pre_onset_s`
before the onset when that is set. Measured:
  detected     a step after the onset with `detected` (any alarm) before the drive ends;
  delay        detection time minus the reference time: the onset for a step, the time the ramp reaches the
               required size for a ramp; goal: within DELAY_GOAL_S (300 ms);
  isolation    "exact": some step after the onset isolates the fault to exactly its structural isolability
               class (the table's iso_class, method B over the tests on board: the candidates hold the fault
               and lie within its class, `isolates_fault`) and none isolates another class or exonerates the
               fault; goal: the first exact isolation within ISOLATION_GOAL_S (1 s) of the detection;
               "wrong": some step after the onset isolates a class without the fault, or isolates the
               fault's class with candidates that do not hold the fault (goal: never);
               "not isolated": detected, but no step isolates a single class (several classes or none);
               "missed": never detected;
  false alarms any detection before the onset (fault-free part of the drive).
Per scenario a fault meets a goal when every one of its cases there (all seeds) does. Fault-free drives:
every scenario with successive noise seeds that no calibration or fault case uses until
`fault_free_minutes` of driving; counted: detection events (rising edges of `detected`), alarm steps and
isolation events.

Sensor faults (f1..f5, f22..f25) change only their own measured signal (the simulator's controller feeds
back true values), so their drives reuse the fault-free simulation of the same scenario and seed and only
recompute the measurement equations and the noise (same noise samples): `faulty_drive`, checked against a
full simulation in tests/host/test_quality_suite.py. Other faults are simulated.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fdi_analysis.export.fault_sizes import FaultSizes, FaultSizesError
from fdi_host.can.dbc import CanDatabase
from fdi_host.can.traffic import build_frames
from fdi_host.ecu.bindings import EcuResult, TableInfo, table_info
from fdi_host.ecu.offline import replay
from fdi_host.ecu.records import isolates_fault
from fdi_host.errors import FdiHostError
from fdi_host.sim.faults import FAULT_IDS, FaultSpec
from fdi_host.sim.scenario import FAULT_SIZES_FILE, SCENARIOS, load_scenario
from fdi_host.sim.vehicle_sim import SimResult, faulty_drive, simulate

DEFAULT_SIZES = FAULT_SIZES_FILE
DELAY_GOAL_S = 0.3  # detection within 300 ms of the onset
ISOLATION_GOAL_S = 1.0  # isolation to exactly the structural class within 1 s of the detection
DETECTION_GOAL_FAULTS = 24  # of 25, in every scenario
ISOLATION_GOAL_FAULTS = 23  # of 25, in every scenario
# Noise seeds of the fault cases: none of the calibration and the screening (each scenario's own, 1001-1012), the
# fault-size sweep (777, 778 and + 100, 200, 300) or the fault-free drives (1000 + 17 k) uses them.
CASE_SEEDS: tuple[int, ...] = (2001, 2002, 2003)
SHAPES = ("step", "ramp")  # fault shapes of the cases (a ramp reaches its size after SuiteConfig.ramp_s)


class QualityError(FdiHostError, ValueError):
    """A suite configuration or data file that cannot be used."""


@dataclass(frozen=True)
class SuiteConfig:
    table: str = "kin"
    scenarios: tuple[str, ...] = SCENARIOS
    multipliers: tuple[float, ...] = (1.0,)
    shapes: tuple[str, ...] = ("step",)
    seeds: tuple[int, ...] = CASE_SEEDS
    faults: tuple[str, ...] = ()  # default: every fault of the table
    ramp_s: float = 2.0  # a ramp reaches multiplier x size after ramp_s
    onset_fraction: float = 0.55
    pre_onset_s: float | None = None  # the replay's start before the onset; None: the drive's start
    fault_free_minutes: float = 30.0
    sizes_file: Path = DEFAULT_SIZES
    ecu: tuple[tuple[str, float | int | str], ...] = ()  # ECU settings other than the defaults (Ecu's overrides)

    def __post_init__(self) -> None:
        for shape in self.shapes:
            check_shape(shape)
        unknown = [f for f in self.faults if f not in FAULT_IDS]
        if unknown:
            raise QualityError(f"unknown fault(s) {unknown}; faults are f1..f25")
        if not self.multipliers or any(not m > 0 for m in self.multipliers):
            raise QualityError("multipliers must be positive")
        if not self.seeds:
            raise QualityError("at least one noise seed")
        if not 0.0 < self.onset_fraction < 1.0:
            raise QualityError("onset_fraction must be in (0, 1)")


@dataclass(frozen=True)
class CaseResult:
    fault: str
    scenario: str
    seed: int
    shape: str
    multiplier: float
    magnitude: float
    onset: float
    t_ref: float  # reference time of the delay
    detected: bool
    delay_s: float | None
    outcome: str  # exact / wrong / not isolated / missed
    isolation_delay_s: float | None  # first exact isolation after the onset, from the detection
    exact_share: float  # share of the steps after the detection that isolate exactly the fault's class
    final_candidates: tuple[str, ...]
    expected_class: tuple[str, ...]
    pre_onset_detections: int

    @property
    def detected_in_time(self) -> bool:
        return self.delay_s is not None and self.delay_s <= DELAY_GOAL_S

    @property
    def isolated_in_time(self) -> bool:
        return (self.outcome == "exact" and self.isolation_delay_s is not None
                and self.isolation_delay_s <= ISOLATION_GOAL_S)


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


def load_fault_sizes(path: Path = DEFAULT_SIZES) -> dict[str, float]:
    """The required size per fault id: the [requirement] table of a fault-size file (the engineering
    requirement, not what the tests happen to detect)."""
    try:
        sizes = FaultSizes.load(Path(path))
        unknown = [f for f in sizes.requirement if f not in FAULT_IDS]
        if unknown:
            raise FaultSizesError(f"{path}: unknown fault {unknown[0]!r} (faults are f1..f25)")
    except FaultSizesError as exc:
        raise QualityError(str(exc)) from exc
    return dict(sizes.requirement)


def _labels(mask: int, faults: Sequence[str]) -> tuple[str, ...]:
    return tuple(f for j, f in enumerate(faults) if mask >> j & 1)


def evaluate_case(
    results: Sequence[EcuResult], spec: FaultSpec, t_ref: float, expected_class: int,
    faults: Sequence[str] = FAULT_IDS, sim_faults: Sequence[str] = FAULT_IDS,
) -> tuple[bool, float | None, str, float | None, float, tuple[str, ...], int]:
    """(detected, delay from t_ref, outcome, isolation delay from the detection, exact share, final candidates,
    detections before onset); the final candidates named by `faults` (the table's, bit j = faults[j]; by default the
    simulator's, FAULT_IDS); `spec.fault` is the simulator's name, bit j of `sim_faults` (ROMO's FAULT_IDS; a vehicle
    on the generic simulator: its model's faults, the table's order)."""
    j = list(sim_faults).index(spec.fault)
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
        exact = isolates_fault(r.candidates, expected_class, 1 << j)
        if detect_t is not None:
            n_after += 1
            n_exact += int(exact)
        if r.isolated and not r.candidates >> j & 1:
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
    iso_delay = None if iso_t is None or detect_t is None else max(0.0, iso_t - detect_t)
    final = _labels(last.candidates, faults) if last is not None else ()
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
                raise QualityError(f"no required size for {fid} in {cfg.sizes_file} [requirement]")
            run.append(fid)
    return run, skipped


def case_onset(cfg: SuiteConfig, base: SimResult) -> float:
    """The fault onset of a case on the fault-free drive `base`."""
    return round(cfg.onset_fraction * float(base.t[-1]), 3)


def ecu_settings(cfg: SuiteConfig) -> dict[str, Any]:
    """The ECU's options other than the defaults (keyword arguments of Ecu and of the replays)."""
    return dict(cfg.ecu)


def replay_start(cfg: SuiteConfig, onset: float) -> float:
    """Where a case's replay starts: the drive's start, or pre_onset_s before the fault onset."""
    return 0.0 if cfg.pre_onset_s is None else max(0.0, onset - cfg.pre_onset_s)


def replay_case(cfg: SuiteConfig, drive: SimResult, onset: float, db: CanDatabase) -> list[EcuResult]:
    """The ECU's steps of one case's faulty drive, replayed from `replay_start`."""
    return replay(cfg.table, build_frames(drive, db), t_start=replay_start(cfg, onset), **ecu_settings(cfg))


def check_shape(shape: str) -> None:
    """QualityError unless `shape` is one of SHAPES."""
    if shape not in SHAPES:
        raise QualityError(f"unknown fault shape {shape!r}; use {', '.join(SHAPES)}")


def case_spec(cfg: SuiteConfig, fault: str, onset: float, size: float, shape: str, multiplier: float
              ) -> tuple[FaultSpec, float]:
    """The fault of one case (`size` x `multiplier`, a step or a ramp over cfg.ramp_s) and its reference time: the
    onset for a step, the time a ramp reaches the required size."""
    check_shape(shape)
    if shape == "step":
        return FaultSpec(fault, onset, size * multiplier), onset
    return (FaultSpec(fault, onset, size * multiplier, shape="ramp", ramp=cfg.ramp_s),
            onset + cfg.ramp_s / multiplier)


def run_suite(cfg: SuiteConfig, progress: Callable[[str], None] | None = None) -> SuiteResult:
    """Run every case and the fault-free drives of `cfg`; `progress(text)` after each unit of work."""
    table = table_info(cfg.table)
    sizes = load_fault_sizes(cfg.sizes_file)
    faults, skipped = fault_cases(cfg, table, sizes)
    result = SuiteResult(cfg, table, sizes, not_in_table=skipped)
    db = CanDatabase()
    for scen_name in cfg.scenarios:
        scen = load_scenario(scen_name)
        for seed in cfg.seeds:
            base = simulate(scen, [], seed=seed)
            onset = case_onset(cfg, base)
            for fid in faults:
                j = FAULT_IDS.index(fid)
                for shape in cfg.shapes:
                    for mult in cfg.multipliers:
                        mag = sizes[fid] * mult
                        spec, t_ref = case_spec(cfg, fid, onset, sizes[fid], shape, mult)
                        res = replay_case(cfg, faulty_drive(base, spec), onset, db)
                        det, delay, outcome, iso_delay, share, final, pre = evaluate_case(
                            res, spec, t_ref, table.iso_class[j], table.faults)
                        result.cases.append(CaseResult(
                            fault=fid, scenario=scen_name, seed=seed, shape=shape, multiplier=mult, magnitude=mag,
                            onset=onset, t_ref=t_ref, detected=det, delay_s=delay, outcome=outcome,
                            isolation_delay_s=iso_delay, exact_share=share, final_candidates=final,
                            expected_class=_labels(table.iso_class[j], table.faults), pre_onset_detections=pre,
                        ))
                        if progress is not None:
                            progress(f"{fid} {scen_name} seed {seed} {shape} x{mult:g}: {outcome}")
    result.fault_free.extend(fault_free_drives(cfg, db, progress))
    return result


def _fault_free_schedule(cfg: SuiteConfig) -> Iterator[tuple[str, int]]:
    """(scenario, seed) pairs, round robin over the scenarios with growing seeds, without end."""
    k = 0
    while True:
        for name in cfg.scenarios:
            yield name, 1000 + 17 * k
        k += 1


def fault_free_drives(
    cfg: SuiteConfig, db: CanDatabase, progress: Callable[[str], None] | None = None
) -> list[FaultFreeResult]:
    out: list[FaultFreeResult] = []
    total = 0.0
    for name, seed in _fault_free_schedule(cfg):
        if total >= cfg.fault_free_minutes * 60.0:
            break
        scen = load_scenario(name)
        drive = simulate(scen, [], seed=seed)
        res = replay(cfg.table, build_frames(drive, db), **ecu_settings(cfg))
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
    """One row per fault over all its cases: detection, delays, isolation outcomes."""
    rows: list[dict[str, object]] = []
    for fid in dict.fromkeys(c.fault for c in result.cases):
        cs = [c for c in result.cases if c.fault == fid]
        det = [c for c in cs if c.detected]
        delays = [c.delay_s for c in det if c.delay_s is not None]
        iso_delays = [c.isolation_delay_s for c in cs if c.isolation_delay_s is not None]
        outcomes = {o: sum(1 for c in cs if c.outcome == o) for o in ("exact", "wrong", "not isolated", "missed")}
        rows.append({
            "fault": fid,
            "size": result.sizes[fid],
            "cases": len(cs),
            "detected": len(det),
            "detected_in_time": sum(c.detected_in_time for c in cs),
            "delay_median_s": float(np.median(delays)) if delays else None,
            "delay_max_s": max(delays) if delays else None,
            "expected_class": list(cs[0].expected_class) if cs else [],
            "isolated_in_time": sum(c.isolated_in_time for c in cs),
            "isolation_delay_median_s": float(np.median(iso_delays)) if iso_delays else None,
            "isolation_delay_max_s": max(iso_delays) if iso_delays else None,
            "exact_share_mean": float(np.mean([c.exact_share for c in cs])) if cs else 0.0,
            **{f"isolation_{k.replace(' ', '_')}": v for k, v in outcomes.items()},
            "pre_onset_detections": sum(c.pre_onset_detections for c in cs),
        })
    return rows


def scenario_goals(result: SuiteResult) -> list[dict[str, object]]:
    """Per scenario: the faults detected within 300 ms and isolated exactly within 1 s of the detection in
    every case (all seeds), the faults with a wrong class, and whether the goals hold there."""
    out: list[dict[str, object]] = []
    faults = list(dict.fromkeys(c.fault for c in result.cases))
    for sc in dict.fromkeys(c.scenario for c in result.cases):
        by_fault = {f: [c for c in result.cases if c.scenario == sc and c.fault == f] for f in faults}
        detected = [f for f, cs in by_fault.items() if cs and all(c.detected_in_time for c in cs)]
        isolated = [f for f, cs in by_fault.items() if cs and all(c.isolated_in_time for c in cs)]
        wrong = [f for f, cs in by_fault.items() if any(c.outcome == "wrong" for c in cs)]
        out.append({
            "scenario": sc,
            "faults": len(faults),
            "detected_in_time": len(detected),
            "isolated_in_time": len(isolated),
            "not_detected_in_time": [f for f in faults if f not in detected],
            "not_isolated_in_time": [f for f in faults if f not in isolated],
            "wrong_class": wrong,
            "goal_detection": len(detected) >= min(DETECTION_GOAL_FAULTS, len(faults)),
            "goal_isolation": len(isolated) >= min(ISOLATION_GOAL_FAULTS, len(faults)),
            "goal_never_wrong": not wrong,
        })
    return out
