"""Which vehicles and noise seeds calibrate the diagnosis and which evaluate it: two sets that never meet.

Calibration: the model plant's drives of the calibration commands (each scenario's own seed, CALIBRATION_SEEDS,
the fault-size sweep's seeds and their confirmation offsets: `fdi_host.tuning.seeds`), and the truth-plant vehicles
1 .. 4999 with their noise seeds, kept for calibrating on a fleet. Evaluation: the truth-plant vehicles from 5001
on with theirs. A vehicle's drives get the noise seed ``100 * vehicle + 4 * scenario + repetition`` (scenario: its
index in FLEET_SCENARIOS, repetition < 4), so the noise seeds of the two vehicle ranges are disjoint as well, and
both lie above every model-plant seed. `check_disjoint` is what the fleet suite and the tests hold the plan to.
"""

from __future__ import annotations

from collections.abc import Iterable

from fdi_host.errors import FdiHostError
from fdi_host.sim.scenario import FLEET_SCENARIOS, load_scenario
from fdi_host.tuning.seeds import (
    CALIBRATION_SEEDS,
    CALIBRATION_VEHICLES,
    CONFIRM_SEED_OFFSETS,
    EVALUATION_VEHICLES,
    REPETITIONS,
    SWEEP_SEEDS,
    fleet_noise_seed,
)

FIRST_EVALUATION_VEHICLE = EVALUATION_VEHICLES.start


class PlanError(FdiHostError, ValueError):
    """Calibration and evaluation would share a vehicle or a noise seed."""


def model_plant_calibration_seeds() -> frozenset[int]:
    """Every noise seed a model-plant calibration drive uses."""
    own = {load_scenario(s).seed for s in FLEET_SCENARIOS}
    sweep = {s + k for s in SWEEP_SEEDS for k in (0, *CONFIRM_SEED_OFFSETS)}
    return frozenset(own | set(CALIBRATION_SEEDS) | sweep)


def noise_seed(vehicle: int, scenario: str, repetition: int = 0) -> int:
    """The noise seed of a vehicle's drive of `scenario` (repetition 0 .. REPETITIONS - 1)."""
    if not 0 <= repetition < REPETITIONS:
        raise PlanError(f"repetition {repetition} outside 0..{REPETITIONS - 1}")
    return fleet_noise_seed(vehicle, FLEET_SCENARIOS.index(scenario), repetition)


def fleet_seeds(vehicles: Iterable[int], repetitions: int = 1) -> frozenset[int]:
    """The noise seeds of every drive of `vehicles` (all scenarios, the first `repetitions`)."""
    return frozenset(noise_seed(v, s, r) for v in vehicles for s in FLEET_SCENARIOS for r in range(repetitions))


def check_disjoint(calibration_vehicles: Iterable[int], calibration_seeds: Iterable[int],
                   evaluation_vehicles: Iterable[int], evaluation_seeds: Iterable[int]) -> None:
    """PlanError naming the shared vehicles or seeds, if calibration and evaluation share any."""
    cv, ev = set(calibration_vehicles), set(evaluation_vehicles)
    cs, es = set(calibration_seeds), set(evaluation_seeds)
    if cv & ev:
        raise PlanError(f"calibration and evaluation share vehicles {sorted(cv & ev)[:5]}")
    if cs & es:
        raise PlanError(f"calibration and evaluation share noise seeds {sorted(cs & es)[:5]}")


def check_evaluation_fleet(vehicles: Iterable[int], repetitions: int = 1) -> None:
    """PlanError unless `vehicles` are evaluation vehicles whose drives share no seed with any calibration."""
    vs = list(vehicles)
    outside = [v for v in vs if v not in EVALUATION_VEHICLES]
    if outside:
        raise PlanError(f"vehicles {outside[:5]} are not evaluation vehicles ({EVALUATION_VEHICLES.start} .. "
                        f"{EVALUATION_VEHICLES.stop - 1}); 1 .. {CALIBRATION_VEHICLES.stop - 1} calibrate")
    calibration_seeds = model_plant_calibration_seeds() | fleet_seeds(CALIBRATION_VEHICLES, REPETITIONS)
    check_disjoint(CALIBRATION_VEHICLES, calibration_seeds, vs, fleet_seeds(vs, repetitions))
