"""The host tools from a notebook or a script: simulate a drive, diagnose it (or a recorded CAN log) with the C ECU
core, and get the diagnosis step by step as arrays or a DataFrame.

    import fdi_host
    drive = fdi_host.simulate("fig6", faults=["f4@8s:0.5:end=14s"], duration=20)   # model plant, seeded noise
    d = fdi_host.diagnose(drive)                 # the ECU ("romo" table) on the drive's CAN traffic
    d.time, d.detected, d.candidates, d.ratios   # per step (fdi_host.diagnosis.Diagnosis)
    d.to_dataframe(); d.plot(ax=ax)
    d = fdi_host.diagnose_log("drive.blf")       # a recorded log (.log, .asc, .blf) the same way

``fdi_host.replay`` is the ``fdi-replay`` program's module, so the function for a log is `diagnose_log` (or
`diagnose` with the log's path).

Time base: that of ``fdi-ecu`` and ``fdi-replay`` (`fdi_host.ecu.session`): the drive's t = 0 (a log's first frame,
unless `t0` says otherwise) lies half a millisecond after the ECU's origin, its step schedule starts at the origin,
and every frame runs the steps due before it, then is received. A step's time in the `Diagnosis` is its boundary
k * dt, as ``fdi-replay`` and ``fdi-monitor`` time it (on the drive's clock the step sees the frames sent before
k * dt - 0.5 ms). A drive and the log written from it are diagnosed alike, step for step.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from fdi_analysis.tables import html_table, require_pandas
from fdi_host.can.dbc import DIAG_ID
from fdi_host.can.frame import Frame
from fdi_host.diagnosis import Diagnosis
from fdi_host.ecu.bindings import Ecu, EcuResult, table_info
from fdi_host.ecu.session import ORIGIN_LEAD
from fdi_host.sim.faults import FaultSpec, parse_fault
from fdi_host.sim.scenario import Scenario, load_scenario
from fdi_host.sim.vehicle_envelope import NOMINAL, Vehicle, draw_vehicle
from fdi_host.sim.vehicle_sim import SimConfig, SimResult

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["Diagnosis", "Drive", "diagnose", "diagnose_log", "simulate"]

FaultsArg = str | FaultSpec | Iterable[str | FaultSpec] | None
VehicleArg = Vehicle | str | int | None
DEFAULT_SIGNALS = ("vx_m", "vy_m", "psidot_m", "ax_m", "ay_m")


@dataclass(frozen=True, repr=False, eq=False)
class Drive:
    """A simulated drive (`result`: the simulator's `SimResult`, which the lower layers take) with what a notebook
    asks of it: its signals as a table, a plot, its CAN frames and log."""

    result: SimResult

    @property
    def t(self) -> np.ndarray[Any, np.dtype[np.float64]]:
        return self.result.t

    @property
    def duration(self) -> float:
        return float(self.result.t[-1]) if self.result.t.size else 0.0

    @property
    def faults(self) -> tuple[FaultSpec, ...]:
        return self.result.faults

    @property
    def label(self) -> str:
        """The scenario, plant and vehicle, as figures name the drive."""
        return f"{self.result.scenario.name}, {self.result.label}"

    @cached_property
    def frames(self) -> list[Frame]:
        """The drive's CAN traffic (DBC-encoded, E2E protected, on the drive's clock), made once."""
        from fdi_host.can.traffic import build_frames

        return build_frames(self.result)

    def write_log(self, path: str | os.PathLike[str]) -> Path:
        """The CAN traffic as a log file (.log, .asc or .blf by the extension); returns the path."""
        from fdi_host.can.logs import write_log

        write_log(self.frames, Path(path))
        return Path(path)

    def with_fault(self, fault: str | FaultSpec) -> Drive:
        """This fault-free drive with `fault` added (same scenario, seed and vehicle): sensor faults recompute the
        sensors only, the others simulate again (the truth plant from a snapshot, when the drive kept one)."""
        spec = parse_fault(fault) if isinstance(fault, str) else fault
        if self.result.vehicle is None:
            from fdi_host.sim.vehicle_sim import faulty_drive

            return Drive(faulty_drive(self.result, spec))
        from fdi_host.sim.truth_sim import faulty_truth_drive

        return Drive(faulty_truth_drive(self.result, spec))

    def to_dataframe(self, which: str = "measured") -> Any:
        """The drive's signals at 1 kHz as a pandas DataFrame indexed by time [s]: ``measured`` (the sensors, with
        faults and noise), ``clean`` (without noise) or ``true`` (states, inputs, demand)."""
        signals = {"measured": self.result.measured, "clean": self.result.clean, "true": self.result.true}
        if which not in signals:
            raise ValueError(f"which = {which!r}: use one of {tuple(signals)}")
        pd = require_pandas()
        return pd.DataFrame(dict(signals[which]), index=pd.Index(self.result.t, name="time [s]"))

    def plot(self, signals: Sequence[str] = DEFAULT_SIGNALS, ax: Axes | None = None) -> Figure:
        """Measured `signals` over time with the fault windows shaded, into `ax` or a new figure."""
        import matplotlib.pyplot as plt
        from matplotlib.figure import Figure

        from fdi_host.sim.plots import shade_faults

        unknown = [s for s in signals if s not in self.result.measured]
        if unknown:
            raise ValueError(f"not measured signals: {unknown}; they are {', '.join(self.result.measured)}")
        if ax is None:
            fig, ax = plt.subplots(figsize=(9.0, 3.5))
        else:
            owner = ax.get_figure()
            assert isinstance(owner, Figure)
            fig = owner
        for s in signals:
            ax.plot(self.result.t, self.result.measured[s], lw=0.7, label=s)
        shade_faults(ax, self.result)
        ax.set_xlabel("time [s]")
        ax.set_title(self.label, fontsize=9)
        ax.legend(fontsize=7, loc="upper left")
        ax.grid(alpha=0.3)
        fig.tight_layout()
        return fig

    def __repr__(self) -> str:
        faults = ", ".join(f.describe() for f in self.faults[:4]) or "none"
        more = f" (+{len(self.faults) - 4} more)" if len(self.faults) > 4 else ""
        return f"Drive({self.label}: {self.duration:.1f} s, seed {self.result.seed}; faults {faults}{more})"

    def _repr_html_(self) -> str:
        rows: list[list[object]] = [[f.onset, "-" if f.end is None else f.end, f.magnitude, f.shape, f.describe()]
                                    for f in self.faults]
        return html_table(rows, ["onset [s]", "end [s]", "magnitude", "shape", "as text"],
                          [f.fault for f in self.faults], repr(self), "fault")


# ------------------------------------------------------------------------------------------ simulate
def _scenario(scenario: str | os.PathLike[str] | Scenario) -> Scenario:
    if isinstance(scenario, Scenario):
        return scenario
    return load_scenario(scenario if isinstance(scenario, str) else Path(scenario))


def _faults(faults: FaultsArg) -> list[FaultSpec] | None:
    if faults is None:
        return None
    items = [faults] if isinstance(faults, str | FaultSpec) else list(faults)
    return [parse_fault(f) if isinstance(f, str) else f for f in items]


def _vehicle(vehicle: VehicleArg) -> Vehicle | None:
    if vehicle is None or isinstance(vehicle, Vehicle):
        return vehicle
    if vehicle == "nominal":
        return NOMINAL
    if isinstance(vehicle, int) and not isinstance(vehicle, bool):
        return draw_vehicle(vehicle)
    raise ValueError(f"vehicle = {vehicle!r}: None (the model plant), 'nominal', a seed (int) or a Vehicle")


def simulate(scenario: str | os.PathLike[str] | Scenario = "fig6", faults: FaultsArg = None, *,
             vehicle: VehicleArg = None, seed: int | None = None, duration: float | None = None,
             noise: bool = True) -> Drive:
    """Drive `scenario` (a shipped scenario's name, a scenario file, or a `Scenario`) in closed loop.

    `faults`: None for the scenario's own, else the faults instead of them (``[]``: none): specs as ``fdi-sim
    --fault`` takes them (``"f4@5s:0.5"``, ``"f6@10s:0.02:ramp=2s"``) or `FaultSpec`s. `vehicle`: None for the model
    plant (the diagnosis model's equations), else the truth plant with ``"nominal"``, a drawn vehicle's seed, or a
    `Vehicle`. `seed`: the sensor noise (default the scenario's); `duration` [s] (default the scenario's);
    ``noise=False`` switches the sensor noise off."""
    sc = _scenario(scenario)
    specs = _faults(faults)
    cfg = SimConfig(noise_scale=1.0 if noise else 0.0)
    veh = _vehicle(vehicle)
    if veh is None:
        from fdi_host.sim.vehicle_sim import simulate as simulate_model

        return Drive(simulate_model(sc, specs, seed=seed, config=cfg, duration=duration))
    from fdi_host.sim.truth_sim import simulate_truth

    return Drive(simulate_truth(sc, specs, vehicle=veh, seed=seed, config=cfg, duration=duration))


# ------------------------------------------------------------------------------------------ diagnose
def ecu_steps(table: str, frames: Iterable[Frame], t0: float, **ecu_options: Any) -> list[EcuResult]:
    """The ECU's result after every diagnosis step for `frames` (timestamps on a clock whose drive t = 0 is `t0`),
    on the time base of ``fdi-ecu`` and ``fdi-replay`` (the module's doc); the ECU's own frames are left out."""
    ecu = Ecu(table, **ecu_options)
    ecu.poll(0.0)  # the step schedule starts at the origin, ORIGIN_LEAD before the drive's t = 0
    out: list[EcuResult] = []
    for f in frames:
        if f.frame_id == DIAG_ID:
            continue
        t = f.timestamp - t0 + ORIGIN_LEAD
        ecu.rx(f.frame_id, f.data, t)
        if any(fid == DIAG_ID for fid, _ in ecu.poll(t)):
            out.append(ecu.result())
    return out


def diagnose(source: Drive | SimResult | Sequence[Frame] | str | os.PathLike[str], table: str = "romo", *,
             t0: float | None = None, **ecu_options: Any) -> Diagnosis:
    """The ECU core on table `table` (``"romo"``: the generated ROMO table; ``"kin"``: the kinematic one) over a
    drive's CAN traffic, a list of frames, or a log file (its path), step by step.

    `t0`: the time of the drive's t = 0 on the frames' clock (default: 0 for a drive, the first frame's time for
    frames and logs). `ecu_options`: the ECU's settings (`fdi_host.ecu.bindings.Ecu`: ``mode``, ``cusum_h``,
    ``estimate``, ``timeout_s``, ...)."""
    if isinstance(source, str | os.PathLike):
        return diagnose_log(source, table, t0=t0, **ecu_options)
    if isinstance(source, Drive | SimResult):
        drive = source if isinstance(source, Drive) else Drive(source)
        return _diagnose(drive.frames, 0.0 if t0 is None else t0, drive.label, table, ecu_options)
    return _diagnose(source, t0, f"{len(source)} frames", table, ecu_options)


def diagnose_log(path: str | os.PathLike[str], table: str = "romo", *, t0: float | None = None,
                 **ecu_options: Any) -> Diagnosis:
    """`diagnose` of a recorded CAN log (.log candump, .asc, .blf), as ``fdi-replay --offline`` runs it, but with
    every step's per-test status, residual and ratio. `t0` as in `diagnose` (default: the first frame's time)."""
    from fdi_host.can.logs import read_log

    return _diagnose(read_log(Path(path)), t0, str(path), table, ecu_options)


def _diagnose(frames: Sequence[Frame], t0: float | None, label: str, table: str,
              ecu_options: dict[str, Any]) -> Diagnosis:
    origin = t0 if t0 is not None else (frames[0].timestamp if frames else 0.0)
    steps = ecu_steps(table, frames, origin, **ecu_options)
    return Diagnosis.from_results(steps, table_info(table), label)
