"""A closed-loop drive on the truth plant: scenario demand -> geometric controller -> actuators -> truth plant
(`fdi_host.sim.truth_plant`) on the scenario's road -> truth sensors (`fdi_host.sim.truth_sensors`).

The controller is the model plant's (`fdi_host.sim.controller`, with its actuator dynamics: steering lag and rate
limit, motor current and brake pressure lags), tuned for the nominal vehicle: it knows nominal mass, radius,
motor and brake constants and steers the zero-slip geometry, and feeds back the true speed. A drawn vehicle
differs from what it was tuned for, as a production vehicle does. Faults enter where Table I places them:
f6..f9 between the steering actuator's reading and the true angle, f10..f21 in the plant, the sensor faults at the
sensors' outputs.

The result is a `SimResult` like the model plant's (labelled ``plant = "truth plant"`` with its vehicle), so CAN
traffic, replay and scoring take it unchanged. A fault case can restart from a snapshot of its fault-free drive
at the onset (`resume`): the fault-free part is shared, the sensors (causal) are recomputed over the whole.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from fdi_host.sim.controller import GeometricController, VehicleConstants
from fdi_host.sim.faults import FAULT_IDS, FaultSpec, fault_matrix
from fdi_host.sim.scenario import Scenario
from fdi_host.sim.truth_plant import (
    N_INPUT,
    N_PLANT_FAULTS,
    N_REC,
    RECORDED_NAMES,
    STATE_NAMES,
    initial_state,
    parameter_vector,
    step,
)
from fdi_host.sim.truth_sensors import clean_readings, measured_readings
from fdi_host.sim.tyre import parameter_array
from fdi_host.sim.vehicle_envelope import NOMINAL, Vehicle
from fdi_host.sim.vehicle_sim import SENSOR_FAULTS, SimConfig, SimResult, SimulationDivergedError

FloatArray = NDArray[np.float64]
TRUTH_PLANT = "truth plant"
STEER_FAULTS = [FAULT_IDS.index(f) for f in ("f6", "f7", "f8", "f9")]
PLANT_FAULTS = [FAULT_IDS.index(f"f{k}") for k in range(10, 22)]
INPUT_NAMES = ("delta1", "delta2", "delta3", "delta4", "iTM1", "iTM2", "iTM3", "iTM4", "P_f", "P_r")
READING_NAMES = ("delta1_m", "delta2_m", "delta3_m", "delta4_m", "iTM1_m", "iTM2_m", "iTM3_m", "iTM4_m",
                 "P_f_m", "P_r_m")


_step: Callable[..., bool] = step  # the compiled step (numba's dispatcher, called with the road's arrays)


class TruthDivergedError(SimulationDivergedError):
    """The truth plant's state became non-finite."""


def nominal_controller(dt: float, cfg: SimConfig) -> GeometricController:
    """The motion controller as tuned for the nominal vehicle (zero-slip steering of the nominal geometry)."""
    n = NOMINAL
    consts = VehicleConstants(n.m, n.R[0], n.J_w, n.K_TM[0], n.pad_mu[0] * n.piston_area * n.disc_radius)
    pos = ((n.l_f, n.w / 2), (n.l_f, -n.w / 2), (-n.l_r, n.w / 2), (-n.l_r, -n.w / 2))

    def contact(vx: float, vy: float, r: float) -> list[tuple[float, float]]:
        return [(vx - y * r, vy + x * r) for x, y in pos]

    return GeometricController(consts, contact, dt, cfg.controller)


@dataclass
class Snapshot:
    """The drive's full state before period `k`: plant state and controller."""

    k: int
    x: FloatArray
    controller: GeometricController


@dataclass
class _Run:
    """The arrays a drive fills, period by period."""

    X: FloatArray
    U: FloatArray
    K: FloatArray
    REC: FloatArray


def _loop(run: _Run, k0: int, k1: int, x: FloatArray, ctrl: GeometricController, dem: dict[str, FloatArray],
          F: FloatArray, vehicle: Vehicle, scenario: Scenario, cfg: SimConfig, snap_at: Sequence[int],
          progress: Callable[[int], None] | None) -> list[Snapshot]:
    p = parameter_vector(vehicle)
    tp = parameter_array()
    road = scenario.road.arrays()
    h = cfg.dt / cfg.substeps
    sp, ss, yr, spr = (dem[c].tolist() for c in ("speed", "sideslip", "yaw_rate", "speed_rate"))
    Fl = F.tolist()
    u = np.zeros(N_INPUT)
    fp = np.zeros(N_PLANT_FAULTS)
    rec = np.zeros(N_REC)
    snaps: list[Snapshot] = []
    wanted = set(snap_at)
    last = k0
    for k in range(k0, k1):
        if k in wanted:
            snaps.append(Snapshot(k, x.copy(), copy.deepcopy(ctrl)))
        speed = math.copysign(math.hypot(x[0], x[1]), x[0])
        readings = ctrl.step(sp[k], ss[k], yr[k], spr[k], speed)
        kv = readings.as_known_vector()
        fk = Fl[k]
        for i in range(4):
            u[i] = kv[i] + fk[STEER_FAULTS[i]]
        for i in range(4, N_INPUT):
            u[i] = kv[i]
        for i, j in enumerate(PLANT_FAULTS):
            fp[i] = fk[j]
        run.X[k] = x
        run.U[k] = u
        run.K[k] = kv
        if not _step(x, u, fp, p, tp, *road, h, cfg.substeps, rec):
            raise TruthDivergedError(f"truth plant diverged at t = {k * cfg.dt:.3f} s ({vehicle.label}, "
                                     f"{scenario.name})")
        run.REC[k] = rec
        if progress is not None and (k - last >= 1000 or k == k1 - 1):
            progress(k + 1 - last)
            last = k + 1
    return snaps


