"""AUTOSAR E2E profile 11 style protection for classic CAN frames: CRC8 SAE-J1850 + 4-bit alive counter.

Layout used on the ROMO bus (CRC offset 0, counter offset 8, data-ID mode BOTH)::

    byte 0        : CRC = CRC8-SAE-J1850(DataID low byte, DataID high byte, bytes 1..n-1)
    byte 1 [3:0]  : alive counter 0..14 (15 is not used, as in profile 11)
    byte 1 [7:4]  : free for the sender (the ROMO messages put their status nibble here)

CRC8-SAE-J1850: polynomial 0x1D, initial value 0xFF, final XOR 0xFF, no reflection (check value of
"123456789" is 0x4B; the AUTOSAR CRC library's table of check values is in the tests). cantools 45 ships
helpers for profiles 2 (CRC8H2F) and 5 (CRC16) only, bound to ARXML data-ID lists, so this module implements
the J1850 CRC and the profile 11 header itself (table driven, 256 bytes, mirrors what the firmware does).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

COUNTER_MAX = 14  # profile 11: counter runs 0..14


def _make_table(poly: int) -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = ((crc << 1) ^ poly) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
        table.append(crc)
    return tuple(table)


_TABLE_1D = _make_table(0x1D)


def crc8_sae_j1850(data: bytes | bytearray, start: int = 0xFF, xor_out: int = 0xFF) -> int:
    """CRC8 SAE-J1850 (AUTOSAR ``Crc_CalculateCRC8`` with a first call)."""
    crc = start & 0xFF
    for b in data:
        crc = _TABLE_1D[crc ^ b]
    return crc ^ xor_out


def p11_crc(payload: bytes | bytearray, data_id: int) -> int:
    """The profile 11 CRC of a frame (byte 0 excluded), data-ID mode BOTH."""
    if not 0 <= data_id <= 0xFFFF:
        raise ValueError(f"data ID {data_id} is not a 16-bit value")
    if len(payload) < 2:
        raise ValueError("an E2E protected frame needs at least 2 bytes")
    return crc8_sae_j1850(bytes((data_id & 0xFF, data_id >> 8)) + bytes(payload[1:]))


def protect(payload: bytes | bytearray, data_id: int, counter: int) -> bytes:
    """Write `counter` into byte 1 [3:0] and the CRC into byte 0; returns the protected frame."""
    if not 0 <= counter <= COUNTER_MAX:
        raise ValueError(f"E2E counter {counter} outside 0..{COUNTER_MAX}")
    out = bytearray(payload)
    out[1] = (out[1] & 0xF0) | counter
    out[0] = p11_crc(out, data_id)
    return bytes(out)


def counter_of(payload: bytes | bytearray) -> int:
    return payload[1] & 0x0F


def next_counter(counter: int) -> int:
    return 0 if counter >= COUNTER_MAX else counter + 1


class E2EStatus(Enum):
    OK = "ok"
    OK_SOME_LOST = "ok_some_lost"  # counter jumped by 2..max_delta
    REPEATED = "repeated"  # same counter as the previous frame
    WRONG_SEQUENCE = "wrong_sequence"  # counter jumped by more than max_delta
    CRC_ERROR = "crc_error"
    INITIAL = "initial"  # first valid frame, nothing to compare against


@dataclass
class E2EReceiver:
    """Receiver-side check of one message (profile 11 ``E2E_P11Check`` semantics, simplified)."""

    data_id: int
    max_delta_counter: int = 1
    last_counter: int | None = None

    def check(self, payload: bytes | bytearray) -> E2EStatus:
        if p11_crc(payload, self.data_id) != payload[0]:
            return E2EStatus.CRC_ERROR
        c = counter_of(payload)
        last, self.last_counter = self.last_counter, c
        if last is None:
            return E2EStatus.INITIAL
        delta = (c - last) % (COUNTER_MAX + 1)
        if delta == 0:
            return E2EStatus.REPEATED
        if delta == 1:
            return E2EStatus.OK
        if delta <= self.max_delta_counter:
            return E2EStatus.OK_SOME_LOST
        return E2EStatus.WRONG_SEQUENCE
