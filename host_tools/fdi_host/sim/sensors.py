"""Sensor models: white Gaussian noise per sample, quantisation by the DBC scaling, operating ranges.

The noise levels (1 sigma) are typical of the sensor classes on the ROMO: an automotive MEMS IMU, an optical
two-axis velocity sensor, resolver-based steering angle and wheel speed sensing in the wheel robots, the
current sensing of the traction inverters and the pressure sensors of the brake-by-wire unit. Quantisation
is not modelled here: it happens when the value is encoded into its CAN signal (DBC scale), so the DBC
resolution must be finer than the noise (tests/host/test_dbc.py checks it). The operating range is what the
simulator can produce in its scenarios; the DBC range must cover it without saturation.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class SensorSpec:
    known: str  # model known (measured signal)
    sigma: float  # noise standard deviation, SI unit
    unit: str
    op_min: float  # operating range the simulator can produce, SI unit
    op_max: float
    sensor: str


_WHEEL = [
    spec
    for i in (1, 2, 3, 4)
    for spec in (
        SensorSpec(f"delta{i}_m", 5e-4, "rad", -np.pi / 2, np.pi / 2, f"steering angle sensor, wheel {i}"),
        SensorSpec(f"iTM{i}_m", 0.5, "A", -300.0, 300.0, f"traction motor current sensor, wheel {i}"),
        SensorSpec(f"omega{i}_m", 0.05, "rad/s", -120.0, 120.0, f"wheel speed sensor, wheel {i}"),
    )
]

SENSORS: tuple[SensorSpec, ...] = (
    SensorSpec("ax_m", 0.02, "m/s^2", -15.0, 15.0, "IMU accelerometer x"),
    SensorSpec("ay_m", 0.02, "m/s^2", -15.0, 15.0, "IMU accelerometer y"),
    SensorSpec("psidot_m", 1.5e-3, "rad/s", -2.0, 2.0, "IMU yaw rate gyro"),
    SensorSpec("vx_m", 0.01, "m/s", -30.0, 30.0, "optical velocity sensor x"),
    SensorSpec("vy_m", 0.01, "m/s", -30.0, 30.0, "optical velocity sensor y"),
    *_WHEEL,
    SensorSpec("P_f_m", 1e4, "Pa", 0.0, 1.0e7, "brake pressure sensor, front axle"),
    SensorSpec("P_r_m", 1e4, "Pa", 0.0, 1.0e7, "brake pressure sensor, rear axle"),
)

# The motion demand is a command, not a measurement: no noise, but it must fit its CAN signals too.
DEMAND_RANGES: dict[str, tuple[float, float]] = {
    "demand_speed": (-30.0, 30.0),
    "demand_sideslip": (-np.pi / 2, np.pi / 2),
    "demand_yaw_rate": (-2.0, 2.0),
}

SENSOR_BY_KNOWN: dict[str, SensorSpec] = {s.known: s for s in SENSORS}


def add_noise(
    clean: Mapping[str, FloatArray], seed: int, scale: float = 1.0
) -> dict[str, FloatArray]:
    """Add white noise to each known signal. Each signal has its own stream derived from (seed, name),
    so the noise of one signal does not depend on which other signals exist or on the faults."""
    out: dict[str, FloatArray] = {}
    for name, x in clean.items():
        spec = SENSOR_BY_KNOWN.get(name)
        if spec is None or scale == 0.0:
            out[name] = x.copy()
            continue
        key = [seed, *name.encode()]
        rng = np.random.default_rng(key)
        out[name] = x + scale * spec.sigma * rng.standard_normal(x.shape)
    return out
