"""One ECU instance fed with timestamped frames: the code path shared by ``fdi-ecu`` (live, on a bus) and
``fdi-replay --offline`` (a log straight through the bindings), so both see exactly the same calls.

Time base. The C core counts time from an origin (uint32 microseconds). The origin is the first frame's
timestamp minus half a millisecond (`ORIGIN_LEAD`): the simulator sends on whole milliseconds, so every frame
sits 0.5 ms after a millisecond mark, never on a diagnosis step boundary. A few tenths of a millisecond of bus
jitter therefore cannot move a frame across a boundary, and a live run and an offline replay of the same
frames cross the same boundaries with the same inputs.

Live, the sender can announce the wall time of the drive's t = 0 (``--origin-file``), which then replaces
the first frame's receive time (that one frame may be delayed by a cold start). An ECU process started (or
restarted) while the drive is under way anchors to the same origin and starts its steps at the last step
boundary before its first frame (`EcuSession.anchor` with ``first_wall``). The first call is ``poll(0)``
at the origin: the C core starts its step schedule T_k = t_first + k * dt at
its first call, so the boundaries fall on whole milliseconds of the drive and the frames half way between.
Order per frame: ``poll(t)`` first (runs the steps that are due strictly from the frames received before),
then ``rx(t)``. A step's diagnosis frame is therefore sent as soon as the first frame after the step boundary
arrives, and it never includes data from after the boundary. Every step that produced a frame is recorded
(`StepRecord`), including its residuals and test ratios, which the bus frame does not carry.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field, is_dataclass
from pathlib import Path
from typing import Any

from fdi_host.can.dbc import DIAG_ID
from fdi_host.ecu.records import DiagRecord, TableClasses

__all__ = ["DIAG_ID", "ORIGIN_LEAD", "EcuSession", "StepRecord", "load_steps", "table_classes"]

ORIGIN_LEAD = 0.0005  # s


@dataclass
class StepRecord:
    step: int
    t: float  # ECU time of the frame that triggered the step [s]
    trigger_id: int
    trigger_counter: int
    trigger_wall: float  # timestamp of that frame (receive time live, log time offline)
    tx_wall: float  # wall-clock time just before the diagnosis frame was handed to the bus (0 offline)
    alarm_mask: int
    evaluable_mask: int
    candidates: int
    iso_class: int
    residuals: list[float]
    ratios: list[float]
    diag_counter: int


def _due(t: float, step: float) -> bool:
    """Whether the C core runs the step at ECU time `step` when called at `t`: the bindings round times to whole
    microseconds and the core runs the steps strictly before the call's microsecond (a frame in the same
    microsecond as a step boundary does not run it; the next frame does)."""
    return round(t * 1e6) > round(step * 1e6)


def _get(obj: Any, *names: str, default: Any = None) -> Any:
    for n in names:
        if hasattr(obj, n):
            return getattr(obj, n)
    return default


def table_classes(ecu: Any) -> TableClasses:
    """Signatures and structural isolability classes of the ECU's table (`bindings.TableInfo`, or an `Ecu`).

    A fault's signature counts only the tests that have an on-board generator (the others are never
    evaluable, so they cannot detect anything); its class is the table's structural isolability class.
    """
    info = getattr(ecu, "table", ecu)
    n_faults = int(info.n_faults)
    sig = [0] * n_faults
    for i, mask in enumerate(info.test_fault_masks):
        if info.has_generator[i]:
            for j in range(n_faults):
                if mask >> j & 1:
                    sig[j] |= 1 << i
    names = tuple(str(n).split(":")[0] for n in info.test_names)
    return TableClasses(tuple(sig), tuple(int(c) for c in info.iso_class[:n_faults]), names, tuple(info.faults))


@dataclass
class EcuSession:
    """Feeds frames with absolute timestamps [s] to an `fdi_host.ecu.bindings.Ecu`; collects what it sends."""

    table: str = "kin"
    origin: float | None = None
    last_t: float = 0.0
    steps: list[StepRecord] = field(default_factory=list)
    frames_in: int = 0
    ecu: Any = None
    next_step: float = 0.0  # ECU time of the next step not yet run [s]; due for a frame in a later microsecond
    dt: float = 0.01  # diagnosis step [s], from the table
    diag_id: int = DIAG_ID  # the ECU's diagnosis frame on its vehicle's bus

    def __post_init__(self) -> None:
        if self.ecu is None:
            from fdi_host.ecu.bindings import Ecu

            self.ecu = Ecu(self.table)
        self.dt = float(self.ecu.step_s)
        bus = getattr(self.ecu, "bus", None)
        if bus is not None:
            self.diag_id = int(bus.diag_id)

    def _t(self, wall: float) -> float:
        origin = self.origin if self.origin is not None else wall - ORIGIN_LEAD
        return max(self.last_t, wall - origin)

    def feed(self, frame_id: int, data: bytes, wall: float, now: float = 0.0) -> list[tuple[int, bytes]]:
        """One received frame (timestamp `wall`); returns the diagnosis frames to send now."""
        if frame_id == self.diag_id:  # our own frame echoed by the bus
            return []
        out: list[tuple[int, bytes]] = []
        if self.origin is None:  # anchor the step schedule (T_k = k * dt) half a millisecond before the frame
            out += self.anchor(wall, now)
        t = self._t(wall)
        if _due(t, self.next_step):  # a poll with no step due does nothing: skip the call
            out += self._poll(t, frame_id, data, wall, now)
        self.ecu.rx(frame_id, data, t)
        self.frames_in += 1
        self.last_t = t
        return out

    def feed_many(self, frames: Iterable[tuple[int, bytes, float]]) -> None:
        """`feed` for a whole log, as fast as possible (offline replay): the same calls in the same order,
        with the per-frame Python work cut to the minimum (own frames skipped, poll only when a step is due)."""
        rx = self.ecu.rx
        own = self.diag_id
        n = 0
        t = self.last_t
        for frame_id, data, wall in frames:
            if frame_id == own:
                continue
            if self.origin is None:
                self.anchor(wall)
            origin = self.origin if self.origin is not None else wall
            t = max(t, wall - origin)
            if _due(t, self.next_step):
                self._poll(t, frame_id, data, wall, 0.0)
            rx(frame_id, data, t)
            n += 1
        self.frames_in += n
        self.last_t = t

    def anchor(self, t0_wall: float, now: float = 0.0, first_wall: float | None = None) -> list[tuple[int, bytes]]:
        """Start the step schedule: the drive's t = 0 is at wall time `t0_wall` (default: the first frame).

        `first_wall`: receive time of the first frame, when this ECU joins a drive already under way (a
        restarted ECU process): the C core then starts at the last step boundary k * dt before that frame,
        on the same grid as from t = 0, instead of catching up (and skipping) every step since t = 0.
        """
        self.origin = t0_wall - ORIGIN_LEAD
        t_start = 0.0
        if first_wall is not None:
            k = math.floor(round((first_wall - self.origin) / self.dt, 6))
            t_start = max(0, k) * self.dt
        self.last_t = t_start
        return self._poll(t_start, -1, b"", self.origin + t_start, now)

    def tick(self, wall_now: float, grace: float = 0.002) -> list[tuple[int, bytes]]:
        """Timer poll: steps due `grace` before now (frames in flight are not overtaken)."""
        if self.origin is None:
            return []
        t = wall_now - grace - self.origin
        if t <= self.last_t:
            return []
        self.last_t = t
        return self._poll(t, -1, b"", wall_now - grace, wall_now)

    def _poll(self, t: float, trig_id: int, trig_data: bytes, wall: float, now: float) -> list[tuple[int, bytes]]:
        frames: list[tuple[int, bytes]] = list(self.ecu.poll(t))
        step_us = round(self.dt * 1e6)
        self.next_step = -(-round(t * 1e6) // step_us) * self.dt  # the C core ran every step before t's microsecond
        if frames:
            r = self.ecu.result()
            _fid, data = frames[-1]
            self.steps.append(
                StepRecord(
                    step=int(_get(r, "step", default=len(self.steps))),
                    t=t, trigger_id=trig_id, trigger_counter=(trig_data[1] & 0x0F) if len(trig_data) > 1 else -1,
                    trigger_wall=wall, tx_wall=now,
                    alarm_mask=int(r.alarm_mask), evaluable_mask=int(r.evaluable_mask),
                    candidates=int(r.candidates), iso_class=int(_get(r, "iso_class", default=0)),
                    residuals=[float(x) for x in _get(r, "residuals", default=[])],
                    ratios=[float(x) for x in _get(r, "ratios", default=[])],
                    diag_counter=data[1] & 0x0F if len(data) > 1 else -1,
                )
            )
        return frames

    def finish(self, t_end_wall: float) -> list[tuple[int, bytes]]:
        """Run the step that is due at the end of the data (offline: one step after the last frame)."""
        if self.origin is None:
            return []
        t = t_end_wall - self.origin
        if t <= self.last_t:
            return []
        self.last_t = t
        return self._poll(t, -1, b"", t_end_wall, 0.0)

    def records(self) -> list[DiagRecord]:
        """Diagnosis per step on the drive's clock (ECU time minus the origin lead)."""
        return [DiagRecord(s.t - ORIGIN_LEAD, s.alarm_mask, s.candidates, s.iso_class) for s in self.steps]

    def to_json(self) -> dict[str, Any]:
        counters = self.ecu.counters()
        cnt: Any = asdict(counters) if is_dataclass(counters) and not isinstance(counters, type) else str(counters)
        cols = list(StepRecord.__dataclass_fields__)
        return {
            "table": self.table,
            "origin": self.origin,
            "origin_lead": ORIGIN_LEAD,
            "frames_in": self.frames_in,
            "counters": cnt,
            "steps": {c: [getattr(s, c) for s in self.steps] for c in cols},
        }

    def write(self, path: str | Path) -> Path:
        p = Path(path)
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(json.dumps(self.to_json(), default=str) + "\n", encoding="utf-8")
        return p


def load_steps(path: str | Path) -> list[StepRecord]:
    """Read the steps of an ECU log written by `EcuSession.write`."""
    doc = json.loads(Path(path).read_text(encoding="utf-8"))
    cols: dict[str, list[Any]] = doc["steps"]
    n = len(cols["step"])
    return [StepRecord(**{c: cols[c][i] for c in cols}) for i in range(n)]
