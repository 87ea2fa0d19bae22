"""The quality suite of a vehicle on the generic simulator (``fdi-quality --vehicle PATH``, any model's plant):
every fault of its table at the required size of its fault-size file ([requirement]) as a step in the middle of a
drive of its scenario, per evaluation seed, and fault-free drives for the false alarms; each drive through what
ships: the vehicle's plugin, as CAN frames through its ECU when the vehicle has a DBC, else its diagnoser stepped
with the drive's signals.

The evaluation seeds are never the scenario's calibration or reference seeds (a `QualityError` if they are): the
plant is the vehicle's model plant, so the figures say how the diagnosis does on the model it was made from, with
other noise, not on a real vehicle. Every report names its plant.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fdi_analysis.export.fault_sizes import FaultSizes, FaultSizesError
from fdi_analysis.model_loader import load_model
from fdi_host.can.dbc import CanDatabase
from fdi_host.can.traffic import frames_from_columns
from fdi_host.ecu.bindings import Diagnoser, EcuResult, table_info
from fdi_host.ecu.offline import replay
from fdi_host.quality.suite import DELAY_GOAL_S, ISOLATION_GOAL_S, QualityError, evaluate_case
from fdi_host.sim import generic
from fdi_host.sim.faults import FaultSpec
from fdi_host.vehicle import Vehicle, resolve

EVAL_SEEDS = (4001, 4002, 4003)  # the cases' noise seeds (never a calibration or reference seed of the scenario)
FAULT_FREE_SEED0 = 5001  # the fault-free drives' seeds count up from here
ONSET_FRACTION = 0.5  # a case's fault starts in the middle of the drive


@dataclass(frozen=True)
class VehicleSuiteConfig:
    vehicle: str
    seeds: tuple[int, ...] = EVAL_SEEDS
    faults: tuple[str, ...] = ()  # default: every fault of the table
    multipliers: tuple[float, ...] = (1.0,)
    fault_free_minutes: float = 30.0
    sizes_file: Path | None = None  # default: the vehicle's fault_sizes
    ecu: tuple[tuple[str, Any], ...] = ()


def quick_config(vehicle: str) -> VehicleSuiteConfig:
    """The CI size: one seed, a few fault-free minutes."""
    return VehicleSuiteConfig(vehicle, seeds=EVAL_SEEDS[:1], fault_free_minutes=5.0)


@dataclass(frozen=True)
class VehicleCase:
    fault: str
    seed: int
    size: float
    onset: float
    detected: bool
    delay_s: float | None
    outcome: str  # exact | not isolated | wrong | missed
    isolation_delay_s: float | None
    final_candidates: tuple[str, ...]
    expected_class: tuple[str, ...]


@dataclass(frozen=True)
class FaultFreeDrive:
    seed: int
    duration_s: float
    detection_events: int
    isolation_events: int


@dataclass
class VehicleSuiteResult:
    config: VehicleSuiteConfig
    vehicle: str
    plant: str
    sizes: dict[str, float]
    cases: list[VehicleCase] = field(default_factory=list)
    fault_free: list[FaultFreeDrive] = field(default_factory=list)
    not_covered: list[str] = field(default_factory=list)  # faults no test of the table is sensitive to


def _sizes(v: Vehicle, cfg: VehicleSuiteConfig, faults: Sequence[str]) -> tuple[Path, dict[str, float]]:
    path = cfg.sizes_file or v.fault_sizes
    if path is None:
        raise QualityError(f"vehicle {v.name}: no fault sizes (fault_sizes = ... in {v.manifest}, or --sizes FILE)")
    try:
        req = dict(FaultSizes.load(Path(path)).requirement)
    except FaultSizesError as exc:
        raise QualityError(str(exc)) from exc
    unknown = sorted(set(req) - set(faults))
    if unknown:
        raise QualityError(f"{path}: [requirement] names {unknown}, not faults of {v.name} ({', '.join(faults)})")
    return Path(path), req


def _results(v: Vehicle, drive: generic.VehicleDrive, ecu: dict[str, Any]) -> list[EcuResult]:
    """The diagnosis after every step of a drive, as the vehicle's plugin computes it."""
    if v.has_bus and v.dbc is not None:
        frames = frames_from_columns(drive.signals, drive.dt, float(drive.t[-1]), CanDatabase(v.dbc))
        return replay(v.spec, frames, **ecu)
    diag = Diagnoser(v.spec, **ecu)
    run = diag.run({s: drive.signals[s] for s in diag.table.signal_names if s in drive.signals})
    return [dataclasses.replace(r, t_us=round(k * drive.dt * 1e6)) for k, r in enumerate(run.results)]


