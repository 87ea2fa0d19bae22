"""The truth plant (issue 44): the tyre against CommonRoad's published functions, the envelope sampler, the
physics sanity of the plant, and the fleet plan's separation of calibration and evaluation."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fdi_host.quality.fleet import FleetConfig
from fdi_host.quality.fleet_plan import (
    CALIBRATION_VEHICLES,
    EVALUATION_VEHICLES,
    PlanError,
    check_disjoint,
    check_evaluation_fleet,
    fleet_seeds,
    model_plant_calibration_seeds,
)
from fdi_host.quality.suite import QualityError
from fdi_host.sim.scenario import FLEET_SCENARIOS, load_scenario, scenario_from_dict
from fdi_host.sim.truth_sim import simulate_truth
from fdi_host.sim.tyre import combined_forces, parameter_array
from fdi_host.sim.vehicle_envelope import ENVELOPE, NOMINAL, draw_vehicle, fleet

G = 9.81


def test_tyre_matches_commonroads_published_functions() -> None:
    tm = pytest.importorskip("vehiclemodels.utils.tire_model")
    from vehiclemodels.vehicle_parameters import setup_vehicle_parameters

    pt = setup_vehicle_parameters(2).tire
    p = parameter_array()
    for kappa in np.linspace(-0.6, 0.6, 13):
        for alpha in np.linspace(-0.35, 0.35, 9):
            for Fz in (800.0, 2565.0, 4500.0):
                s = -kappa  # CommonRoad's slip is braking-positive
                F0x = tm.formula_longitudinal(s, 0.0, Fz, pt)
                F0y, mu_y = tm.formula_lateral(alpha, 0.0, Fz, pt)
                fx = tm.formula_longitudinal_comb(s, alpha, F0x, pt)
                fy = tm.formula_lateral_comb(s, alpha, 0.0, mu_y, Fz, F0y, pt)
                fl, fs = combined_forces(kappa, alpha, Fz, p, 1.0, 1.0)
                assert fl == pytest.approx(fx, rel=1e-9, abs=1e-6)
                assert fs == pytest.approx(fy, rel=1e-9, abs=1e-6)


def test_tyre_scales_friction_and_stiffness() -> None:
    p = parameter_array()
    peak = max(abs(combined_forces(0.0, a, 2565.0, p, 0.5, 1.0)[1]) for a in np.linspace(0, 0.5, 200))
    peak1 = max(abs(combined_forces(0.0, a, 2565.0, p, 1.0, 1.0)[1]) for a in np.linspace(0, 0.5, 200))
    assert peak / peak1 == pytest.approx(0.5, rel=0.02)
    soft = combined_forces(0.0, 0.002, 2565.0, p, 1.0, 0.85)[1] - combined_forces(0.0, 0.0, 2565.0, p, 1.0, 0.85)[1]
    stiff = combined_forces(0.0, 0.002, 2565.0, p, 1.0, 1.0)[1] - combined_forces(0.0, 0.0, 2565.0, p, 1.0, 1.0)[1]
    assert soft / stiff == pytest.approx(0.85, rel=0.02)


def test_sampler_is_seeded_and_inside_the_envelope() -> None:
    assert draw_vehicle(5001) == draw_vehicle(5001)
    assert draw_vehicle(5001) != draw_vehicle(5002)
    vs = fleet(200, 5001)
    for name, (kind, lo, hi) in ENVELOPE.items():
        nominal = getattr(NOMINAL, name)
        vals = []
        for v in vs:
            x = getattr(v, name)
            if name.startswith("bias"):
                vals.append(x.peak * (1 if x.b0 >= 0 else -1))
                assert x.peak <= max(abs(lo), abs(hi)) + 1e-12
                continue
            vals += list(x.values()) if isinstance(x, dict) else list(x) if isinstance(x, tuple) else [x]
        noms = nominal if isinstance(nominal, tuple) else (nominal,)
        scale = noms[0] if kind == "rel" else 1.0
        arr = np.array(vals) / scale
        if not name.startswith("bias"):
            assert arr.min() >= lo - 1e-12 and arr.max() <= hi + 1e-12, name
            assert arr.min() < lo + 0.15 * (hi - lo) and arr.max() > hi - 0.15 * (hi - lo), name  # spans it


def test_steady_cornering_follows_the_demand_and_weight_is_carried_on_a_grade() -> None:
    r = simulate_truth(load_scenario("cornering"), [], vehicle=NOMINAL)
    last = slice(-2000, None)
    tr = r.true
    assert tr["psidot"][last].mean() == pytest.approx(0.3, rel=0.03)
    assert tr["ay"][last].mean() == pytest.approx(12.0 * 0.3, rel=0.03)
    assert tr["roll"][last].mean() > 0.0  # turning left, the body leans out: its left side rises
    # outer (right) wheels carry more than the inner ones
    assert (tr["Fz2"] + tr["Fz4"])[last].mean() > (tr["Fz1"] + tr["Fz3"])[last].mean() + 1000.0
    # at rest on a 6 % grade and a 4 % bank (brakes holding): the loads carry m g cos(grade) cos(bank)
    v = dataclasses.replace(NOMINAL, grade=0.06, bank=0.04)
    doc = {"scenario": {"name": "hold", "duration": 6.0}, "demand": {"speed": {"kind": "const", "value": 0.0}}}
    rest = simulate_truth(scenario_from_dict(doc), [], vehicle=v)
    loads = sum(rest.true[f"Fz{i}"][-500:].mean() for i in (1, 2, 3, 4))
    assert loads == pytest.approx(v.m * G * np.cos(np.arctan(0.06)) * np.cos(np.arctan(0.04)), rel=1e-3)
    # held by the hold pressure: the brake torque smooths its sign over omega_brake, so the car creeps (< 5 cm/s)
    assert abs(rest.true["vx"][-500:]).max() < 0.05
    # the accelerometer measures specific force: on the grade at rest it reads g sin(grade)
    assert rest.clean["ax_m"][-500:].mean() == pytest.approx(G * np.sin(np.arctan(0.06)), abs=0.02)


@pytest.mark.parametrize("vehicle", [None, 5001, 5002, 5003])
def test_no_nan_in_any_scenario(vehicle: int | None) -> None:
    v = NOMINAL if vehicle is None else draw_vehicle(vehicle)
    for name in FLEET_SCENARIOS:
        r = simulate_truth(load_scenario(name), [], vehicle=v)
        for key, x in (r.true | r.measured).items():
            assert np.isfinite(x).all(), (name, key)


def test_low_friction_vehicle_survives_the_wet_patch() -> None:
    v = dataclasses.replace(draw_vehicle(5004), mu_peak=0.5)
    r = simulate_truth(load_scenario("wet_patch"), [], vehicle=v)
    assert np.isfinite(r.true["vx"]).all() and r.true["mu_left"].min() == pytest.approx(0.3)


def test_calibration_and_evaluation_never_overlap() -> None:
    cal_seeds = model_plant_calibration_seeds() | fleet_seeds(CALIBRATION_VEHICLES, 4)
    ev = range(EVALUATION_VEHICLES.start, EVALUATION_VEHICLES.start + 500)
    check_disjoint(CALIBRATION_VEHICLES, cal_seeds, ev, fleet_seeds(ev, 4))
    with pytest.raises(PlanError):
        check_disjoint([1, 2], [], [2, 3], [])
    with pytest.raises(PlanError):
        check_disjoint([1], [1001], [5001], [1001])
    with pytest.raises(PlanError):
        check_evaluation_fleet([17])  # a calibration vehicle
    with pytest.raises(QualityError):
        FleetConfig(first_vehicle=10, vehicles=3)
    FleetConfig(vehicles=3)  # the default evaluation fleet is accepted