def _result(scenario: Scenario, specs: tuple[FaultSpec, ...], seed: int, t: FloatArray, run: _Run,
            dem: dict[str, FloatArray], F: FloatArray, vehicle: Vehicle, cfg: SimConfig) -> SimResult:
    true: dict[str, FloatArray] = {s: run.X[:, i].copy() for i, s in enumerate(STATE_NAMES)}
    true |= {s: run.U[:, i].copy() for i, s in enumerate(INPUT_NAMES)}
    true |= {s: run.REC[:, i].copy() for i, s in enumerate(RECORDED_NAMES)}
    true |= {f"demand_{c}": dem[c] for c in ("speed", "sideslip", "yaw_rate")}
    readings = {s: run.K[:, i].copy() for i, s in enumerate(READING_NAMES)}
    clean = clean_readings(true, readings, t, F, vehicle, cfg.dt)
    measured = measured_readings(clean, seed, cfg.noise_scale)
    return SimResult(scenario, specs, seed, t, true, clean, measured, F, cfg, plant=TRUTH_PLANT, vehicle=vehicle)


def simulate_truth(
    scenario: Scenario,
    faults: Sequence[FaultSpec] | None = None,
    *,
    vehicle: Vehicle = NOMINAL,
    seed: int | None = None,
    config: SimConfig | None = None,
    duration: float | None = None,
    progress: Callable[[int], None] | None = None,
    snapshots: Sequence[float] = (),
) -> SimResult:
    """Drive `scenario` with `faults` (default: the scenario's own) on `vehicle`; `snapshots` are times at which
    the drive's state is kept (in ``result.snapshots``) for `resume`."""
    cfg = config or SimConfig()
    specs = tuple(scenario.faults if faults is None else faults)
    seed = scenario.seed if seed is None else seed
    T = scenario.duration if duration is None else duration
    n = round(T / cfg.dt) + 1
    t: FloatArray = np.arange(n, dtype=float) * cfg.dt
    dem = scenario.demand_signals(t)
    F = fault_matrix(specs, t)
    ctrl = nominal_controller(cfg.dt, cfg)
    ctrl.preset(float(dem["speed"][0]), float(dem["sideslip"][0]), float(dem["yaw_rate"][0]))
    x = initial_state(vehicle, scenario.initial_speed)
    run = _Run(np.empty((n, len(STATE_NAMES))), np.empty((n, N_INPUT)), np.empty((n, N_INPUT)),
               np.empty((n, N_REC)))
    snaps = _loop(run, 0, n, x, ctrl, dem, F, vehicle, scenario, cfg,
                  [min(n - 1, round(s / cfg.dt)) for s in snapshots], progress)
    res = _result(scenario, specs, seed, t, run, dem, F, vehicle, cfg)
    res.snapshots = {s.k: s for s in snaps}
    res.runs = run
    return res


def resume(base: SimResult, spec: FaultSpec, until: float | None = None) -> SimResult:
    """The drive of `base` (a fault-free truth-plant drive with a snapshot at the fault's onset) with `spec`
    added, simulated from the onset to `until` (default: the end of `base`): the fault-free part is shared."""
    if base.vehicle is None or not isinstance(base.runs, _Run):
        raise ValueError("resume needs a truth-plant drive of simulate_truth")
    cfg = base.config
    k0 = round(spec.onset / cfg.dt)
    snap = base.snapshots.get(k0)
    if snap is None:
        raise ValueError(f"no snapshot at the onset {spec.onset} s (snapshots: {sorted(base.snapshots)})")
    n = base.t.size if until is None else min(base.t.size, round(until / cfg.dt) + 1)
    t = base.t[:n]
    F = base.fault_values[:n] + fault_matrix([spec], t)
    dem = {c: base.true[f"demand_{c}"][:n] for c in ("speed", "sideslip", "yaw_rate")}
    dem["speed_rate"] = base.scenario.demand_signals(t)["speed_rate"]
    src = base.runs
    run = _Run(src.X[:n].copy(), src.U[:n].copy(), src.K[:n].copy(), src.REC[:n].copy())
    _loop(run, k0, n, snap.x.copy(), copy.deepcopy(snap.controller), dem, F, base.vehicle, base.scenario, cfg,
          (), None)
    return _result(base.scenario, (*base.faults, spec), base.seed, t, run, dem, F, base.vehicle, cfg)


def faulty_truth_drive(base: SimResult, spec: FaultSpec, until: float | None = None) -> SimResult:
    """`base` with `spec`: sensor faults recompute only the sensors (the motion is the same), others `resume`."""
    if spec.fault not in SENSOR_FAULTS:
        return resume(base, spec, until)
    if base.vehicle is None or not isinstance(base.runs, _Run):
        raise ValueError("faulty_truth_drive needs a truth-plant drive of simulate_truth")
    n = base.t.size if until is None else min(base.t.size, round(until / base.config.dt) + 1)
    t = base.t[:n]
    F = base.fault_values[:n] + fault_matrix([spec], t)
    true = {k: v[:n] for k, v in base.true.items()}
    readings = {s: base.runs.K[:n, i].copy() for i, s in enumerate(READING_NAMES)}
    clean = clean_readings(true, readings, t, F, base.vehicle, base.config.dt)
    measured = measured_readings(clean, base.seed, base.config.noise_scale)
    return dataclasses.replace(base, faults=(*base.faults, spec), t=t, true=true, clean=clean, measured=measured,
                               fault_values=F, snapshots={}, runs=None)
