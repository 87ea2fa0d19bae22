"""Frames straight through the C ECU core, offline: its result at every diagnosis step."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from fdi_host.can.frame import Frame
from fdi_host.ecu.bindings import DIAG_ID, Ecu, EcuResult


def replay(table: str, frames: Sequence[Frame], t_start: float = 0.0, **overrides: Any) -> list[EcuResult]:
    """The ECU's result at every diagnosis step for the frames from t_start on (`overrides`: Ecu's)."""
    ecu = Ecu(table, **overrides)
    out: list[EcuResult] = []
    for f in frames:
        if f.timestamp < t_start:
            continue
        ecu.rx(f.frame_id, f.data, f.timestamp)
        for fid, _ in ecu.poll(f.timestamp):
            if fid == DIAG_ID:
                out.append(ecu.result())
    return out
