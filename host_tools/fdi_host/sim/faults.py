"""Fault injection as in Table I of the paper: additive faults f1..f25 with onset, magnitude and shape.

Where each fault enters is read from the model (the equations that contain the fault symbol):

* f1..f5 (S1..S5) and f22..f25 (S.omega_i): sensor faults, they change one measured signal only;
* f6..f9 (S.delta_i): steering offset ``delta_i = delta_i_m + f``. The steering actuator closes its loop on
  the *measured* angle, so the measured angle follows the command and the true angle is off by f;
* f10..f13 (W_i.TM): motor torque; f14..f17 (W_i.DB): brake torque; f18..f21 (W_i.FL, W_i.FS): tyre forces.

A fault is given in a scenario file (``[[fault]]`` tables) or on the command line::

    f4@5s:0.5                  step of 0.5 (the fault's unit, here m/s) from t = 5 s on
    f6@10s:0.02:ramp=2s        ramp from 0 at 10 s to 0.02 rad at 12 s, then held
    f10@3s:-80:end=9s          step from 3 s to 9 s
    f22@4s:2:intermittent=1s/0.3   on for 30 % of every 1 s period from 4 s on
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from fdi_host.errors import FdiHostError

FAULT_IDS: tuple[str, ...] = tuple(f"f{k}" for k in range(1, 26))
Shape = Literal["step", "ramp", "intermittent"]
FloatArray = NDArray[np.float64]


class FaultSpecError(FdiHostError, ValueError):
    """A fault given in a form that cannot be understood."""


@dataclass(frozen=True)
class FaultSpec:
    fault: str
    onset: float
    magnitude: float
    shape: Shape = "step"
    ramp: float = 0.0  # s, ramp time to full magnitude ("ramp")
    period: float = 1.0  # s ("intermittent")
    duty: float = 0.5  # on-fraction of each period ("intermittent")
    end: float | None = None  # s, fault removed at this time (None: stays)

    def __post_init__(self) -> None:
        if not self.fault.isidentifier():
            raise FaultSpecError(f"bad fault name {self.fault!r}")
        if self.shape not in ("step", "ramp", "intermittent"):
            raise FaultSpecError(f"{self.fault}: unknown shape {self.shape!r}")
        if self.shape == "ramp" and self.ramp <= 0.0:
            raise FaultSpecError(f"{self.fault}: a ramp needs ramp > 0")
        if self.shape == "intermittent" and not (self.period > 0.0 and 0.0 < self.duty <= 1.0):
            raise FaultSpecError(f"{self.fault}: intermittent needs period > 0 and 0 < duty <= 1")
        if self.end is not None and self.end <= self.onset:
            raise FaultSpecError(f"{self.fault}: end {self.end} is not after onset {self.onset}")

    @property
    def index(self) -> int:
        """The fault's column among ROMO's faults (Table I)."""
        return FAULT_IDS.index(self.fault)

    def profile(self, t: FloatArray) -> FloatArray:
        """Fault value at times `t`."""
        on = t >= self.onset
        if self.end is not None:
            on &= t < self.end
        tau = t - self.onset
        if self.shape == "ramp":
            shape = np.clip(tau / self.ramp, 0.0, 1.0)
        elif self.shape == "intermittent":
            shape = (np.mod(np.maximum(tau, 0.0), self.period) < self.duty * self.period).astype(float)
        else:
            shape = np.ones_like(t)
        return np.where(on, self.magnitude * shape, 0.0)

    def describe(self) -> str:
        s = f"{self.fault}@{self.onset:g}s:{self.magnitude:g}"
        if self.shape == "ramp":
            s += f":ramp={self.ramp:g}s"
        if self.shape == "intermittent":
            s += f":intermittent={self.period:g}s/{self.duty:g}"
        if self.end is not None:
            s += f":end={self.end:g}s"
        return s


_TIME = r"([-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?)(ms|s)?"


def _seconds(text: str, what: str) -> float:
    m = re.fullmatch(_TIME, text.strip())
    if not m:
        raise FaultSpecError(f"bad time {text!r} for {what} (use e.g. 5s, 250ms or 5)")
    v = float(m.group(1))
    return v / 1000.0 if m.group(2) == "ms" else v


def _known(spec: FaultSpec, names: Sequence[str]) -> FaultSpec:
    if spec.fault not in names:
        which = "f1..f25 (Table I)" if tuple(names) == FAULT_IDS else ", ".join(names)
        raise FaultSpecError(f"unknown fault {spec.fault!r}; faults are {which}")
    return spec


def parse_fault(text: str, names: Sequence[str] = FAULT_IDS) -> FaultSpec:
    """Parse ``fID@ONSET:MAGNITUDE[:ramp=T][:end=T][:for=T][:intermittent=PERIOD[/DUTY]]``, a fault of `names`
    (ROMO's by default; a vehicle's model's for another vehicle)."""
    head, _, rest = text.partition(":")
    if "@" not in head or not rest:
        raise FaultSpecError(f"bad fault {text!r}; expected e.g. f4@5s:0.5 or f6@10s:0.02:ramp=2s")
    fid, onset_txt = head.split("@", 1)
    parts = rest.split(":")
    try:
        magnitude = float(parts[0])
    except ValueError as exc:
        raise FaultSpecError(f"bad magnitude {parts[0]!r} in {text!r}") from exc
    onset = _seconds(onset_txt, "onset")
    kw: dict[str, Any] = {}
    for p in parts[1:]:
        key, _, val = p.partition("=")
        if key == "ramp":
            kw["shape"], kw["ramp"] = "ramp", _seconds(val, "ramp")
        elif key == "end":
            kw["end"] = _seconds(val, "end")
        elif key == "for":
            kw["end"] = onset + _seconds(val, "for")
        elif key == "intermittent":
            per, _, duty = val.partition("/")
            kw["shape"], kw["period"] = "intermittent", _seconds(per, "period")
            if duty:
                kw["duty"] = float(duty)
        else:
            raise FaultSpecError(f"unknown fault option {key!r} in {text!r} (ramp, end, for, intermittent)")
    return _known(FaultSpec(fault=fid.strip(), onset=onset, magnitude=magnitude, **kw), names)


def fault_from_table(tab: Mapping[str, Any], names: Sequence[str] = FAULT_IDS) -> FaultSpec:
    """A ``[[fault]]`` table of a scenario file (keys as `FaultSpec` fields; ``duration`` sets ``end``)."""
    allowed = {"fault", "onset", "magnitude", "shape", "ramp", "period", "duty", "end", "duration"}
    unknown = set(tab) - allowed
    if unknown:
        raise FaultSpecError(f"unknown keys {sorted(unknown)} in fault table {dict(tab)}")
    kw = {k: v for k, v in tab.items() if k != "duration"}
    if "duration" in tab:
        kw["end"] = float(tab["onset"]) + float(tab["duration"])
    for k in ("onset", "magnitude", "ramp", "period", "duty", "end"):
        if k in kw and kw[k] is not None:
            kw[k] = float(kw[k])
    return _known(FaultSpec(**kw), names)


def fault_matrix(specs: Iterable[FaultSpec], t: FloatArray, names: Sequence[str] = FAULT_IDS) -> FloatArray:
    """(len(t), len(names)) fault values (ROMO's 25 by default); several specs of one fault add up."""
    out = np.zeros((t.size, len(names)))
    for s in specs:
        out[:, list(names).index(_known(s, names).fault)] += s.profile(t)
    return out


def active_intervals(values: FloatArray, t: FloatArray) -> list[tuple[float, float]]:
    """Maximal [start, end) intervals where `values` is nonzero (end = last sample + dt)."""
    on = values != 0.0
    if not on.any():
        return []
    dt = float(t[1] - t[0]) if t.size > 1 else 0.0
    edges = np.flatnonzero(np.diff(np.concatenate(([0], on.astype(np.int8), [0]))))
    return [(float(t[a]), float(t[b - 1] + dt)) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def ground_truth(
    specs: Sequence[FaultSpec], t: FloatArray, fault_info: Mapping[str, Mapping[str, Any]],
    names: Sequence[str] = FAULT_IDS,
) -> dict[str, Any]:
    """JSON-ready ground truth: the specs and, per fault of `names`, when it is active and with which values."""
    F = fault_matrix(specs, t, names)
    faults = []
    for k, fid in enumerate(names):
        col = F[:, k]
        if not col.any():
            continue
        iv = active_intervals(col, t)
        faults.append(
            {
                "fault": fid,
                **{key: fault_info.get(fid, {}).get(key, "") for key in ("unit", "desc", "equations")},
                "intervals": [
                    {
                        "start": a,
                        "end": b,
                        "min": float(col[(t >= a) & (t < b)].min()),
                        "max": float(col[(t >= a) & (t < b)].max()),
                    }
                    for a, b in iv
                ],
            }
        )
    return {"specs": [asdict(s) | {"text": s.describe()} for s in specs], "faults": faults}
