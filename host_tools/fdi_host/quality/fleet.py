"""The diagnosis quality suite on a fleet of truth-plant vehicles: faults x scenarios x vehicles through the C ECU.

The diagnosis is scored on vehicles that are not its model: the truth plant (`fdi_host.sim.truth_sim`) drives
vehicles drawn from the envelope (`fdi_host.sim.vehicle_envelope`), the evaluation vehicles of the fleet plan
(`fdi_host.quality.fleet_plan`: no calibration uses their vehicles or noise seeds; the suite refuses others).

One task is one vehicle x scenario: its fault-free drive (with a snapshot at the fault onset, `onset_fraction` of
the drive), replayed whole through the ECU (false alarms; each false detection is kept with the tests it accused, so
the report says which test alarms where), then every fault case at the onset: the faulty drive
shares the fault-free part and is simulated from the onset to `post_onset_s` after it (sensor faults only
recompute the sensors), and the ECU replays it from the drive's start (an ECU runs from the ignition on: its on-line
estimators learn the vehicle before the fault; `pre_onset_s` replays only that long before the onset instead). A
case is scored as the model
plant's suite does (`fdi_host.quality.suite.evaluate_case`), with one more outcome: "masked" when the ECU
detected something before the onset (a false alarm in the replayed window): the diagnosis was in alarm already,
so the case is neither detected nor isolated. Goals of the truth-plant suite (issue 44): detected within 500 ms
of the onset, isolated exactly within 1 s of the detection, per fault on at least 95 % of the vehicles (a vehicle
counts when every scenario's case meets the goal). `fault_free_repetitions` > 1 drives each truth-plant vehicle and
scenario fault-free again on the noise seeds of the further repetitions of the fleet plan (more fault-free hours for
the false-alarm goal: >= 5 h; the fault cases use repetition 0).

Minimum detectable fault: the smallest size on the grid SWEEP_GRID x the required size (up to the fault's
physical limit) that is detected within 500 ms on at least 95 % of the vehicles, searched from the required size
down or up, one grid step per round for all faults at once. A fault whose cases are masked on more than 5 % of
the vehicles has none (no size can reach 95 %): the report says so and why.

The model plant's figures of the same faults, scenarios and goals (its noise seed CASE_SEEDS[0], the road ignored:
the model has none) stand beside them, so that the cost of model error shows. Tasks run on local processes by
default, or on a Dask cluster (`fdi_host.executors`).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from fdi_analysis.export.fault_sizes import FaultSizes, FaultSizesError
from fdi_host.can.dbc import CanDatabase
from fdi_host.can.traffic import build_frames
from fdi_host.ecu.bindings import EcuResult, table_info
from fdi_host.ecu.offline import replay
from fdi_host.executors import ExecutorError, run_tasks
from fdi_host.quality.fleet_plan import FIRST_EVALUATION_VEHICLE, check_evaluation_fleet, noise_seed
from fdi_host.quality.suite import CASE_SEEDS, DEFAULT_SIZES, QualityError, evaluate_case, load_fault_sizes
from fdi_host.sim.faults import FAULT_IDS, FaultSpec
from fdi_host.sim.scenario import FLEET_SCENARIOS, load_scenario
from fdi_host.sim.truth_sim import faulty_truth_drive, simulate_truth
from fdi_host.sim.vehicle_envelope import draw_vehicle
from fdi_host.sim.vehicle_sim import SimResult, faulty_drive, simulate
from fdi_host.tuning.seeds import REPETITIONS

FLEET_DELAY_GOAL_S = 0.5  # detection within 500 ms of the onset
FLEET_ISOLATION_GOAL_S = 1.0  # exact isolation within 1 s of the detection
VEHICLE_SHARE_GOAL = 0.95  # on at least 95 % of the vehicles
SWEEP_GRID: tuple[float, ...] = (0.1, 0.2, 0.3, 0.5, 0.7, 1.0, 1.5, 2.0, 3.0, 5.0, 7.0, 10.0)  # x required size
TRUTH = "truth plant"
MODEL = "model plant"


@dataclass(frozen=True)
class FleetConfig:
    table: str = "romo"
    vehicles: int = 25
    first_vehicle: int = FIRST_EVALUATION_VEHICLE
    scenarios: tuple[str, ...] = FLEET_SCENARIOS
    faults: tuple[str, ...] = ()  # default: every fault of the table's tests
    onset_fraction: float = 0.55
    pre_onset_s: float | None = None  # the replay's start before the onset; None: the drive's start
    post_onset_s: float = 2.0
    sweep: bool = True  # search the minimum detectable fault
    fault_free_repetitions: int = 1  # fault-free drives per truth-plant vehicle and scenario (noise seeds of the plan)
    model_plant_seeds: tuple[int, ...] = CASE_SEEDS[:1]  # () leaves the model plant's figures out
    sizes_file: Path = DEFAULT_SIZES
    ecu: tuple[tuple[str, float | int | str], ...] = ()
    workers: int | None = None  # local processes (None: one per core)
    scheduler: str | None = None  # a Dask scheduler instead

    def __post_init__(self) -> None:
        if self.vehicles < 1:
            raise QualityError("a fleet has at least one vehicle")
        unknown = [s for s in self.scenarios if s not in FLEET_SCENARIOS]
        if unknown:
            raise QualityError(f"unknown scenarios {unknown}; the fleet drives {', '.join(FLEET_SCENARIOS)}")
        bad = [f for f in self.faults if f not in FAULT_IDS]
        if bad:
            raise QualityError(f"unknown fault(s) {bad}; faults are f1..f25")
        if not 1 <= self.fault_free_repetitions <= REPETITIONS:
            raise QualityError(f"fault-free repetitions: 1 .. {REPETITIONS} (the noise seeds the fleet plan keeps "
                               "for each vehicle and scenario)")
        if not 0.0 < self.onset_fraction < 1.0 or (self.pre_onset_s is not None and self.pre_onset_s <= 0.0) \
                or self.post_onset_s <= FLEET_DELAY_GOAL_S:
            raise QualityError("onset_fraction in (0, 1), pre_onset_s > 0, post_onset_s > the 500 ms goal")
        try:
            check_evaluation_fleet(self.vehicle_seeds, self.fault_free_repetitions)
        except ValueError as exc:
            raise QualityError(str(exc)) from exc

    @property
    def vehicle_seeds(self) -> tuple[int, ...]:
        return tuple(range(self.first_vehicle, self.first_vehicle + self.vehicles))


@dataclass(frozen=True)
class FleetCase:
    plant: str  # TRUTH or MODEL
    vehicle: int  # truth plant: the vehicle's seed; model plant: the noise seed
    scenario: str
    fault: str
    multiplier: float
    magnitude: float
    onset: float
    delay_s: float | None
    outcome: str  # exact / wrong / not isolated / missed / masked
    isolation_delay_s: float | None
    pre_onset_detections: int

    @property
    def detected_in_time(self) -> bool:
        return self.outcome != "masked" and self.delay_s is not None and self.delay_s <= FLEET_DELAY_GOAL_S

    @property
    def isolated_in_time(self) -> bool:
        return (self.detected_in_time and self.outcome == "exact" and self.isolation_delay_s is not None
                and self.isolation_delay_s <= FLEET_ISOLATION_GOAL_S)


@dataclass(frozen=True)
class FalseDetection:
    """A detection in a fault-free drive: when, and the tests accused at its first step."""

    t_s: float  # since the drive's start
    tests: tuple[str, ...]  # the accused tests' names (MSO<id>)


@dataclass(frozen=True)
class FaultFreeDrive:
    plant: str
    vehicle: int
    scenario: str
    seed: int
    duration_s: float
    detection_events: int
    isolation_events: int
    alarm_steps: int
    steps: int
    repetition: int = 0
    detections: tuple[FalseDetection, ...] = ()


@dataclass(frozen=True)
class Task:
    """One vehicle (or model-plant seed) x scenario: its fault-free drive and the fault cases (fault, x size)."""

    plant: str
    vehicle: int
    scenario: str
    cases: tuple[tuple[str, float], ...]
    fault_free: bool
    config: FleetConfig
    sizes: tuple[tuple[str, float], ...]
    repetition: int = 0  # the fleet plan's noise-seed repetition of the drive (fault cases: 0)


@dataclass(frozen=True)
class TaskResult:
    task: Task
    cases: tuple[FleetCase, ...] = ()
    fault_free: FaultFreeDrive | None = None
    wall_s: float = 0.0
    error: str = ""


@dataclass
class FleetResult:
    config: FleetConfig
    table: str
    sizes: dict[str, float]
    limits: dict[str, float]
    faults: list[str]
    not_in_table: list[str]
    cases: list[FleetCase] = field(default_factory=list)  # at the required size
    sweep_cases: list[FleetCase] = field(default_factory=list)  # the minimum-detectable-fault search
    fault_free: list[FaultFreeDrive] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    executor: str = ""
    wall_s: float = 0.0
    mdf: dict[str, dict[str, Any]] = field(default_factory=dict)  # fault -> search outcome


def _events(results: Sequence[EcuResult], dt: float) -> tuple[tuple[FalseDetection, ...], int, int]:
    """(each detection with its time and the tests it accused, isolation events, alarm steps) of a replay."""
    detections = []
    iso = 0
    prev_d = prev_i = False
    for r in results:
        if r.detected and not prev_d:
            accused = r.accused_mask | r.alarm_mask
            names = tuple(n.split(":")[0] for i, n in enumerate(r.test_names) if accused >> i & 1)
            detections.append(FalseDetection(round(r.step * dt, 3), names))
        iso += int(r.isolated and not prev_i)
        prev_d, prev_i = r.detected, r.isolated
    return tuple(detections), iso, sum(1 for r in results if r.alarm_mask)


def _base_drive(task: Task, onset: float) -> SimResult:
    scen = load_scenario(task.scenario)
    if task.plant == TRUTH:
        return simulate_truth(scen, [], vehicle=draw_vehicle(task.vehicle),
                              seed=noise_seed(task.vehicle, task.scenario, task.repetition), snapshots=[onset])
    return simulate(scen, [], seed=task.vehicle)


def _faulty(task: Task, base: SimResult, spec: FaultSpec, until: float) -> SimResult:
    if task.plant == TRUTH:
        return faulty_truth_drive(base, spec, until)
    return faulty_drive(base, spec, until)


def run_task(task: Task) -> TaskResult:
    """The fault-free drive and the fault cases of one task (see the module's docstring)."""
    t0 = time.perf_counter()
    cfg = task.config
    sizes = dict(task.sizes)
    scen = load_scenario(task.scenario)
    onset = round(cfg.onset_fraction * scen.duration, 3)
    base = _base_drive(task, onset)
    db = CanDatabase()
    ecu: dict[str, Any] = dict(cfg.ecu)
    t_start = 0.0 if cfg.pre_onset_s is None else max(0.0, onset - cfg.pre_onset_s)
    base_frames = build_frames(base, db, t_from=0.0 if task.fault_free else t_start)
    info = table_info(cfg.table)
    ff = None
    if task.fault_free:
        detections, iso, alarms = _events(res := replay(cfg.table, base_frames, **ecu), info.dt)
        ff = FaultFreeDrive(task.plant, task.vehicle, task.scenario, base.seed, float(base.t[-1]), len(detections),
                            iso, alarms, len(res), task.repetition, detections)
    # The frames before the onset are the fault-free drive's (sensors and noise are causal): encoded once.
    before = [f for f in base_frames if t_start <= f.timestamp < onset]
    end = onset + cfg.post_onset_s
    cases = []
    for fault, mult in task.cases:
        spec = FaultSpec(fault, onset, sizes[fault] * mult)
        drive = _faulty(task, base, spec, end)
        frames = before + [f for f in build_frames(drive, db, t_from=onset) if f.timestamp <= end]
        res = replay(cfg.table, frames, t_start=t_start, **ecu)
        _, delay, outcome, iso_delay, _, _, pre = evaluate_case(res, spec, onset, info.iso_class[spec.index])
        cases.append(FleetCase(task.plant, task.vehicle, task.scenario, fault, mult, spec.magnitude, onset, delay,
                               "masked" if pre else outcome, iso_delay, pre))
    return TaskResult(task, tuple(cases), ff, time.perf_counter() - t0)


def _failed(task: Task, exc: BaseException) -> TaskResult:
    return TaskResult(task, error=f"{task.plant} {task.vehicle} {task.scenario}: {type(exc).__name__}: "
                                  f"{' '.join(str(exc).split())}")


def _faults(cfg: FleetConfig, sizes: dict[str, float]) -> tuple[list[str], list[str]]:
    """(faults run, faults skipped because no test with an on-board generator is sensitive to them)."""
    info = table_info(cfg.table)
    covered = 0
    for m, has_gen in zip(info.test_fault_masks, info.has_generator, strict=True):
        covered |= m if has_gen else 0
    run, skipped = [], []
    for fid in cfg.faults or FAULT_IDS[: info.n_faults]:
        j = FAULT_IDS.index(fid)
        if j >= info.n_faults or not covered >> j & 1:
            skipped.append(fid)
            continue
        if fid not in sizes:
            raise QualityError(f"no required size for {fid} in {cfg.sizes_file} [requirement]")
        run.append(fid)
    return run, skipped


def _run(tasks: list[Task], cfg: FleetConfig, out: FleetResult, sweep: bool,
         progress: Callable[[str], None] | None) -> None:
    try:
        executor, results = run_tasks(run_task, tasks, _failed, workers=cfg.workers, scheduler=cfg.scheduler)
    except ExecutorError as exc:
        raise QualityError(str(exc)) from exc
    out.executor = executor
    for r in results:
        if r.error:
            out.errors.append(r.error)
        (out.sweep_cases if sweep else out.cases).extend(r.cases)
        if r.fault_free is not None:
            out.fault_free.append(r.fault_free)
        if progress is not None:
            t = r.task
            bad = sum(not c.detected_in_time for c in r.cases)
            ff = r.fault_free
            progress(f"{t.plant} {t.vehicle} {t.scenario}" + (f" (repetition {t.repetition})" if t.repetition else "")
                     + f": {len(r.cases)} cases, {bad} not detected in time"
                     + (f", {ff.detection_events} false detections" if ff is not None else "")
                     + (f", ERROR {r.error}" if r.error else ""))


def vehicle_share(cases: Sequence[FleetCase], fault: str, multiplier: float, goal: Callable[[FleetCase], bool],
                  plant: str = TRUTH) -> tuple[float, int]:
    """(share of the vehicles on which every scenario's case of `fault` at `multiplier` meets `goal`, vehicles)."""
    by_vehicle: dict[int, list[FleetCase]] = {}
    for c in cases:
        if c.plant == plant and c.fault == fault and c.multiplier == multiplier:
            by_vehicle.setdefault(c.vehicle, []).append(c)
    if not by_vehicle:
        return 0.0, 0
    ok = sum(all(goal(c) for c in cs) for cs in by_vehicle.values())
    return ok / len(by_vehicle), len(by_vehicle)


def _unmasked_share(cases: Sequence[FleetCase], fault: str) -> float:
    return vehicle_share(cases, fault, 1.0, lambda c: c.outcome != "masked")[0]


def _sweep(cfg: FleetConfig, out: FleetResult, progress: Callable[[str], None] | None) -> None:
    """The minimum detectable fault per fault: grid steps down from the required size while it passes, up while
    it fails, one step per round for every fault still searching."""
    passes: dict[str, dict[float, bool]] = {f: {} for f in out.faults}
    for f in out.faults:
        share, _ = vehicle_share(out.cases, f, 1.0, lambda c: c.detected_in_time)
        passes[f][1.0] = share >= VEHICLE_SHARE_GOAL
        unmasked = _unmasked_share(out.cases, f)
        if unmasked < VEHICLE_SHARE_GOAL:
            out.mdf[f] = {"multiplier": None, "reason": f"masked: {100 * (1 - unmasked):.0f} % of the vehicles were "
                          "in false alarm before the onset in some scenario, so no size reaches 95 %"}
    while True:
        todo = {f: m for f in out.faults if f not in out.mdf
                for m in [_next_size(f, passes[f], out.sizes[f], out.limits.get(f, float("inf")), out.mdf)]
                if m is not None}
        if not todo:
            return
        tasks = [Task(TRUTH, v, s, tuple(todo.items()), False, cfg, tuple(out.sizes.items()))
                 for v in cfg.vehicle_seeds for s in cfg.scenarios]
        if progress is not None:
            progress(f"size sweep: {', '.join(f'{f} x{m:g}' for f, m in todo.items())}")
        _run(tasks, cfg, out, True, progress)
        for f, m in todo.items():
            share, _ = vehicle_share(out.sweep_cases, f, m, lambda c: c.detected_in_time)
            passes[f][m] = share >= VEHICLE_SHARE_GOAL


def _next_size(fault: str, tried: dict[float, bool], size: float, limit: float,
               mdf: dict[str, dict[str, Any]]) -> float | None:
    """The next multiplier to try for `fault`, or None after recording its outcome in `mdf`."""
    grid = SWEEP_GRID
    if tried[1.0]:  # passes at the required size: down the grid while it passes
        low = min(tried)
        if not tried[low]:
            mdf[fault] = {"multiplier": min(m for m, ok in tried.items() if ok), "reason": ""}
            return None
        k = grid.index(low)
        if k == 0:
            mdf[fault] = {"multiplier": low, "reason": f"passes at the grid's smallest size (x{low:g})"}
            return None
        return grid[k - 1]
    high = max(tried)  # fails at the required size: up the grid until it passes
    if tried[high]:
        mdf[fault] = {"multiplier": high, "reason": ""}
        return None
    k = grid.index(high)
    if k + 1 >= len(grid) or grid[k + 1] * size > limit:
        mdf[fault] = {"multiplier": None, "reason": f"not detected in time on 95 % of the vehicles up to x{high:g} "
                      "the required size (the grid's end or the fault's physical limit)"}
        return None
    return grid[k + 1]


def run_fleet_suite(cfg: FleetConfig, progress: Callable[[str], None] | None = None) -> FleetResult:
    """Every vehicle x scenario with its fault-free drive and every fault at the required size, the model plant's
    same cases, then (cfg.sweep) the minimum-detectable-fault search."""
    t0 = time.perf_counter()
    sizes = load_fault_sizes(cfg.sizes_file)
    try:
        limits = dict(FaultSizes.load(cfg.sizes_file).limits)
    except FaultSizesError as exc:
        raise QualityError(str(exc)) from exc
    faults, skipped = _faults(cfg, sizes)
    out = FleetResult(cfg, cfg.table, sizes, limits, faults, skipped)
    cases = tuple((f, 1.0) for f in faults)
    size_items = tuple(sizes.items())
    tasks = [Task(TRUTH, v, s, cases, True, cfg, size_items) for v in cfg.vehicle_seeds for s in cfg.scenarios]
    tasks += [Task(TRUTH, v, s, (), True, cfg, size_items, rep) for rep in range(1, cfg.fault_free_repetitions)
              for v in cfg.vehicle_seeds for s in cfg.scenarios]
    tasks += [Task(MODEL, seed, s, cases, True, cfg, size_items) for seed in cfg.model_plant_seeds
              for s in cfg.scenarios]
    _run(tasks, cfg, out, False, progress)
    if cfg.sweep:
        _sweep(cfg, out, progress)
    out.wall_s = time.perf_counter() - t0
    return out


def quick_config(table: str = "romo", **kw: Any) -> FleetConfig:
    """The CI size: two vehicles, cornering and the wet patch, one model-plant seed, no size sweep."""
    return replace(FleetConfig(table=table, vehicles=2, scenarios=("cornering", "wet_patch"), sweep=False), **kw)
