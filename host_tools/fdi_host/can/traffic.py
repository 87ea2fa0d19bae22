"""Simulated signals -> CAN frames (DBC-encoded, E2E protected, at their cycle times), and back.

Frame k of a message with cycle time T and start delay d is sent at ``t = d + k*T`` and carries the sensor
values of the 1 kHz sample at that time (noise from `fdi_host.sim.sensors`, quantisation by the DBC scaling).
Frames sent in the same millisecond are ordered by CAN ID (arbitration). Log files: `fdi_host.can.logs`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from fdi_host.can import e2e
from fdi_host.can.dbc import CanDatabase
from fdi_host.can.frame import Frame
from fdi_host.sim.vehicle_sim import SimResult

FloatArray = NDArray[np.float64]


def sim_signal_arrays(result: SimResult) -> dict[str, FloatArray]:
    """Everything the bus can carry: measured knowns (noisy) and the motion demand (exact)."""
    out = dict(result.measured)
    for c in ("speed", "sideslip", "yaw_rate"):
        out[f"demand_{c}"] = result.true[f"demand_{c}"]
    return out


def build_frames(
    result: SimResult,
    db: CanDatabase | None = None,
    t0: float = 0.0,
    progress: Callable[[int], None] | None = None,
    t_from: float = 0.0,
) -> list[Frame]:
    """All frames of the drive, time ordered, from `t_from` on (the frames before it are not encoded; the E2E
    counters run as if they were). `t0` is added to every timestamp."""
    return frames_from_columns(sim_signal_arrays(result), result.config.dt, float(result.t[-1]), db, t0, progress,
                               t_from)


def frames_from_columns(
    signals: dict[str, FloatArray],
    dt: float,
    t_end: float,
    db: CanDatabase | None = None,
    t0: float = 0.0,
    progress: Callable[[int], None] | None = None,
    t_from: float = 0.0,
) -> list[Frame]:
    """The frames of every message the DBC maps simulator signals to, from signals sampled every `dt` from t = 0
    to `t_end` (keyed by the DBC's ModelSignal names; any vehicle's database)."""
    db = db or CanDatabase()
    frames: list[tuple[float, int, bytes]] = []
    for name in db.simulated_messages:
        msg = db.message(name)
        cycle = db.cycle_time_ms(name) * 1e-3
        delay = db.start_delay_ms(name) * 1e-3
        times = np.arange(delay, t_end + 1e-9, cycle)
        idx = np.rint(times / dt).astype(int)
        maps = db.maps_by_message[name]
        missing = [sm.sim for sm in maps if sm.sim not in signals]
        if missing:
            raise KeyError(f"{db.path}: message {name} carries {missing}, which the drive does not have")
        cols = {sm.sim: signals[sm.sim][idx].tolist() for sm in maps}
        counter = 0
        for j, ts in enumerate(times.tolist()):
            if ts >= t_from:
                frames.append((ts, msg.frame_id, db.encode_sim(name, {k: v[j] for k, v in cols.items()}, counter)))
            counter = e2e.next_counter(counter)
        if progress is not None:
            progress(len(times))
    frames.sort(key=lambda f: (round(f[0], 9), f[1]))
    return [Frame(t0 + ts, fid, data) for ts, fid, data in frames]


@dataclass(frozen=True)
class DecodedSignals:
    """Per message: frame times and the simulator signals decoded from the frames."""

    times: dict[str, FloatArray]
    values: dict[str, FloatArray]  # sim signal name -> values at the times of its message
    message_of: dict[str, str]  # sim signal name -> message name
    e2e_errors: int


def decode_frames(frames: Sequence[Frame], db: CanDatabase | None = None) -> DecodedSignals:
    """Decode frames into simulator signals; frames with a bad E2E CRC are counted and dropped."""
    db = db or CanDatabase()
    times: dict[str, list[float]] = {}
    vals: dict[str, list[float]] = {}
    message_of: dict[str, str] = {}
    errors = 0
    for f in frames:
        try:
            msg = db.message_by_id(f.frame_id)
        except KeyError:
            continue
        did = db.data_id(msg.name)
        if did is not None and e2e.p11_crc(f.data, did) != f.data[0]:
            errors += 1
            continue
        dec = db.decode_sim(f.frame_id, f.data, check_e2e=False)
        times.setdefault(msg.name, []).append(f.timestamp)
        for k, v in dec.items():
            vals.setdefault(k, []).append(v)
            message_of[k] = msg.name
    return DecodedSignals(
        {k: np.asarray(v) for k, v in times.items()},
        {k: np.asarray(v) for k, v in vals.items()},
        message_of,
        errors,
    )


def bus_load(frames: Sequence[Frame], baudrate: int, duration: float) -> float:
    """Approximate bus load: classic CAN, 11-bit ID, worst-case bit stuffing."""
    bits = 0
    for f in frames:
        payload = 8 * len(f.data)
        bits += 47 + payload + (34 + payload - 1) // 4
    return bits / (baudrate * duration)
