"""The closed-loop drive: scenario demand -> geometric controller -> actuators -> plant -> sensors.

Time stepping. The controller and the recorded signals run at 1 kHz (``dt``); the plant is integrated with
``substeps`` inner steps per period (default 2, i.e. 0.5 ms) by a semi-implicit Euler scheme: the body
states (vx, vy, psidot) explicitly, each wheel speed linearly implicitly with the exact diagonal Jacobian
d(domega_i)/d(omega_i) from `fdi_host.sim.plant`:

    omega_i <- omega_i + h * domega_i / (1 - h * J_ii)

The wheel-spin mode is the stiff one (at standstill, where the slip is normalised by v_eps = 0.5 m/s, its
eigenvalue reaches about -8000 1/s, -2000 1/s more from the brake's tanh); the implicit update is
unconditionally stable for it, while the body modes (|lambda| < 600 1/s) are well inside the explicit
limit 2/h. The algebraic loop Fz <-> (ax, ay) is solved exactly at each evaluation (see `fdi_host.sim.plant`).

Recorded at each 1 kHz sample k (before the step): true states, true actuator inputs, accelerations ax, ay
(the loop solution), the internal quantities of `fdi_host.sim.plant.RECORDED`, the demand and the faults. The
measured signals follow from the model's measurement equations (faults included) plus sensor noise.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fdi_host.errors import FdiHostError
from fdi_host.sim.controller import ControllerConfig, GeometricController, VehicleConstants
from fdi_host.sim.faults import FAULT_IDS, FaultSpec, fault_matrix
from fdi_host.sim.plant import RECORDED, STATES, Plant
from fdi_host.sim.scenario import Scenario
from fdi_host.sim.sensors import add_noise
from fdi_host.sim.vehicle_envelope import Vehicle

FloatArray = NDArray[np.float64]


class SimulationDivergedError(FdiHostError, FloatingPointError):
    """A simulated state became non-finite (a fault or an input far beyond what the vehicle can follow)."""


@dataclass(frozen=True)
class SimConfig:
    dt: float = 1e-3
    substeps: int = 2
    noise_scale: float = 1.0  # 0 switches the sensor noise off
    controller: ControllerConfig = field(default_factory=ControllerConfig)


@dataclass
class SimResult:
    scenario: Scenario
    faults: tuple[FaultSpec, ...]
    seed: int
    t: FloatArray
    true: dict[str, FloatArray]  # states, inputs, ax, ay, RECORDED, demand_*
    clean: dict[str, FloatArray]  # measured signals with faults, without noise
    measured: dict[str, FloatArray]  # measured signals with faults and noise (quantised later, on CAN)
    fault_values: FloatArray  # (N, 25)
    config: SimConfig
    plant: str = "model plant"  # the label every figure made from this drive carries
    vehicle: Vehicle | None = None  # the truth plant's vehicle (None: the model plant)
    snapshots: dict[int, Any] = field(default_factory=dict)  # truth plant: states kept for fault cases
    runs: Any = None  # truth plant: the raw arrays of the drive (for fault cases from a snapshot)

    @property
    def label(self) -> str:
        """The plant and vehicle the drive came from, as figures name it."""
        return self.plant if self.vehicle is None else f"{self.plant}, {self.vehicle.label}"

    def fault(self, fid: str) -> FloatArray:
        return self.fault_values[:, FAULT_IDS.index(fid)]


_PLANT_CACHE: dict[str, Plant] = {}


def default_plant() -> Plant:
    """The plant compiled from the default model file (compiled once per process)."""
    if "default" not in _PLANT_CACHE:
        _PLANT_CACHE["default"] = Plant.from_model_file()
    return _PLANT_CACHE["default"]


def simulate(
    scenario: Scenario,
    faults: Sequence[FaultSpec] | None = None,
    *,
    seed: int | None = None,
    plant: Plant | None = None,
    config: SimConfig | None = None,
    duration: float | None = None,
    progress: Callable[[int], None] | None = None,
) -> SimResult:
    """Run `scenario` with `faults` (default: the scenario's own). `progress(n)` is called with the
    number of 1 kHz steps done since the previous call (about every 1000 steps)."""
    plant = plant or default_plant()
    cfg = config or SimConfig()
    specs = tuple(scenario.faults if faults is None else faults)
    seed = scenario.seed if seed is None else seed
    T = scenario.duration if duration is None else duration
    n = round(T / cfg.dt) + 1
    t: FloatArray = np.arange(n, dtype=float) * cfg.dt
    dem = scenario.demand_signals(t)
    F = fault_matrix(specs, t)
    plant_fault_idx = [FAULT_IDS.index(f) for f in plant.faults]
    consts = VehicleConstants.from_parameters(plant.params)
    ctrl = GeometricController(consts, plant.contact_velocity_function(), cfg.dt, cfg.controller)
    g_inputs = plant.input_functions()
    R = plant.params["R"]

    v0 = scenario.initial_speed
    x = [v0, 0.0, 0.0, v0 / R, v0 / R, v0 / R, v0 / R]
    ctrl.preset(float(dem["speed"][0]), float(dem["sideslip"][0]), float(dem["yaw_rate"][0]))
    ax, ay = 0.0, 0.0
    ns = len(STATES)
    X = np.empty((n, ns))
    U = np.empty((n, len(plant.inputs)))
    K = np.empty((n, len(plant.input_known_names)))
    A = np.empty((n, 2))
    REC = np.empty((n, len(RECORDED)))
    h = cfg.dt / cfg.substeps
    sp, ss, yr, spr = (dem[c].tolist() for c in ("speed", "sideslip", "yaw_rate", "speed_rate"))
    Fl = F.tolist()
    last = 0
    for k in range(n):
        speed = math.copysign(math.hypot(x[0], x[1]), x[0])
        readings = ctrl.step(sp[k], ss[k], yr[k], spr[k], speed)
        kv = readings.as_known_vector()
        fk = Fl[k]
        u = g_inputs(kv, fk)
        fplant = [fk[j] for j in plant_fault_idx]
        X[k] = x
        U[k] = u
        K[k] = kv
        for j in range(cfg.substeps):
            xdot, jac, ax, ay, rec = plant.rhs([*x, *u, *fplant, ax, ay], record=(j == 0))
            if rec is not None:
                A[k] = (ax, ay)
                REC[k] = rec
            x = [
                x[0] + h * xdot[0],
                x[1] + h * xdot[1],
                x[2] + h * xdot[2],
                *(x[3 + i] + h * xdot[3 + i] / (1.0 - h * jac[i]) for i in range(4)),
            ]
        if not all(math.isfinite(v) for v in x):
            raise SimulationDivergedError(f"simulation diverged at t = {t[k]:.3f} s: {x}")
        if progress is not None and (k - last >= 1000 or k == n - 1):
            progress(k + 1 - last)
            last = k + 1

    true: dict[str, FloatArray] = {s: X[:, i].copy() for i, s in enumerate(STATES)}
    true |= {s: U[:, i].copy() for i, s in enumerate(plant.inputs)}
    true |= {"ax": A[:, 0].copy(), "ay": A[:, 1].copy()}
    true |= {s: REC[:, i].copy() for i, s in enumerate(RECORDED)}
    true |= {f"demand_{c}": dem[c] for c in ("speed", "sideslip", "yaw_rate")}
    sig = dict(true) | {f: F[:, i] for i, f in enumerate(FAULT_IDS)}
    clean = {name: fn(sig) for name, fn in plant.measurement_functions().items()}
    # Actuator-side readings are what the actuators reported; the measurement equations reproduce them.
    for i, name in enumerate(plant.input_known_names):
        if not np.allclose(clean[name], K[:, i], atol=1e-9):
            raise AssertionError(f"measurement equation of {name} disagrees with the actuator reading")
    measured = add_noise(clean, seed, cfg.noise_scale)
    return SimResult(scenario, specs, seed, t, true, clean, measured, F, cfg)


# Sensor faults change only their own measured signal: the controller feeds back true values.
SENSOR_FAULTS: frozenset[str] = frozenset({"f1", "f2", "f3", "f4", "f5", "f22", "f23", "f24", "f25"})


def faulty_drive(base: SimResult, spec: FaultSpec, until: float | None = None) -> SimResult:
    """The drive of `base` (fault-free, same scenario and seed) with `spec` added, up to `until` (default: its
    end). Sensor faults reuse the simulation (measurement equations and noise recomputed); others are simulated
    again. A truth-plant drive has its own: `fdi_host.sim.truth_sim.faulty_truth_drive`."""
    if base.vehicle is not None:
        raise ValueError("a truth-plant drive: use fdi_host.sim.truth_sim.faulty_truth_drive")
    if spec.fault not in SENSOR_FAULTS:
        end = float(base.t[-1]) if until is None else min(until, float(base.t[-1]))
        return simulate(base.scenario, [spec], seed=base.seed, config=base.config, duration=end)
    F = base.fault_values + fault_matrix([spec], base.t)
    sig = dict(base.true) | {f: F[:, i] for i, f in enumerate(FAULT_IDS)}
    clean = {name: fn(sig) for name, fn in default_plant().measurement_functions().items()}
    measured = add_noise(clean, base.seed, base.config.noise_scale)
    return dataclasses.replace(base, faults=(spec,), clean=clean, measured=measured, fault_values=F)
