"""The noise seeds the calibration of the model-plant diagnosis drives with (thresholds, screening, fault-size
sweep): one list, which the calibration commands use and the quality suites keep clear of."""

from __future__ import annotations

# Noise seeds of further drives per scenario besides the scenario's own. Twelve: with the two of the first
# calibration the 30 fault-free minutes of the quality suite (other seeds) saw 4 false detections, all at the onset
# of the straight drive's hard braking (a tail that three drives per scenario do not reach).
CALIBRATION_SEEDS: tuple[int, ...] = tuple(range(1001, 1013))
SWEEP_SEEDS: tuple[int, ...] = (777, 778)  # fault-sizes: an alarm counts when the drives of every seed alarm
CONFIRM_SEED_OFFSETS: tuple[int, ...] = (100, 200, 300)  # the sweep's confirmation also uses seed + each of these

# The truth-plant vehicles that calibrate the diagnosis on a fleet (fdi-tune calibrate --fleet) and those that evaluate
# it (fdi-quality --fleet): disjoint ranges, checked by fdi_host.quality.fleet_plan.
CALIBRATION_VEHICLES = range(1, 5000)
EVALUATION_VEHICLES = range(5001, 100_000)
REPETITIONS = 4  # noise seeds per vehicle and scenario


def fleet_noise_seed(vehicle: int, scenario_index: int, repetition: int = 0) -> int:
    """The noise seed of a truth-plant vehicle's drive of the scenario at `scenario_index` of the fleet's scenarios
    (repetition 0 .. REPETITIONS - 1): 100 * vehicle + 4 * scenario + repetition."""
    return 100 * vehicle + REPETITIONS * scenario_index + repetition
