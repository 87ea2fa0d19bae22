"""Physics sanity of the simulated drives."""

from __future__ import annotations

import numpy as np
import pytest

from fdi_host.sim.plant import Plant
from fdi_host.sim.scenario import load_scenario
from fdi_host.sim.vehicle_sim import SimConfig, SimResult, simulate


@pytest.fixture(scope="module")
def cornering() -> SimResult:
    return simulate(load_scenario("cornering"), faults=[], config=SimConfig(noise_scale=0.0))


@pytest.fixture(scope="module")
def straight() -> SimResult:
    return simulate(load_scenario("straight"), faults=[], config=SimConfig(noise_scale=0.0))


def _eq2(plant: Plant, ax: np.ndarray, ay: np.ndarray) -> list[np.ndarray]:
    """Paper eq. (2) with its static part, written out here independently of the model file."""
    p = plant.params
    m, g, h, l_, w = p["m"], p["g"], p["h_CoG"], p["l_f"] + p["l_r"], p["w"]
    kf, kr = p["k_f"], p["k_r"]
    lon = m * ax * h / (2 * l_)
    lat = m * ay * h / (w * (kf + kr))
    return [
        m * g * p["l_r"] / (2 * l_) - lon - kf * lat,
        m * g * p["l_r"] / (2 * l_) - lon + kf * lat,
        m * g * p["l_f"] / (2 * l_) + lon - kr * lat,
        m * g * p["l_f"] / (2 * l_) + lon + kr * lat,
    ]


def test_steady_cornering_loads_match_eq2(cornering: SimResult, plant: Plant) -> None:
    r = cornering
    steady = r.t >= 12.0
    ax, ay = r.true["ax"][steady], r.true["ay"][steady]
    assert ay.mean() > 2.0  # really cornering (left turn: load moves to the right wheels 2, 4)
    ref = _eq2(plant, ax, ay)
    for i in range(4):
        np.testing.assert_allclose(r.true[f"Fz{i + 1}"][steady], ref[i], rtol=1e-9, atol=1e-6)
    assert r.true["Fz2"][steady].mean() > r.true["Fz1"][steady].mean() + 500
    total = sum(r.true[f"Fz{i}"][steady] for i in (1, 2, 3, 4))
    np.testing.assert_allclose(total, plant.params["m"] * plant.params["g"], rtol=1e-12)


def test_steady_cornering_lateral_acceleration_is_v2_over_r(cornering: SimResult) -> None:
    r = cornering
    dt = r.config.dt
    psi = np.cumsum(r.true["psidot"]) * dt
    vx, vy = r.true["vx"], r.true["vy"]
    X = np.cumsum(vx * np.cos(psi) - vy * np.sin(psi)) * dt
    Y = np.cumsum(vx * np.sin(psi) + vy * np.cos(psi)) * dt
    steady = r.t >= 12.0
    x, y = X[steady], Y[steady]
    # algebraic circle fit: x^2 + y^2 + D x + E y + F = 0
    A = np.column_stack([x, y, np.ones_like(x)])
    D, E, F = np.linalg.lstsq(A, -(x**2 + y**2), rcond=None)[0]
    radius = float(np.sqrt(D**2 / 4 + E**2 / 4 - F))
    speed = np.hypot(vx[steady], vy[steady]).mean()
    assert r.true["ay"][steady].mean() == pytest.approx(speed**2 / radius, rel=0.01)
    # and the geometric controller follows the demanded 40 m radius reasonably (tyre slip: a few %)
    assert radius == pytest.approx(float(r.scenario.extra["radius"]), rel=0.1)


def test_straight_driving_stays_straight(straight: SimResult) -> None:
    r = straight
    assert np.abs(r.true["vy"]).max() < 1e-6
    assert np.abs(r.true["psidot"]).max() < 1e-6
    cruise = (r.t > 9.0) & (r.t < 11.0)
    assert np.abs(r.true["vx"][cruise] - 20.0).max() < 0.1
    assert np.abs(r.true["ay"]).max() < 1e-6


def test_braking_uses_the_brakes_and_moves_load_forward(straight: SimResult) -> None:
    r = straight
    braking = (r.t > 11.8) & (r.t < 13.0)
    assert r.true["ax"][braking].mean() < -4.0
    assert r.true["P_f"][braking].min() > 1e5
    assert (r.true["Fz1"][braking] > r.true["Fz3"][braking] + 800).all()
    accel = (r.t > 3.0) & (r.t < 6.0)
    assert r.true["P_f"][accel].max() < 1.0  # Pa: released
    assert (r.true["Fz3"][accel] > r.true["Fz1"][accel]).all()
