"""Frames onto a python-can bus at their timestamps: real time, N times faster, or as fast as possible.

Frame i is sent at ``start + (t_i - t_0) / speed`` on the monotonic clock (sleep until then; frames of the
same millisecond go back to back, in CAN-ID order as the simulator produced them). The wall-clock time
(``time.time()``, the clock the kernel stamps received UDP/SocketCAN frames with) just before each
``bus.send`` is recorded with the frame's ID and E2E counter (`SendLog`), so latencies can be measured
against receive timestamps on the same host: the udp_multicast interface overwrites frame timestamps with
the receive time, so a send time cannot travel in the frame itself.

A restarted sender joins the drive where it is (`resume_frames`): only the frames not yet due on the drive's
clock are sent, at their times on that clock (``first_wall``), and every message's alive counter starts
again at a given value, as a sender that lost its state would.
"""

from __future__ import annotations

import gc
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import can
import numpy as np

from fdi_host.can import e2e
from fdi_host.can.dbc import CanDatabase
from fdi_host.can.frame import Frame


@dataclass
class SendLog:
    sim_t: list[float] = field(default_factory=list)  # frame time relative to the first frame [s]
    wall: list[float] = field(default_factory=list)  # time.time() before bus.send [s]
    frame_id: list[int] = field(default_factory=list)
    counter: list[int] = field(default_factory=list)
    max_behind: float = 0.0  # largest delay of a send behind its schedule [s]
    start_wall: float = 0.0  # wall-clock time at which the first frame was due [s]
    interrupted: bool = False

    def save(self, path: str | Path) -> Path:
        p = Path(path)
        p.parent.mkdir(parents=True, exist_ok=True)
        with p.open("wb") as fh:
            np.savez(fh, sim_t=np.asarray(self.sim_t), wall=np.asarray(self.wall),
                     frame_id=np.asarray(self.frame_id, dtype=np.int64),
                     counter=np.asarray(self.counter, dtype=np.int64))
        return p

    @staticmethod
    def load(path: str | Path) -> SendLog:
        with np.load(Path(path)) as z:
            return SendLog([float(x) for x in z["sim_t"]], [float(x) for x in z["wall"]],
                           [int(x) for x in z["frame_id"]], [int(x) for x in z["counter"]])


def send_paced(
    bus: can.BusABC,
    frames: Sequence[Frame],
    speed: float | None = 1.0,
    stop: Callable[[], bool] = lambda: False,
    lead: float = 0.05,
    on_start: Callable[[float], None] | None = None,
    first_wall: float | None = None,
) -> SendLog:
    """Send `frames` (time ordered) at `speed` times real time (None: as fast as possible).

    `stop()` is checked between frames (Ctrl-C / SIGTERM handlers set it); `lead` [s] before the first frame;
    `on_start(wall)` is called with the wall-clock time the first frame is due, before it is sent. The
    garbage collector is paused while sending (its pauses would delay frames by milliseconds).
    `first_wall`: the wall-clock time the first frame is due (a sender joining a drive under way), instead of
    `lead` from now.
    """
    if speed is not None and not speed > 0.0:
        raise ValueError(f"speed must be > 0 (or None for as fast as possible), got {speed}")
    log = SendLog()
    if not frames:
        return log
    t0 = frames[0].timestamp
    gc.collect()
    gc_was_on = gc.isenabled()
    gc.disable()
    if first_wall is not None:
        start = time.monotonic() + (first_wall - time.time())
        log.start_wall = first_wall
    else:
        start = time.monotonic() + lead
        log.start_wall = time.time() + lead
    if on_start is not None:
        on_start(log.start_wall)
    try:
        _send_loop(bus, frames, speed, stop, start, t0, log)
    finally:
        if gc_was_on:
            gc.enable()
    return log


def _send_loop(bus: can.BusABC, frames: Sequence[Frame], speed: float | None, stop: Callable[[], bool],
               start: float, t0: float, log: SendLog) -> None:
    for f in frames:
        if stop():
            log.interrupted = True
            break
        rel = f.timestamp - t0
        if speed is not None:
            target = start + rel / speed
            wait = target - time.monotonic()
            if wait > 0.0:
                time.sleep(wait)
            else:
                log.max_behind = max(log.max_behind, -wait)
        msg = can.Message(arbitration_id=f.frame_id, data=f.data, is_extended_id=f.frame_id > 0x7FF, dlc=len(f.data))
        log.wall.append(time.time())
        bus.send(msg)
        log.sim_t.append(rel)
        log.frame_id.append(f.frame_id)
        log.counter.append(f.data[1] & 0x0F if len(f.data) > 1 else -1)


def resume_frames(frames: Sequence[Frame], t_from: float, counter_start: int,
                  db: CanDatabase | None = None) -> list[Frame]:
    """The frames of a drive from drive time `t_from` on, each message's alive counter restarted at
    `counter_start` (0..14) and its E2E CRC recomputed, as a restarted sender would send them (frames of IDs
    not in the DBC, other ECUs' traffic, as they are)."""
    if not 0 <= counter_start <= e2e.COUNTER_MAX:
        raise ValueError(f"counter start {counter_start} outside 0..{e2e.COUNTER_MAX}")
    db = db or CanDatabase()
    counters: dict[int, int] = {}
    data_ids: dict[int, int | None] = {}
    out = []
    for f in frames:
        if f.timestamp < t_from:
            continue
        if f.frame_id not in data_ids:
            try:
                data_ids[f.frame_id] = db.data_id(db.message_by_id(f.frame_id).name)
            except KeyError:  # another ECU's frame (not in the DBC): sent as recorded
                data_ids[f.frame_id] = None
        did = data_ids[f.frame_id]
        data = f.data
        if did is not None and len(data) >= 2:
            c = counters.get(f.frame_id, counter_start)
            counters[f.frame_id] = e2e.next_counter(c)
            data = e2e.protect(data, did, c)
        out.append(Frame(f.timestamp, f.frame_id, data))
    return out
