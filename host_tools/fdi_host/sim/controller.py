"""Geometric motion controller (zero tyre slip) and the intelligent actuators it commands.

Steering. For the demanded body motion (speed V, side-slip beta, yaw rate r) the CoG velocity is
(V cos beta, V sin beta); the velocity of each wheel's contact point in body axes, (u_i, v_i), is taken from
the model's own contact-point equations W_i.vL / W_i.vS evaluated at delta_i = 0. With zero slip the wheel
must roll along that velocity, so ``delta_i = atan2(v_i, u_i)`` (limited to +-90 deg; below a small demanded
speed the angles are held).

Wheel torques. A PI speed controller with demand feed-forward gives an acceleration demand a; the four wheels
share the force m*a equally (plus the torque to spin the wheels up), converted to motor current with K_TM.
Regenerative braking is limited; beyond it the brake-by-wire unit applies axle pressure (front share
`brake_front_share`), converted from torque with mu_DB*A_DB*r_DB. At standstill a hold pressure is applied.
The controller feeds back the *true* speed (an ideal state estimator: the motion controller is outside the
paper's scope), so a sensor fault changes only its own signal and never the motion.

Actuators. Steering, current and pressure loops are first-order lags (exactly discretised at the control
rate) with limits. Each actuator reports its own sensor value (delta_i_m, iTM_i_m, P_a_m); the plant's true
inputs follow from the model's measurement equations (e.g. ``delta_i = delta_i_m + f``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

ContactFn = Callable[[float, float, float], Sequence[tuple[float, float]]]


@dataclass(frozen=True)
class ControllerConfig:
    kp_speed: float = 1.5  # 1/s
    ki_speed: float = 0.3  # 1/s^2
    a_max: float = 4.0  # m/s^2
    a_min: float = -9.0  # m/s^2
    i_max: float = 300.0  # A, motor current limit
    i_regen_min: float = -120.0  # A, regenerative braking limit; beyond it the friction brakes act
    p_max: float = 1.0e7  # Pa (100 bar)
    p_hold: float = 2.0e6  # Pa, standstill hold pressure
    brake_front_share: float = 0.6
    v_steer_hold: float = 0.2  # m/s, below this demanded speed the steering angles are held
    v_standstill: float = 0.05  # m/s
    delta_max: float = math.pi / 2
    tau_steer: float = 0.04  # s
    steer_rate_max: float = 3.0  # rad/s
    tau_current: float = 0.004  # s
    tau_pressure: float = 0.03  # s


@dataclass(frozen=True)
class VehicleConstants:
    m: float
    R: float
    J_w: float
    K_TM: float
    brake_gain: float  # N m per Pa at one wheel: mu_DB * A_DB * r_DB

    @classmethod
    def from_parameters(cls, p: Mapping[str, float]) -> VehicleConstants:
        return cls(p["m"], p["R"], p["J_w"], p["K_TM"], p["mu_DB"] * p["A_DB"] * p["r_DB"])


@dataclass(frozen=True)
class ActuatorReadings:
    """What the actuators report (the model's actuator-side knowns)."""

    delta_m: tuple[float, float, float, float]
    current_m: tuple[float, float, float, float]
    P_f_m: float
    P_r_m: float

    def as_known_vector(self) -> list[float]:
        return [*self.delta_m, *self.current_m, self.P_f_m, self.P_r_m]


@dataclass
class GeometricController:
    consts: VehicleConstants
    contact: ContactFn
    dt: float
    cfg: ControllerConfig = field(default_factory=ControllerConfig)
    _delta: list[float] = field(default_factory=lambda: [0.0] * 4)
    _delta_cmd: list[float] = field(default_factory=lambda: [0.0] * 4)
    _current: list[float] = field(default_factory=lambda: [0.0] * 4)
    _pf: float = 0.0
    _pr: float = 0.0
    _integ: float = 0.0

    def steering_angles(self, speed: float, sideslip: float, yaw_rate: float) -> list[float]:
        """Zero-slip steering angles for a demanded motion."""
        vx, vy = speed * math.cos(sideslip), speed * math.sin(sideslip)
        out = []
        for u, v in self.contact(vx, vy, yaw_rate):
            d = math.atan2(v, u)
            if d > math.pi / 2:  # the wheel would roll backwards: steer the other way, drive reversed
                d -= math.pi
            elif d < -math.pi / 2:
                d += math.pi
            out.append(max(-self.cfg.delta_max, min(self.cfg.delta_max, d)))
        return out

    def step(
        self, speed_dem: float, sideslip_dem: float, yaw_rate_dem: float, speed_rate_dem: float, speed: float
    ) -> ActuatorReadings:
        """One control period: demand and measured (true) speed -> actuator readings after the period."""
        c, k = self.cfg, self.consts
        if abs(speed_dem) >= c.v_steer_hold:
            self._delta_cmd = self.steering_angles(speed_dem, sideslip_dem, yaw_rate_dem)
        # speed control -> acceleration demand
        err = speed_dem - speed
        standstill = abs(speed_dem) < c.v_standstill and abs(speed) < 4 * c.v_steer_hold
        if standstill:
            self._integ = 0.0
            a_dem = 0.0
        else:
            a_raw = speed_rate_dem + c.kp_speed * err + self._integ
            a_dem = max(c.a_min, min(c.a_max, a_raw))
            if a_dem == a_raw:  # anti-windup: integrate only when not saturated
                self._integ += c.ki_speed * err * self.dt
        torque = k.m * a_dem * k.R / 4.0 + k.J_w * a_dem / k.R  # per wheel
        i_cmd = torque / k.K_TM
        brake_torque = 0.0  # total over four wheels, >= 0
        if i_cmd < c.i_regen_min:
            brake_torque = 4.0 * (c.i_regen_min - i_cmd) * k.K_TM
            i_cmd = c.i_regen_min
        i_cmd = max(-c.i_max, min(c.i_max, i_cmd))
        pf = c.brake_front_share * brake_torque / 2.0 / k.brake_gain
        pr = (1.0 - c.brake_front_share) * brake_torque / 2.0 / k.brake_gain
        if standstill:
            i_cmd, pf, pr = 0.0, c.p_hold, c.p_hold
        pf, pr = min(pf, c.p_max), min(pr, c.p_max)
        # actuator dynamics over one period
        a_s = 1.0 - math.exp(-self.dt / c.tau_steer)
        a_i = 1.0 - math.exp(-self.dt / c.tau_current)
        a_p = 1.0 - math.exp(-self.dt / c.tau_pressure)
        max_step = c.steer_rate_max * self.dt
        for j in range(4):
            step = a_s * (self._delta_cmd[j] - self._delta[j])
            self._delta[j] += max(-max_step, min(max_step, step))
            self._current[j] += a_i * (i_cmd - self._current[j])
        self._pf += a_p * (pf - self._pf)
        self._pr += a_p * (pr - self._pr)
        d, cur = self._delta, self._current
        return ActuatorReadings((d[0], d[1], d[2], d[3]), (cur[0], cur[1], cur[2], cur[3]), self._pf, self._pr)

    def preset(self, speed: float, sideslip: float, yaw_rate: float) -> None:
        """Start in steady state for a demanded motion (steering settled)."""
        if abs(speed) >= self.cfg.v_steer_hold:
            self._delta_cmd = self.steering_angles(speed, sideslip, yaw_rate)
            self._delta = list(self._delta_cmd)
