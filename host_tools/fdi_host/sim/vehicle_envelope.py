"""The vehicles of the truth plant: the nominal ROMO and seeded draws from the stated envelope (issue 44).

A vehicle instance is every parameter the truth plant (`fdi_host.sim.truth_plant`) and its sensors
(`fdi_host.sim.truth_sensors`) use. The nominal vehicle has the diagnosis model's values where the model has the
quantity (mass, inertia, geometry, radius, motor and brake constants, dry friction 1.0) and values typical of a
vehicle of this class where it does not (suspension, drag, rolling resistance, relaxation lengths, sensor filters).

The envelope (a requirement, issue 44; every draw is uniform in its range, independently):

    mass                  nominal .. +25 %           yaw inertia        +-15 %
    CoG height            +-15 %                     tyre stiffness     +-15 % (both slip stiffnesses)
    peak friction         0.5 .. 1.0 (dry road)      rolling radius     +-1.5 % per wheel
    motor torque constant +-4 % per motor            brake pad friction +-10 % per wheel
    drag area CdA         0.5 .. 0.8 m^2             rolling resistance 0.008 .. 0.015
    grade                 +-8 % (road offset)        bank               +-5 % (road offset)
    IMU bias ax, ay       +-0.15 m/s^2 with drift    yaw-rate bias      +-0.006 rad/s with drift
    sensor latency        0 .. 10 ms per group (IMU, velocity sensor, wheel robots, brake unit)

Grade and bank are offsets of the road a vehicle drives on, added to the scenario's own route profile; the sum is
held inside the envelope. A bias is a constant plus a drift (two slow sinusoids, periods 60..600 s) whose peak
stays inside the stated range. Beyond the envelope, each draw also carries the small sensor imperfections of the
truth plant's sensor model, fixed ranges stated in SENSOR_RANGES (scale errors, filter time constants).

Seeds: a vehicle is its seed; `fleet(n, first)` are the seeds first .. first + n - 1. Which seeds calibrate and
which evaluate is the fleet plan's business (`fdi_host.quality.fleet_plan`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fdi_host.errors import FdiHostError

GROUPS: tuple[str, ...] = ("imu", "velocity", "wheel", "brake")  # sensor groups (latency, filter)


class VehicleDrawError(FdiHostError, ValueError):
    """A ``--truth-vehicle`` that is neither ``nominal`` nor a seed."""


@dataclass(frozen=True)
class Bias:
    """A sensor bias: constant plus a drift of two slow sinusoids, b(t) = b0 + sum a_k sin(2 pi t / T_k + p_k)."""

    b0: float = 0.0
    amplitudes: tuple[float, float] = (0.0, 0.0)
    periods: tuple[float, float] = (300.0, 120.0)  # s
    phases: tuple[float, float] = (0.0, 0.0)  # rad

    def at(self, t: np.ndarray[Any, np.dtype[np.float64]]) -> np.ndarray[Any, np.dtype[np.float64]]:
        out = np.full_like(t, self.b0)
        for a, T, ph in zip(self.amplitudes, self.periods, self.phases, strict=True):
            out = out + a * np.sin(2.0 * np.pi * t / T + ph)
        return out

    @property
    def peak(self) -> float:
        return abs(self.b0) + sum(abs(a) for a in self.amplitudes)


@dataclass(frozen=True)
class Vehicle:
    """One vehicle of the truth plant (SI units; wheel tuples in the order FL, FR, RL, RR = wheels 1..4)."""

    name: str = "nominal"
    seed: int | None = None  # None: the nominal vehicle
    # body
    m: float = 1046.0
    Iz: float = 1130.0
    Ix: float = 400.0  # roll inertia of the body
    Iy: float = 1100.0  # pitch inertia of the body
    h: float = 0.50  # CoG height over the road
    l_f: float = 1.199
    l_r: float = 1.199
    w: float = 1.45
    # suspension per corner and anti-roll bars per axle
    k_susp: float = 30000.0  # N/m
    c_susp: float = 2500.0  # N s/m
    k_arb_f: float = 22000.0  # N m/rad, front anti-roll bar
    k_arb_r: float = 16000.0  # N m/rad, rear
    # wheels and tyres
    R: tuple[float, float, float, float] = (0.27, 0.27, 0.27, 0.27)  # effective rolling radius
    J_w: float = 0.9
    mu_peak: float = 1.0  # peak friction on the dry road (a wet patch scales it)
    tyre_stiffness: float = 1.0  # scale of the published slip stiffnesses
    sigma_x: float = 0.25  # m, longitudinal relaxation length
    sigma_y: float = 0.45  # m, lateral relaxation length
    # resistances
    CdA: float = 0.6  # m^2
    rho_air: float = 1.2  # kg/m^3
    c_rr: float = 0.010
    # drive and brakes
    K_TM: tuple[float, float, float, float] = (1.6, 1.6, 1.6, 1.6)  # N m/A incl. gear
    ripple: float = 0.015  # torque ripple, share of the torque
    ripple_per_rev: float = 24.0  # ripple periods per wheel revolution
    pad_mu: tuple[float, float, float, float] = (0.4, 0.4, 0.4, 0.4)
    piston_area: float = 2.0e-3  # m^2, brake piston
    disc_radius: float = 0.12  # m, effective brake disc radius
    omega_brake: float = 0.3  # rad/s, smoothing of the brake torque's sign at standstill
    # road offsets (added to the scenario's route profile)
    grade: float = 0.0  # tan of the slope along the direction of travel (0.08 = 8 %), uphill positive
    bank: float = 0.0  # tan of the slope across it, left side higher positive
    # sensors
    bias_ax: Bias = field(default_factory=Bias)
    bias_ay: Bias = field(default_factory=Bias)
    bias_yaw: Bias = field(default_factory=Bias)
    scale_imu: tuple[float, float, float] = (1.0, 1.0, 1.0)  # ax, ay, yaw rate
    scale_velocity: tuple[float, float] = (1.0, 1.0)
    filter_tau: Mapping[str, float] = field(
        default_factory=lambda: {"imu": 0.004, "velocity": 0.005, "wheel": 0.002, "brake": 0.005})
    latency: Mapping[str, float] = field(default_factory=lambda: dict.fromkeys(GROUPS, 0.0))  # s

    @property
    def label(self) -> str:
        return "nominal vehicle" if self.seed is None else f"vehicle {self.seed}"

    def describe(self) -> dict[str, Any]:
        """JSON-ready parameters."""
        return dataclasses.asdict(self)


NOMINAL = Vehicle()

# The envelope of issue 44: (low, high) as factors of the nominal value ("rel") or absolute values ("abs").
ENVELOPE: dict[str, tuple[str, float, float]] = {
    "m": ("rel", 1.0, 1.25),
    "Iz": ("rel", 0.85, 1.15),
    "h": ("rel", 0.85, 1.15),
    "tyre_stiffness": ("abs", 0.85, 1.15),
    "mu_peak": ("abs", 0.5, 1.0),
    "R": ("rel", 0.985, 1.015),  # per wheel
    "K_TM": ("rel", 0.96, 1.04),  # per motor
    "pad_mu": ("rel", 0.9, 1.1),  # per wheel
    "CdA": ("abs", 0.5, 0.8),
    "c_rr": ("abs", 0.008, 0.015),
    "grade": ("abs", -0.08, 0.08),
    "bank": ("abs", -0.05, 0.05),
    "bias_ax": ("abs", -0.15, 0.15),
    "bias_ay": ("abs", -0.15, 0.15),
    "bias_yaw": ("abs", -0.006, 0.006),
    "latency": ("abs", 0.0, 0.010),  # per group
}
# Beyond the envelope: the sensor model's small imperfections every draw carries (fixed ranges of this module).
SENSOR_RANGES: dict[str, tuple[float, float]] = {
    "scale_imu": (0.995, 1.005),
    "scale_velocity": (0.995, 1.005),
    "drift_share": (0.0, 0.3),  # drift amplitude as a share of the bias range
    "filter_imu": (0.002, 0.006),
    "filter_velocity": (0.003, 0.008),
}


def _bias(rng: np.random.Generator, limit: float) -> Bias:
    drift = float(rng.uniform(*SENSOR_RANGES["drift_share"])) * limit
    split = float(rng.uniform(0.3, 0.7))
    b0 = float(rng.uniform(-(limit - drift), limit - drift))
    return Bias(b0=b0, amplitudes=(drift * split, drift * (1.0 - split)),
                periods=(float(rng.uniform(200.0, 600.0)), float(rng.uniform(60.0, 200.0))),
                phases=(float(rng.uniform(0.0, 2 * np.pi)), float(rng.uniform(0.0, 2 * np.pi))))


def draw_vehicle(seed: int) -> Vehicle:
    """The vehicle of `seed`: every quantity of ENVELOPE drawn uniformly in its range (same seed, same vehicle)."""
    rng = np.random.default_rng([44, seed])
    n = NOMINAL

    def draw(name: str, nominal: float) -> float:
        kind, lo, hi = ENVELOPE[name]
        v = float(rng.uniform(lo, hi))
        return v * nominal if kind == "rel" else v

    def four(name: str, nominal: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
        a, b, c, d = (draw(name, x) for x in nominal)
        return a, b, c, d

    s_imu = SENSOR_RANGES["scale_imu"]
    s_vel = SENSOR_RANGES["scale_velocity"]
    return dataclasses.replace(
        n,
        name=f"vehicle {seed}",
        seed=seed,
        m=draw("m", n.m),
        Iz=draw("Iz", n.Iz),
        h=draw("h", n.h),
        tyre_stiffness=draw("tyre_stiffness", 1.0),
        mu_peak=draw("mu_peak", 1.0),
        R=four("R", n.R),
        K_TM=four("K_TM", n.K_TM),
        pad_mu=four("pad_mu", n.pad_mu),
        CdA=draw("CdA", 1.0),
        c_rr=draw("c_rr", 1.0),
        grade=draw("grade", 1.0),
        bank=draw("bank", 1.0),
        bias_ax=_bias(rng, ENVELOPE["bias_ax"][2]),
        bias_ay=_bias(rng, ENVELOPE["bias_ay"][2]),
        bias_yaw=_bias(rng, ENVELOPE["bias_yaw"][2]),
        scale_imu=(float(rng.uniform(*s_imu)), float(rng.uniform(*s_imu)), float(rng.uniform(*s_imu))),
        scale_velocity=(float(rng.uniform(*s_vel)), float(rng.uniform(*s_vel))),
        filter_tau=dict(n.filter_tau) | {"imu": float(rng.uniform(*SENSOR_RANGES["filter_imu"])),
                                         "velocity": float(rng.uniform(*SENSOR_RANGES["filter_velocity"]))},
        latency={g: draw("latency", 1.0) for g in GROUPS},
    )


def fleet(n: int, first: int) -> list[Vehicle]:
    """The vehicles of seeds first .. first + n - 1."""
    if n < 1:
        raise ValueError("a fleet has at least one vehicle")
    return [draw_vehicle(first + k) for k in range(n)]


def vehicle_from_option(text: str | None) -> Vehicle | None:
    """The command lines' ``--truth-vehicle``: None (no option: the model plant), "nominal", or a seed."""
    if text is None:
        return None
    if text == "nominal":
        return NOMINAL
    try:
        seed = int(text)
    except ValueError:
        raise VehicleDrawError(f"--truth-vehicle {text!r}: expected 'nominal' or an integer seed") from None
    return draw_vehicle(seed)
