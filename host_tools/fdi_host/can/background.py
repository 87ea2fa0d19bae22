"""Other ECUs' traffic on the vehicle bus: frames the diagnosis does not subscribe to, up to a given bus load.

A real vehicle bus carries far more than the sensor messages of dbc/romo.dbc: engine, body, chassis and
gateway ECUs send their own cyclic messages, up to a full 500 kbit/s bus (about 4,000 frames/s). This module
makes such traffic, deterministically from a seed, so that the live loop and its benchmark can be run at a
realistic load:

* a message set (`background_messages`): cycle times drawn from a vehicle-like mix (5 ms .. 1 s, most at
  10-100 ms), payload lengths 0..8 bytes (most 8), about one message in six with a 29-bit (extended) ID in the
  J1939 style (priority, PGN, source address), the others 11-bit IDs, faster messages on lower (higher
  priority) IDs; no ID of the excluded set (every message of the DBC, so never a frame the ECU subscribes to
  or the diagnosis frame). Messages are added until their rates sum to the requested frames/s (to within one
  frame per second: the last ones are the 1 s messages);
* their frames over a drive (`background_frames`): message m sends at ``phase_m + k * cycle_m`` (phases spread
  over the cycle, on a 10 us grid), its payload a fixed pattern with a rolling counter in byte 0;
* `merge_frames` interleaves them with the simulator's frames in time order (CAN-ID order within a tick, as
  arbitration orders frames that are ready together); `bus_load` is the load these frames would put on a
  classic CAN bus (standard or extended arbitration field, with and without worst-case bit stuffing).

The frame type is the one of the host tools (`fdi_host.can.frame.Frame`): an ID above 0x7FF is an extended
ID (`Frame.to_can`), so every extended ID drawn here is above 0x7FF.
"""

from __future__ import annotations

import heapq
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from fdi_host.can.dbc import CanDatabase
from fdi_host.can.frame import Frame

__all__ = ["BackgroundMessage", "BusLoad", "background_frames", "background_messages", "bus_load",
           "excluded_ids", "for_drive", "merge_frames"]

# (cycle [ms], weight): a vehicle-like mix; most messages at 10-100 ms, a few fast ones, slow status messages.
CYCLE_MIX: tuple[tuple[float, float], ...] = (
    (5.0, 0.06), (10.0, 0.22), (20.0, 0.20), (50.0, 0.16), (100.0, 0.18), (200.0, 0.08), (500.0, 0.05),
    (1000.0, 0.05),
)
# payload length -> weight: most frames are 8 bytes; a few 0-byte (heartbeat) frames.
DLC_MIX: tuple[tuple[int, float], ...] = (
    (0, 0.03), (1, 0.03), (2, 0.05), (3, 0.04), (4, 0.08), (5, 0.05), (6, 0.08), (7, 0.04), (8, 0.60),
)
EXTENDED_SHARE = 1.0 / 6.0
PHASE_GRID_MS = 0.01
DEFAULT_SEED = 2024
_STD_ID_MAX = 0x7FF
_J1939_SOURCES = (0x00, 0x03, 0x0B, 0x17, 0x21, 0x27, 0x31, 0x49, 0x5A)


@dataclass(frozen=True)
class BackgroundMessage:
    frame_id: int  # 11-bit (<= 0x7FF) or 29-bit (> 0x7FF) identifier
    extended: bool
    dlc: int  # payload bytes, 0..8
    cycle_ms: float
    phase_ms: float  # first frame at this time after the drive's t = 0

    @property
    def rate_hz(self) -> float:
        return 1000.0 / self.cycle_ms


def excluded_ids(db: CanDatabase | None = None) -> frozenset[int]:
    """Every ID of the CAN database (default dbc/romo.dbc): background traffic never uses them (neither a message
    the ECU subscribes to nor the diagnosis frame)."""
    db = db or CanDatabase()
    return frozenset(int(m.frame_id) for m in db.db.messages)


def _pick(rng: np.random.Generator, mix: Sequence[tuple[float, float]]) -> float:
    w = np.asarray([p for _, p in mix], dtype=float)
    return float(mix[int(rng.choice(len(mix), p=w / w.sum()))][0])


def background_messages(rate_hz: float, exclude: Iterable[int] = (),
                        seed: int = DEFAULT_SEED) -> list[BackgroundMessage]:
    """A deterministic set of other ECUs' cyclic messages whose rates sum to `rate_hz` frames/s (to within 1)."""
    if rate_hz < 0.0:
        raise ValueError(f"background rate must be >= 0 frames/s, got {rate_hz}")
    rng = np.random.default_rng(seed)
    excl = set(int(i) for i in exclude)
    drawn: list[tuple[float, int, bool]] = []  # (cycle, dlc, extended)
    left = rate_hz
    slowest = max(c for c, _ in CYCLE_MIX)
    while left >= 1000.0 / slowest - 1e-9:
        cycle = _pick(rng, CYCLE_MIX)
        while 1000.0 / cycle > left + 1e-9:  # too fast for what is left: the next slower cycle of the mix
            cycle = min(c for c, _ in CYCLE_MIX if c > cycle)
        dlc = int(_pick(rng, [(float(d), w) for d, w in DLC_MIX]))
        drawn.append((cycle, dlc, bool(rng.random() < EXTENDED_SHARE)))
        left -= 1000.0 / cycle
    # 11-bit IDs: faster messages on lower (higher priority) IDs, as bus designs do; above the lowest DBC ID
    # region so that the ROMO sensors keep their priority on a real bus.
    std = [d for d in drawn if not d[2]]
    pool = np.asarray([i for i in range(0x0A0, 0x7F0) if i not in excl and not 0x7DF <= i <= 0x7EF])
    std_ids = sorted(int(i) for i in rng.choice(pool, size=len(std), replace=False)) if std else []
    ext_ids: set[int] = set()
    out: list[BackgroundMessage] = []
    k_std = 0
    for cycle, dlc, ext in sorted(drawn, key=lambda d: d[0]):
        if ext:
            while True:  # J1939 style: priority 3/6, PGN in the proprietary/common range, a source address
                prio = 3 if cycle <= 20.0 else 6
                common = rng.random() < 0.7
                pgn = 0xF000 + int(rng.integers(0, 0xFFF)) if common else 0xFF00 + int(rng.integers(0, 0xFF))
                fid = prio << 26 | pgn << 8 | int(rng.choice(_J1939_SOURCES))
                if fid not in ext_ids and fid not in excl and fid > _STD_ID_MAX:
                    break
            ext_ids.add(fid)
        else:
            fid = std_ids[k_std]
            k_std += 1
        grid = round(cycle / PHASE_GRID_MS)
        phase = round(int(rng.integers(0, grid)) * PHASE_GRID_MS, 2)
        out.append(BackgroundMessage(fid, ext, dlc, cycle, phase))
    return sorted(out, key=lambda m: (m.frame_id > _STD_ID_MAX, m.frame_id))


