"""E2E profile 11 header: CRC8 SAE-J1850 against published check values, counter, error detection."""

from __future__ import annotations

import pytest

from fdi_host.can import e2e

# AUTOSAR SWS CRC Library, Crc_CalculateCRC8 check values (SAE-J1850, start 0xFF, xor 0xFF).
AUTOSAR_CHECK = [
    ("00000000", 0x59),
    ("F20183", 0x37),
    ("0FAA0055", 0x79),
    ("00FF5511", 0xB8),
    ("332255AABBCCDDEEFF", 0xCB),
    ("926B55", 0x8C),
    ("FFFFFFFF", 0x74),
]


@pytest.mark.parametrize(("hexdata", "crc"), AUTOSAR_CHECK)
def test_crc8_autosar_check_values(hexdata: str, crc: int) -> None:
    assert e2e.crc8_sae_j1850(bytes.fromhex(hexdata)) == crc


def test_crc8_catalogue_check() -> None:
    assert e2e.crc8_sae_j1850(b"123456789") == 0x4B  # CRC-8/SAE-J1850 catalogue "check"


def test_protect_sets_counter_and_crc_and_keeps_status_nibble() -> None:
    raw = bytes([0, 0xA0, 1, 2, 3, 4, 5, 6])
    out = e2e.protect(raw, 0x1080, 7)
    assert out[1] == 0xA7 and out[2:] == raw[2:]
    assert out[0] == e2e.crc8_sae_j1850(bytes([0x80, 0x10]) + out[1:])


def test_every_single_bit_error_is_detected() -> None:
    frame = e2e.protect(bytes(range(8)), 0x1234, 3)
    for byte in range(8):
        for bit in range(8):
            bad = bytearray(frame)
            bad[byte] ^= 1 << bit
            assert e2e.p11_crc(bad, 0x1234) != bad[0], (byte, bit)


def test_data_id_is_part_of_the_crc() -> None:
    frame = e2e.protect(bytes(8), 0x1100, 0)
    assert e2e.p11_crc(frame, 0x1101) != frame[0]


def test_receiver_states() -> None:
    rx = e2e.E2EReceiver(0x42, max_delta_counter=2)
    mk = lambda c: e2e.protect(bytes(8), 0x42, c)  # noqa: E731
    assert rx.check(mk(13)) is e2e.E2EStatus.INITIAL
    assert rx.check(mk(14)) is e2e.E2EStatus.OK
    assert rx.check(mk(0)) is e2e.E2EStatus.OK  # wrap 14 -> 0
    assert rx.check(mk(0)) is e2e.E2EStatus.REPEATED
    assert rx.check(mk(2)) is e2e.E2EStatus.OK_SOME_LOST
    assert rx.check(mk(9)) is e2e.E2EStatus.WRONG_SEQUENCE
    bad = bytearray(mk(10))
    bad[5] ^= 0x10
    assert rx.check(bad) is e2e.E2EStatus.CRC_ERROR


def test_counter_range() -> None:
    with pytest.raises(ValueError):
        e2e.protect(bytes(8), 1, 15)
    assert e2e.next_counter(14) == 0 and e2e.next_counter(3) == 4
