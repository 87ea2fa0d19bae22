"""A simulated drive as a command line asks for it (the drive options of `fdi_host.sim.options`), and its
ground-truth file: shared by ``fdi-sim`` and ``fdi-sim live``."""

from __future__ import annotations

import argparse
import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from tqdm import tqdm

from fdi_host.sim.faults import FaultSpecError, ground_truth, parse_fault
from fdi_host.sim.options import DEFAULT_SCENARIO
from fdi_host.sim.plant import Plant
from fdi_host.sim.scenario import ScenarioError, load_scenario
from fdi_host.sim.vehicle_envelope import VehicleDrawError, vehicle_from_option
from fdi_host.sim.vehicle_sim import SimConfig, SimResult, default_plant, simulate

if TYPE_CHECKING:
    from fdi_host.sim.generic import VehicleDrive
    from fdi_host.vehicle import Vehicle as VehicleSpec


def write_truth(result: SimResult, plant: Plant, duration: float, start_time: float, noise: bool,
                path: Path) -> Path:
    """Ground truth of a drive (fault specs, per fault: equations, unit, active intervals) as JSON."""
    info = {
        v.name: {
            "unit": v.unit,
            "desc": v.desc,
            "equations": [e.id for e in plant.model.equations if v.name in e.faults],
        }
        for v in plant.model.faults
    }
    gt = ground_truth(result.faults, result.t, info)
    gt |= {"scenario": result.scenario.name, "seed": result.seed, "duration": duration, "start_time": start_time,
           "noise": noise, "plant": result.label}
    if result.vehicle is not None:
        gt["vehicle"] = result.vehicle.describe()
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(gt, indent=2) + "\n", encoding="utf-8")
    return path


@dataclass(frozen=True)
class Drive:
    """A simulated drive as the command line asked for it."""

    result: SimResult
    plant: Plant
    duration: float


def simulate_from_args(ap: argparse.ArgumentParser, args: argparse.Namespace) -> Drive:
    """Scenario, scenario faults (unless --no-scenario-faults) and --fault specs, duration, seed and noise from
    the common options of `fdi-sim` and `fdi-sim live`, on the model plant or (--truth-vehicle) the truth plant;
    simulates with a progress bar. A bad option (an unknown scenario name, a bad fault spec or vehicle draw) is a
    usage error (ap.error: exit 2); a scenario file that is not one raises its ScenarioError (exit 1)."""
    try:
        sc = load_scenario(args.scenario)
    except ScenarioError as exc:
        if Path(args.scenario).is_file():
            raise
        ap.error(str(exc))
    try:
        extra = [parse_fault(f) for f in args.fault]
        vehicle = vehicle_from_option(getattr(args, "truth_vehicle", None))
    except (FaultSpecError, VehicleDrawError) as exc:
        ap.error(str(exc))
    faults = ([] if args.no_scenario_faults else list(sc.faults)) + extra
    duration = args.duration if args.duration is not None else sc.duration
    cfg = SimConfig(noise_scale=0.0 if args.no_noise else 1.0)
    plant = default_plant()
    desc = f"simulate {sc.name}" + ("" if vehicle is None else f" ({vehicle.label})")
    with tqdm(total=round(duration / cfg.dt) + 1, unit="ms", desc=desc, disable=args.quiet) as bar:
        if vehicle is None:
            result = simulate(sc, faults, seed=args.seed, plant=plant, config=cfg, duration=duration,
                              progress=bar.update)
        else:
            from fdi_host.sim.truth_sim import simulate_truth

            result = simulate_truth(sc, faults, vehicle=vehicle, seed=args.seed, config=cfg, duration=duration,
                                    progress=bar.update)
    return Drive(result=result, plant=plant, duration=duration)


def simulate_vehicle_from_args(ap: argparse.ArgumentParser, args: argparse.Namespace,
                               vehicle: VehicleSpec) -> VehicleDrive:
    """The drive options of `fdi-sim` and `fdi-sim live` for a vehicle on the generic simulator: its scenario (or
    --scenario FILE), faults of its model (--fault, any shape), seed, duration and noise; a drive of its model
    plant. A bad option is a usage error (ap.error)."""
    from fdi_analysis.model_loader import load_model
    from fdi_host.sim import generic

    if getattr(args, "truth_vehicle", None) is not None:
        ap.error(f"--truth-vehicle: vehicle {vehicle.name} has no truth plant, only its model plant")
    scenario = vehicle.scenario if args.scenario == DEFAULT_SCENARIO else Path(args.scenario)
    if scenario is None:
        ap.error(f"vehicle {vehicle.name} has no scenario (scenario = ... in {vehicle.manifest}); give --scenario FILE")
    model = load_model(vehicle.model)
    try:
        faults = [parse_fault(text, [f.name for f in model.faults]) for text in args.fault]
    except FaultSpecError as exc:
        ap.error(str(exc))
    if not getattr(args, "quiet", False):
        print(f"simulate {vehicle.name}: {scenario.name} on the model plant of {vehicle.model.name}", flush=True)
    return generic.vehicle_drive(model, generic.Scenario.load(scenario), faults, args.seed, args.duration,
                                 not getattr(args, "no_noise", False),
                                 f"model plant of {vehicle.name} ({vehicle.model.name})")


def write_vehicle_truth(drive: VehicleDrive, vehicle: VehicleSpec, start_time: float, path: Path) -> Path:
    """The ground truth of a vehicle's drive, as `write_truth` for ROMO's."""
    truth = drive.truth | {"start_time": start_time, "vehicle": vehicle.name}
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(truth, indent=2) + "\n", encoding="utf-8")
    return path
