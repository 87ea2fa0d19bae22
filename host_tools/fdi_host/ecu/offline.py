"""Frames straight through the C ECU core, offline: its result (and, if asked, its exoneration evidence) at every
diagnosis step."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any

from fdi_host.can.frame import Frame
from fdi_host.ecu.bindings import Ecu, EcuResult, Evidence


def _steps(ecu: Ecu, frames: Sequence[Frame], t_start: float) -> Iterator[None]:
    """Feed the frames from t_start on; yields after every diagnosis step (when its frame is sent)."""
    own = ecu.bus.diag_id
    for f in frames:
        if f.timestamp < t_start:
            continue
        ecu.rx(f.frame_id, f.data, f.timestamp)
        for fid, _ in ecu.poll(f.timestamp):
            if fid == own:
                yield None


def replay(table: str, frames: Sequence[Frame], t_start: float = 0.0, **overrides: Any) -> list[EcuResult]:
    """The ECU's result at every diagnosis step for the frames from t_start on (`overrides`: Ecu's)."""
    ecu = Ecu(table, **overrides)
    return [ecu.result() for _ in _steps(ecu, frames, t_start)]


def replay_explained(table: str, frames: Sequence[Frame], t_start: float = 0.0,
                     **overrides: Any) -> list[tuple[EcuResult, Evidence]]:
    """As `replay`, with the exoneration's evidence (fdi_diag_explain) after every step."""
    ecu = Ecu(table, **overrides)
    return [(ecu.result(), ecu.explain()) for _ in _steps(ecu, frames, t_start)]
