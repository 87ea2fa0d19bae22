"""The one CAN frame type of the host tools: a classic data frame with its time, as simulated traffic, log
files, the live bus and the ECU bindings all see it (python-can's `can.Message` converts to and from it)."""

from __future__ import annotations

from dataclasses import dataclass

import can


@dataclass(frozen=True)
class Frame:
    timestamp: float  # [s], on the drive's clock (simulated traffic) or the log's / receiver's clock
    frame_id: int  # 11-bit or 29-bit identifier
    data: bytes

    def to_can(self, channel: int = 0) -> can.Message:
        return can.Message(
            timestamp=self.timestamp, arbitration_id=self.frame_id, data=self.data,
            is_extended_id=self.frame_id > 0x7FF, dlc=len(self.data), channel=channel,
        )

    @classmethod
    def from_can(cls, msg: can.Message) -> Frame:
        return cls(float(msg.timestamp), int(msg.arbitration_id), bytes(msg.data))
