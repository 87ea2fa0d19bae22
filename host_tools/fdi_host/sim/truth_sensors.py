"""The truth plant's sensors: what each sensor group reports of the truth plant's motion.

Per signal, in this order: the physical quantity the sensor senses (the accelerometer the specific force in its
own, rolling and pitching, frame; the gyro the body's yaw rate; the velocity sensor the velocity of its mounting
point; the wheel robots their angle, current and speed readings; the brake unit its pressures), plus its bias
(constant plus slow drift: the IMU), times its scale error, through the group's internal first-order filter,
delayed by the group's latency (whole samples of the 1 kHz rate), plus a sensor fault of Table I (f1..f5,
f22..f25, at the sensor's output as today), plus white noise (`fdi_host.sim.sensors.add_noise`, the same levels
and streams as the model plant's sensors).

Groups: ``imu`` (ax_m, ay_m, psidot_m), ``velocity`` (vx_m, vy_m), ``wheel`` (delta_i_m, iTM_i_m, omega_i_m: each
wheel robot's readings) and ``brake`` (P_f_m, P_r_m). Everything here is causal: the readings up to a time depend
on the motion up to that time only, which lets a fault case share its drive's fault-free part.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

from fdi_host.sim.faults import FAULT_IDS
from fdi_host.sim.sensors import add_noise
from fdi_host.sim.vehicle_envelope import Vehicle

FloatArray = NDArray[np.float64]
D_X, D_Y = 1.0, 0.3  # m, the velocity sensor's position ahead of and left of the CoG (the model's d_x, d_y)
SENSOR_FAULT_OF: dict[str, str] = {
    "ax_m": "f1", "ay_m": "f2", "psidot_m": "f3", "vx_m": "f4", "vy_m": "f5",
    "omega1_m": "f22", "omega2_m": "f23", "omega3_m": "f24", "omega4_m": "f25",
}
GROUP_OF: dict[str, str] = (
    {"ax_m": "imu", "ay_m": "imu", "psidot_m": "imu", "vx_m": "velocity", "vy_m": "velocity",
     "P_f_m": "brake", "P_r_m": "brake"}
    | {f"{n}{i}_m": "wheel" for n in ("delta", "iTM", "omega") for i in (1, 2, 3, 4)}
)


def _lag(x: FloatArray, dt: float, tau: float, delay: int) -> FloatArray:
    """First-order filter (time constant tau, starting settled at x[0]), then a delay of `delay` samples."""
    y = x
    if tau > 0.0:
        a = float(np.exp(-dt / tau))
        y = np.asarray(lfilter([1.0 - a], [1.0, -a], x, zi=np.array([a * x[0]]))[0], dtype=float)
    if delay > 0:
        y = np.concatenate((np.full(delay, y[0]), y[:-delay]))
    return y


def sensed(true: Mapping[str, FloatArray], readings: Mapping[str, FloatArray], t: FloatArray,
           v: Vehicle) -> dict[str, FloatArray]:
    """The physical quantity each sensor senses, with the IMU's bias and every scale error (before filters)."""
    sx, sy, sr = v.scale_imu
    out = {
        "ax_m": sx * (true["spec_fx"] + v.bias_ax.at(t)),
        "ay_m": sy * (true["spec_fy"] + v.bias_ay.at(t)),
        "psidot_m": sr * (true["psidot"] + v.bias_yaw.at(t)),
        "vx_m": v.scale_velocity[0] * (true["vx"] - D_Y * true["psidot"]),
        "vy_m": v.scale_velocity[1] * (true["vy"] + D_X * true["psidot"]),
    }
    out |= {f"omega{i}_m": true[f"omega{i}"] for i in (1, 2, 3, 4)}
    return out | dict(readings)


def clean_readings(true: Mapping[str, FloatArray], readings: Mapping[str, FloatArray], t: FloatArray,
                   faults: FloatArray, v: Vehicle, dt: float) -> dict[str, FloatArray]:
    """Every sensor's reading without its white noise: sensed, filtered, delayed, plus its sensor fault."""
    out: dict[str, FloatArray] = {}
    for name, x in sensed(true, readings, t, v).items():
        g = GROUP_OF[name]
        y = _lag(x, dt, v.filter_tau[g], round(v.latency[g] / dt))
        fid = SENSOR_FAULT_OF.get(name)
        out[name] = y + faults[:, FAULT_IDS.index(fid)] if fid is not None else y
    return out


def measured_readings(clean: Mapping[str, FloatArray], seed: int, noise_scale: float) -> dict[str, FloatArray]:
    """The readings with the sensors' white noise (the model plant's levels and per-signal streams)."""
    return add_noise(clean, seed, noise_scale)
