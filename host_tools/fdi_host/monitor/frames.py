"""Per-message bus statistics from received frames: received, lost, late, E2E errors.

* lost: gaps in the E2E alive counter (profile 11 counts 0..14; a jump by d means d - 1 frames missing; a
  gap of a whole multiple of 15 frames is invisible, as on a real bus);
* late: a frame that arrives more than half a cycle after its nominal time, the nominal time being the
  arrival of the message's first frame plus its frame index (lost frames included) times the DBC cycle time
  (messages given in `cycles`, i.e. the diagnosis frame: the ECU sends one when a step completes and merges
  steps that fall due together, so there a frame is late when it comes more than 1.5 steps after the
  previous one);
* e2e errors: CRC mismatch; repeated: the same counter twice (ignored, like the ECU does);
* gaps: silences longer than `gap_threshold` (the sender or the ECU restarted, or a sensor went silent).
  After a gap the message starts afresh: its alive counter may restart anywhere, so the counter jump is
  not counted as lost frames, and the nominal times are anchored again at the first frame after the gap.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from fdi_host.can import e2e
from fdi_host.can.dbc import CanDatabase


@dataclass
class MessageStats:
    name: str
    frame_id: int
    cycle: float  # s, from the DBC
    received: int = 0
    lost: int = 0
    late: int = 0
    e2e_errors: int = 0
    repeated: int = 0
    gaps: int = 0
    gap_time: float = 0.0  # s, total silence in gaps
    max_lateness: float = 0.0  # s, largest arrival - nominal
    first_t: float | None = None
    last_t: float = 0.0
    last_counter: int | None = None
    index: int = 0  # frame index of the last frame (lost frames counted)

    def to_json(self) -> dict[str, Any]:
        d = asdict(self)
        for k in ("first_t", "last_t", "last_counter", "index"):
            d.pop(k)
        return d


class FrameStats:
    """Feed every received frame to `add`; read `messages` (by frame id)."""

    def __init__(self, db: CanDatabase, cycles: dict[int, float] | None = None, gap_threshold: float = 0.25) -> None:
        if not gap_threshold > 0.0:
            raise ValueError(f"gap threshold must be > 0 s, got {gap_threshold}")
        self.db = db
        self.gap_threshold = gap_threshold
        self.cycles = dict(cycles or {})  # frame id -> cycle [s] overriding the DBC (the diagnosis step)
        self.messages: dict[int, MessageStats] = {}
        self.unknown = 0

    def add(self, frame_id: int, data: bytes, t: float) -> bool:
        """Account one frame received at `t`; returns True if it passed the E2E check."""
        st = self.messages.get(frame_id)
        if st is None:
            try:
                msg = self.db.message_by_id(frame_id)
            except KeyError:
                self.unknown += 1
                return False
            cycle = self.cycles.get(frame_id, self.db.cycle_time_ms(msg.name) * 1e-3)
            st = MessageStats(msg.name, frame_id, cycle)
            self.messages[frame_id] = st
        did = self.db.data_id(st.name)
        if len(data) < 2 or (did is not None and e2e.p11_crc(data, did) != data[0]):
            st.e2e_errors += 1
            return False
        c = e2e.counter_of(data)
        if st.last_counter is None or st.first_t is None:
            st.first_t, st.index = t, 0
        elif t - st.last_t > max(self.gap_threshold, 3.0 * st.cycle):  # a silence: start afresh
            st.gaps += 1
            st.gap_time += t - st.last_t
            st.first_t, st.index = t, 0
        else:
            delta = (c - st.last_counter) % (e2e.COUNTER_MAX + 1)
            if delta == 0:
                st.repeated += 1
                return False
            st.lost += delta - 1
            st.index += delta
            if frame_id in self.cycles:
                lateness = t - (st.last_t + delta * st.cycle)
            else:
                lateness = t - (st.first_t + st.index * st.cycle)
            st.max_lateness = max(st.max_lateness, lateness)
            if lateness > 0.5 * st.cycle:
                st.late += 1
        st.last_counter = c
        st.last_t = t
        st.received += 1
        return True

    def to_json(self) -> dict[str, Any]:
        return {"unknown_ids": self.unknown,
                "messages": {f"0x{k:03X}": v.to_json() for k, v in sorted(self.messages.items())}}
