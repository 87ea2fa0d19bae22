"""Drive scenarios: a joystick-like motion demand {speed, side-slip angle, yaw rate} plus faults, from TOML.

A scenario file (``host_tools/scenarios/<name>.toml``)::

    [scenario]
    name = "fig6"
    description = "..."
    duration = 50.0          # s
    seed = 6                 # sensor noise seed
    initial_speed = 6.0      # m/s, vehicle rolling straight at t = 0

    [demand.speed]           # m/s; one table, or an array of tables [[demand.speed]] that add up
    kind = "pwl"             # const | pwl | sawtooth | square | sine
    t = [0, 10, 20]
    value = [6, 12, 8]
    smooth = 0.5             # s, first-order smoothing of the channel (joystick / rate limiting)

    [demand.yaw_rate]        # rad/s
    kind = "sawtooth"        # rises from -amplitude to +amplitude over each period
    amplitude = 0.3
    period = 12.0
    start = 4.0              # s, zero before (optional end = ..., offset = ...)

    [demand.sideslip]        # rad
    kind = "square"          # +amplitude for duty*period, then 0 (offset added)
    amplitude = 0.05
    period = 8.0
    duty = 0.25

    [road]                   # optional: grade, bank and friction patches, see fdi_host.sim.road

    [[fault]]                # optional, see fdi_host.sim.faults
    fault = "f4"
    onset = 10.0
    magnitude = 0.5
    duration = 6.0
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

from fdi_host import resources
from fdi_host.errors import FdiHostError
from fdi_host.sim.faults import FaultSpec, fault_from_table
from fdi_host.sim.road import Road, RoadError, road_from_dict

SCENARIO_DIR = resources.SCENARIOS.path()  # host_tools/scenarios in a checkout, the package's copy in a wheel
FAULT_SIZES_FILE = SCENARIO_DIR / "fault_sizes.toml"  # the required fault sizes, and the sizes the sweep states
SCENARIOS: tuple[str, ...] = ("straight", "cornering", "slalom", "fig6", "low_speed")  # the five manoeuvres
# The drives of real roads (grade and bank, stops and standstill, a wet patch): their [road] table needs the truth
# plant (the model plant has no road); the fleet suite drives all eight.
ROAD_SCENARIOS: tuple[str, ...] = ("country_road", "urban", "wet_patch")
FLEET_SCENARIOS: tuple[str, ...] = SCENARIOS + ROAD_SCENARIOS
CHANNELS: tuple[str, ...] = ("speed", "sideslip", "yaw_rate")
FloatArray = NDArray[np.float64]


class ScenarioError(FdiHostError, ValueError):
    """A scenario file that is not well formed."""


@dataclass(frozen=True)
class Profile:
    """One additive component of a demand channel."""

    kind: str
    params: Mapping[str, Any]

    def __call__(self, t: FloatArray) -> FloatArray:
        p = self.params
        start = float(p.get("start", 0.0))
        end = float(p.get("end", np.inf))
        offset = float(p.get("offset", 0.0))
        amp = float(p.get("amplitude", 0.0))
        period = float(p.get("period", 1.0))
        tau = t - start
        if self.kind == "const":
            base = np.full_like(t, float(p["value"]))
            return base
        if self.kind == "pwl":
            tt = np.asarray(p["t"], dtype=float)
            vv = np.asarray(p["value"], dtype=float)
            if tt.size != vv.size or tt.size < 1 or np.any(np.diff(tt) <= 0):
                raise ScenarioError("pwl needs increasing 't' and a 'value' list of the same length")
            return np.asarray(np.interp(t, tt, vv), dtype=float)
        if self.kind == "sawtooth":
            frac = np.mod(tau, period) / period
            wave = amp * (2.0 * frac - 1.0)
        elif self.kind == "square":
            duty = float(p.get("duty", 0.5))
            wave = np.where(np.mod(tau, period) < duty * period, amp, 0.0)
        elif self.kind == "sine":
            wave = amp * np.sin(2.0 * np.pi * tau / period)
        else:
            raise ScenarioError(f"unknown profile kind {self.kind!r} (const, pwl, sawtooth, square, sine)")
        active = (t >= start) & (t < end)
        return np.where(active, wave + offset, 0.0)


@dataclass(frozen=True)
class Channel:
    profiles: tuple[Profile, ...]
    smooth: float = 0.0  # s

    def sample(self, t: FloatArray) -> FloatArray:
        y = np.zeros_like(t)
        for pr in self.profiles:
            y = y + pr(t)
        if self.smooth > 0.0 and t.size > 1:
            dt = float(t[1] - t[0])
            a = float(np.exp(-dt / self.smooth))
            zi = np.array([a * y[0]])
            y = np.asarray(lfilter([1.0 - a], [1.0, -a], y, zi=zi)[0], dtype=float)
        return y


@dataclass(frozen=True)
class Scenario:
    name: str
    duration: float
    demand: Mapping[str, Channel]
    faults: tuple[FaultSpec, ...] = ()
    seed: int = 0
    initial_speed: float = 0.0
    description: str = ""
    source: Path | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)
    road: Road = field(default_factory=Road)  # the truth plant's road (grade, bank, friction patches)

    def demand_signals(self, t: FloatArray) -> dict[str, FloatArray]:
        """Demand channels at times `t` plus ``speed_rate`` (d/dt of the speed demand)."""
        out = {c: self.demand[c].sample(t) if c in self.demand else np.zeros_like(t) for c in CHANNELS}
        out["speed_rate"] = np.gradient(out["speed"], t) if t.size > 1 else np.zeros_like(t)
        return out


def _channel(value: Any, where: str) -> Channel:
    tables = value if isinstance(value, list) else [value]
    smooth = 0.0
    profiles = []
    for tab in tables:
        if not isinstance(tab, dict) or "kind" not in tab:
            raise ScenarioError(f"{where}: each demand table needs a 'kind'")
        smooth = max(smooth, float(tab.get("smooth", 0.0)))
        params = {k: v for k, v in tab.items() if k not in ("kind", "smooth")}
        profiles.append(Profile(str(tab["kind"]), params))
    return Channel(tuple(profiles), smooth)


def scenario_from_dict(doc: Mapping[str, Any], source: Path | None = None) -> Scenario:
    where = str(source or "<scenario>")
    meta = doc.get("scenario", {})
    if "duration" not in meta:
        raise ScenarioError(f"{where}: [scenario] needs a duration")
    demand_doc = doc.get("demand", {})
    unknown = set(demand_doc) - set(CHANNELS)
    if unknown:
        raise ScenarioError(f"{where}: unknown demand channels {sorted(unknown)}; use {CHANNELS}")
    demand = {c: _channel(v, f"{where}: demand.{c}") for c, v in demand_doc.items()}
    faults = tuple(fault_from_table(f) for f in doc.get("fault", []))
    try:
        road = road_from_dict(doc.get("road"), where)
    except RoadError as exc:
        raise ScenarioError(str(exc)) from exc
    known = {"name", "duration", "seed", "initial_speed", "description"}
    return Scenario(
        name=str(meta.get("name", source.stem if source else "scenario")),
        duration=float(meta["duration"]),
        demand=demand,
        faults=faults,
        seed=int(meta.get("seed", 0)),
        initial_speed=float(meta.get("initial_speed", 0.0)),
        description=str(meta.get("description", "")),
        source=source,
        extra={k: v for k, v in meta.items() if k not in known},
        road=road,
    )


def available() -> list[str]:
    """The vehicle scenarios of the scenario folder: the files with a [scenario] table (the fault-size files and the
    generic simulator's drives, e.g. three_tank.toml, beside them are not ones)."""
    names = []
    for p in sorted(SCENARIO_DIR.glob("*.toml")):
        try:
            doc = tomllib.loads(p.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
            continue  # loading it by name reports what is wrong
        if isinstance(doc.get("scenario"), dict):
            names.append(p.stem)
    return names


def load_scenario(name_or_path: str | Path) -> Scenario:
    """Load ``host_tools/scenarios/<name>.toml`` or a TOML file path."""
    p = Path(name_or_path)
    if not p.suffix:
        p = SCENARIO_DIR / f"{name_or_path}.toml"
    if not p.is_file():
        raise ScenarioError(f"no scenario {name_or_path!r}; available: {', '.join(available())}")
    try:
        doc = tomllib.loads(p.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{p}: not valid TOML: {exc}") from exc
    return scenario_from_dict(doc, p)