def background_frames(messages: Sequence[BackgroundMessage], t_end: float, t0: float = 0.0,
                      seed: int = DEFAULT_SEED) -> list[Frame]:
    """The messages' frames from t = 0 to `t_end` [s] (inclusive), time ordered, `t0` added to every time.

    Times are whole 10 us ticks (integers converted once), so the order within a tick is by ID, reproducibly."""
    rng = np.random.default_rng(seed + 1)
    ticks: list[np.ndarray] = []
    ids: list[np.ndarray] = []
    msg_idx: list[np.ndarray] = []
    end_tick = int(np.floor(t_end / (PHASE_GRID_MS * 1e-3) + 1e-6))
    for j, m in enumerate(messages):
        phase = round(m.phase_ms / PHASE_GRID_MS)
        step = round(m.cycle_ms / PHASE_GRID_MS)
        k = np.arange(phase, end_tick + 1, step, dtype=np.int64)
        ticks.append(k)
        ids.append(np.full(k.size, m.frame_id, dtype=np.int64))
        msg_idx.append(np.full(k.size, j, dtype=np.int64))
    if not ticks:
        return []
    tk, fid, mj = np.concatenate(ticks), np.concatenate(ids), np.concatenate(msg_idx)
    order = np.lexsort((fid, tk))
    tk, mj = tk[order], mj[order]
    base = [bytes(rng.integers(0, 256, size=m.dlc, dtype=np.uint8).tolist()) for m in messages]
    counters = [0] * len(messages)
    out: list[Frame] = []
    scale = PHASE_GRID_MS * 1e-3
    for t_tick, j in zip(tk.tolist(), mj.tolist(), strict=True):
        m = messages[j]
        data = base[j]
        if m.dlc:
            data = bytes((counters[j],)) + data[1:]
            counters[j] = (counters[j] + 1) & 0xFF
        out.append(Frame(t0 + t_tick * scale, m.frame_id, data))
    return out


def for_drive(frames: Sequence[Frame], total_rate_hz: float, duration: float | None = None,
              seed: int = DEFAULT_SEED, db: CanDatabase | None = None) -> list[Frame]:
    """Other ECUs' frames that bring a drive's traffic (`frames`, time ordered) to `total_rate_hz` frames/s
    over its `duration` [s] (default: from its first to its last frame), on the drive's clock from its first
    frame to its last; none if the drive alone reaches the rate."""
    if not frames:
        return []
    t0, t1 = frames[0].timestamp, frames[-1].timestamp
    span = duration if duration is not None else t1 - t0
    if span <= 0.0:
        return []
    rate = max(0.0, total_rate_hz - len(frames) / span)
    msgs = background_messages(rate, excluded_ids(db), seed)
    return background_frames(msgs, t1 - t0, t0, seed)


def merge_frames(*streams: Sequence[Frame]) -> list[Frame]:
    """Time-ordered streams into one, in time order (stable: equal times keep stream order, then ID order)."""
    return list(heapq.merge(*streams, key=lambda f: (f.timestamp, f.frame_id)))


@dataclass(frozen=True)
class BusLoad:
    frames_per_s: float
    nominal: float  # share of the bus without stuff bits
    worst_case: float  # with worst-case bit stuffing


def bus_load(frames: Sequence[Frame], duration: float, baudrate: int = 500_000) -> BusLoad:
    """Load of classic CAN data frames on a `baudrate` bus over `duration` [s]: frame bits (SOF, arbitration,
    control, data, CRC, delimiters, EOF, interframe space; an ID above 0x7FF has the 29-bit arbitration field)
    without and with worst-case stuffing (one stuff bit per 4 bits of the stuffed part)."""
    if duration <= 0.0:
        raise ValueError(f"duration must be > 0, got {duration}")
    nominal = 0
    worst = 0
    for f in frames:
        payload = 8 * len(f.data)
        stuffed = (54 if f.frame_id > _STD_ID_MAX else 34) + payload  # SOF .. CRC
        bits = stuffed + 13  # CRC delimiter, ACK, EOF, interframe space
        nominal += bits
        worst += bits + (stuffed - 1) // 4
    return BusLoad(len(frames) / duration, nominal / (baudrate * duration), worst / (baudrate * duration))