def run_vehicle_suite(cfg: VehicleSuiteConfig,
                      progress: Callable[[str], None] | None = None) -> VehicleSuiteResult:
    v = resolve(cfg.vehicle)
    if v.scenario is None:
        raise QualityError(f"vehicle {v.name} has no scenario (scenario = ... in {v.manifest})")
    sc = generic.Scenario.load(v.scenario)
    used = sorted({*sc.seeds, sc.reference_seed} & {*cfg.seeds, FAULT_FREE_SEED0})
    if used:
        raise QualityError(f"seeds {used} calibrated {v.name} ({v.scenario}): evaluate on other seeds")
    model = load_model(v.model)
    table = table_info(cfg.vehicle)
    _, sizes = _sizes(v, cfg, table.faults)
    covered = 0
    for m, has_gen in zip(table.test_fault_masks, table.has_generator, strict=True):
        covered |= m if has_gen else 0
    plant = f"model plant of {v.name} ({v.model.name}), scenario {v.scenario.name}"
    result = VehicleSuiteResult(cfg, v.name, plant, sizes)
    ecu = dict(cfg.ecu)
    onset = round(ONSET_FRACTION * sc.duration, 3)
    for fault in cfg.faults or table.faults:
        if fault not in table.faults:
            raise QualityError(f"--faults: {fault!r} is not a fault of {v.name} ({', '.join(table.faults)})")
        j = table.faults.index(fault)
        if not covered >> j & 1:
            result.not_covered.append(fault)
            continue
        if fault not in sizes:
            raise QualityError(f"no required size for {fault} in the fault-size file's [requirement]")
        for seed in cfg.seeds:
            for mult in cfg.multipliers:
                spec = FaultSpec(fault, onset, sizes[fault] * mult)
                drive = generic.vehicle_drive(model, sc, [spec], seed, label=plant)
                det, delay, outcome, iso_delay, _, final, _ = evaluate_case(
                    _results(v, drive, ecu), spec, onset, table.iso_class[j], table.faults, table.faults)
                result.cases.append(VehicleCase(
                    fault, seed, spec.magnitude, onset, det, delay, outcome, iso_delay, final,
                    tuple(f for k, f in enumerate(table.faults) if table.iso_class[j] >> k & 1)))
                if progress is not None:
                    progress(f"{fault} seed {seed} x{mult:g}: {outcome}")
    seed, total = FAULT_FREE_SEED0, 0.0
    while total < cfg.fault_free_minutes * 60.0:
        drive = generic.vehicle_drive(model, sc, [], seed, label=plant)
        res = _results(v, drive, ecu)
        n_det, n_iso = _events([r.detected for r in res]), _events([r.isolated for r in res])
        result.fault_free.append(FaultFreeDrive(seed, float(drive.t[-1]), n_det, n_iso))
        total += float(drive.t[-1])
        seed += 1
        if progress is not None:
            progress(f"fault-free seed {seed - 1}: {n_det} detections ({total / 60:.1f} min)")
    return result


def _events(flags: Sequence[bool]) -> int:
    """How many times a flag rises (an episode)."""
    return sum(int(b and not a) for a, b in zip([False, *flags], flags, strict=False))


def _ms(v: float | None) -> str:
    return "-" if v is None else f"{1000 * v:.0f}"


def markdown(r: VehicleSuiteResult) -> str:
    """The suite as Markdown: per fault its cases, then the fault-free drives."""
    lines = [f"# Quality of {r.vehicle} (plant: {r.plant})", "",
             f"Faults as steps at the required size (x {', '.join(f'{m:g}' for m in r.config.multipliers)}) at "
             f"{ONSET_FRACTION:.0%} of the drive, seeds {', '.join(map(str, r.config.seeds))}; goals: detection "
             f"within {1000 * DELAY_GOAL_S:.0f} ms, isolation to the structural class within "
             f"{1000 * ISOLATION_GOAL_S:.0f} ms of it.", "",
             "| fault | size | detected | delay ms (worst) | isolated | iso. delay ms (worst) | outcomes | class |",
             "|---|---|---|---|---|---|---|---|"]
    for fault in dict.fromkeys(c.fault for c in r.cases):
        cs = [c for c in r.cases if c.fault == fault]
        delays = [c.delay_s for c in cs if c.delay_s is not None]
        isos = [c.isolation_delay_s for c in cs if c.isolation_delay_s is not None]
        outcomes = ", ".join(f"{n} {o}" for o in ("exact", "not isolated", "wrong", "missed")
                             if (n := sum(c.outcome == o for c in cs)))
        lines.append(f"| {fault} | {cs[0].size:g} | {sum(c.detected for c in cs)}/{len(cs)} | "
                     f"{_ms(max(delays) if delays else None)} | {sum(c.outcome == 'exact' for c in cs)}/{len(cs)} | "
                     f"{_ms(max(isos) if isos else None)} | {outcomes} | {', '.join(cs[0].expected_class)} |")
    if r.not_covered:
        lines += ["", f"Not covered by any test of the table: {', '.join(r.not_covered)}."]
    minutes = sum(d.duration_s for d in r.fault_free) / 60.0
    lines += ["", f"Fault-free: {len(r.fault_free)} drives, {minutes:.1f} min: "
                  f"{sum(d.detection_events for d in r.fault_free)} detections, "
                  f"{sum(d.isolation_events for d in r.fault_free)} isolations."]
    return "\n".join(lines) + "\n"


def write(r: VehicleSuiteResult, out: Path) -> list[Path]:
    """quality.json and quality.md in `out`."""
    out.mkdir(parents=True, exist_ok=True)
    doc = {"vehicle": r.vehicle, "plant": r.plant, "config": dataclasses.asdict(r.config), "sizes": r.sizes,
           "cases": [dataclasses.asdict(c) for c in r.cases],
           "fault_free": [dataclasses.asdict(d) for d in r.fault_free], "not_covered": r.not_covered}
    paths = [out / "quality.json", out / "quality.md"]
    paths[0].write_text(json.dumps(doc, indent=2, default=str) + "\n", encoding="utf-8")
    paths[1].write_text(markdown(r), encoding="utf-8")
    return paths
