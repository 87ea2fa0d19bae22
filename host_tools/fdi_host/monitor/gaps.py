"""Silences on the bus as the monitor sees them: the ECU's FDI_Diagnosis stream or the simulator's sensor frames.

A *gap* of a stream is a silence longer than a threshold (default 0.25 s, far above the 5..20 ms cycles and
the tens of milliseconds a loaded sender may lag) between two of its frames: it starts at the last frame before
the silence and ends at the first frame after it, both on the drive's clock. Two streams:

* ``diagnosis``: FDI_Diagnosis frames (the ECU process is down or restarting);
* ``sensors``: any simulator frame (the simulator is down or restarting).

While a silence lasts it is reported as open (`GapTracker.silent`, for the live table). At the end of a run
(`GapTracker.finish`) a silence that never ended is a gap only where the run shows that the stream should
have gone on: the diagnosis stream when sensor frames kept coming after it stopped, the sensor stream when it
stopped before the end of the drive (the drive's duration from truth.json). The normal end of a drive, and
the ECU's last frames after it, are not gaps.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

STREAMS = ("diagnosis", "sensors")
WHAT = {"diagnosis": "ECU silent (no FDI_Diagnosis)", "sensors": "simulator silent (no sensor frames)"}


@dataclass(frozen=True)
class Gap:
    stream: str  # "diagnosis" or "sensors"
    start: float  # drive time of the last frame before the silence [s]
    end: float  # first frame after it, or the end of the run if it never came back [s]
    resumed: bool = True  # False: the stream did not come back before the run ended

    @property
    def duration(self) -> float:
        return self.end - self.start

    def to_json(self) -> dict[str, Any]:
        return {"stream": self.stream, "what": WHAT.get(self.stream, self.stream), "start": self.start,
                "end": self.end, "duration": self.duration, "resumed": self.resumed}

    def describe(self) -> str:
        tail = "" if self.resumed else ", not resumed"
        return (f"gap: {WHAT.get(self.stream, self.stream)} from {self.start:.2f} s to {self.end:.2f} s "
                f"({self.duration:.2f} s{tail})")


@dataclass
class GapTracker:
    """Feed every frame's stream and drive time to `frame`; closed gaps accumulate in `gaps`."""

    threshold: float = 0.25  # s
    gaps: list[Gap] = field(default_factory=list)
    last: dict[str, float] = field(default_factory=dict)  # stream -> drive time of its last frame

    def __post_init__(self) -> None:
        if not self.threshold > 0.0:
            raise ValueError(f"gap threshold must be > 0 s, got {self.threshold}")

    def frame(self, stream: str, t: float) -> Gap | None:
        """A frame of `stream` at drive time `t`; returns the gap it ends, if any."""
        if stream not in STREAMS:
            raise ValueError(f"unknown stream {stream!r}; expected one of {', '.join(STREAMS)}")
        prev = self.last.get(stream)
        gap = None
        if prev is not None and t - prev > self.threshold:
            gap = Gap(stream, prev, t)
            self.gaps.append(gap)
        if prev is None or t > prev:
            self.last[stream] = t
        return gap

    def silent(self, now: float) -> dict[str, float]:
        """Streams silent for longer than the threshold at drive time `now`: stream -> silence so far [s]."""
        return {s: now - t for s, t in self.last.items() if now - t > self.threshold}

    def finish(self, drive_end: float | None = None) -> list[Gap]:
        """Close the run: add the silences that never ended (see the module doc); returns all gaps, by start."""
        diag, sens = self.last.get("diagnosis"), self.last.get("sensors")
        if diag is not None and sens is not None and sens - diag > self.threshold:
            self.gaps.append(Gap("diagnosis", diag, sens, resumed=False))
        if sens is not None and drive_end is not None and drive_end - sens > self.threshold:
            self.gaps.append(Gap("sensors", sens, drive_end, resumed=False))
        self.gaps.sort(key=lambda g: (g.start, g.stream))
        return list(self.gaps)


def gap_summary(gaps: Sequence[Gap]) -> str:
    """One line: count and total time per stream."""
    parts = []
    for s in STREAMS:
        mine = [g for g in gaps if g.stream == s]
        parts.append(f"{s} {len(mine)} ({sum(g.duration for g in mine):.2f} s)")
    return "gaps: " + ", ".join(parts)


def overlap(a: float, b: float, gaps: Sequence[Gap]) -> float:
    """Time of [a, b) inside the gaps [s] (gaps of different streams may overlap; counted once)."""
    spans = sorted((max(a, g.start), min(b, g.end)) for g in gaps if g.end > a and g.start < b)
    total, cur_a, cur_b = 0.0, None, None
    for x, y in spans:
        if cur_a is None or cur_b is None or x > cur_b:
            if cur_a is not None and cur_b is not None:
                total += cur_b - cur_a
            cur_a, cur_b = x, y
        else:
            cur_b = max(cur_b, y)
    if cur_a is not None and cur_b is not None:
        total += cur_b - cur_a
    return total
