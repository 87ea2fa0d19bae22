"""Bad CAN input through the ECU core (fdi_host.ecu.bindings) on simulated fault-free traffic: unknown IDs, wrong
DLC, bad CRC, repeated and jumping alive counters, raw values out of range (alive counter 15), sender status,
bursts at 10x the nominal rate, gaps (a sender going silent) and reordered frames.

For each: the frames are counted by their reason, the affected message's signals go invalid once its timeout
(3 cycles) has passed, the tests reading them become "not evaluable" while the others stay evaluable, they come
back after a warm-up, nothing is ever detected or isolated (the values are fault-free), nothing crashes.
Corruptions are applied to every frame of one message in a window, for the velocity sensor (read by every
kinematic test) and for wheel robot 1 (read by none of them).
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from fdi_host.can import e2e
from fdi_host.can.dbc import CanDatabase
from fdi_host.can.frame import Frame
from fdi_host.can.traffic import build_frames
from fdi_host.ecu.bindings import DIAG_ID, REASONS, Ecu, EcuResult
from fdi_host.sim.scenario import load_scenario
from fdi_host.sim.vehicle_sim import simulate

DURATION = 10.5
W0, W1 = 4.0, 5.5  # corruption window [s]; warm-up after it: 3.2 s
MESSAGES = {  # name -> (CAN ID, FDI_SIGM_* signals it carries, E2E data ID)
    "VelocitySensor": (136, 0x18, 4232),
    "WheelRobot1": (256, 0x20 | 0x200 | 0x8000, 4352),
}
TABLE = "kin"


@pytest.fixture(scope="module")
def clean() -> list[Frame]:
    return build_frames(simulate(load_scenario("fig6"), [], duration=DURATION))


def replay(frames: list[Frame], **ecu_options: object) -> tuple[Ecu, list[EcuResult]]:
    ecu = Ecu(TABLE, **ecu_options)
    out: list[EcuResult] = []
    for f in frames:
        ecu.rx(f.frame_id, f.data, f.timestamp)
        for fid, _ in ecu.poll(f.timestamp):
            assert fid == DIAG_ID
            out.append(ecu.result())
    return ecu, out


def in_window(f: Frame, can_id: int) -> bool:
    return f.frame_id == can_id and W0 <= f.timestamp < W1


def corrupt(frames: list[Frame], can_id: int, fn: Callable[[Frame, int], list[Frame]]) -> tuple[list[Frame], int]:
    """Replace every frame of `can_id` in the window by fn(frame, k) (k = 0, 1, ...); returns frames, count."""
    out: list[Frame] = []
    k = 0
    for f in frames:
        if in_window(f, can_id):
            out.extend(fn(f, k))
            k += 1
        else:
            out.append(f)
    return out, k


def reprotect(f: Frame, data_id: int, counter: int, status: int | None = None) -> Frame:
    raw = bytearray(f.data)
    if status is not None:
        raw[1] = (raw[1] & 0x0F) | (status << 4)
    raw[1] = (raw[1] & 0xF0) | counter
    raw[0] = e2e.p11_crc(raw, data_id)
    return Frame(f.timestamp, f.frame_id, bytes(raw))


def check_invalid_window(results: list[EcuResult], message: str) -> None:
    """The message's signals invalid and its dependent tests not evaluable inside the window (after the
    timeout), independent tests evaluable, everything evaluable again at the end; never a detection."""
    _, sig, _ = MESSAGES[message]
    tab = Ecu(TABLE).table
    dependent = sum(1 << i for i in range(tab.n_tests) if tab.has_generator[i] and tab.test_input_masks[i] & sig)
    all_tests = sum(1 << i for i in range(tab.n_tests) if tab.has_generator[i])
    inside = [r for r in results if W0 + 0.05 <= r.t_us * 1e-6 < W1]
    assert inside
    for r in inside:
        assert r.validity & sig == 0, f"{message} signals still valid at {r.t_us} us"
        assert r.evaluable_mask & dependent == 0
        assert r.evaluable_mask == all_tests & ~dependent
    assert results[-1].evaluable_mask == all_tests, "tests did not come back after the window"
    assert results[-1].validity & sig == sig
    assert not any(r.detected or r.isolated or r.candidates for r in results), "a detection on fault-free values"


def counted(ecu: Ecu, message: str) -> dict[str, int]:
    m = ecu.counters().messages[message]
    assert m.received == m.accepted + sum(m.rejected.values())
    return m.rejected


@pytest.mark.parametrize("message", list(MESSAGES))
def test_unknown_id_wrong_dlc_bad_crc(clean: list[Frame], message: str) -> None:
    can_id, _, _ = MESSAGES[message]
    for kind, fn, reason in (
        ("crc", lambda f, k: [Frame(f.timestamp, f.frame_id, bytes([f.data[0] ^ 0x3C]) + f.data[1:])], "bad_crc"),
        ("dlc", lambda f, k: [Frame(f.timestamp, f.frame_id, f.data[: 1 + k % 7])], "bad_dlc"),
        ("unknown", lambda f, k: [Frame(f.timestamp, 0x7FF - k % 3, f.data)], "unknown_id"),
    ):
        frames, n = corrupt(clean, can_id, fn)
        ecu, res = replay(frames)
        c = ecu.counters()
        assert c.rejected[reason] == n, kind
        if reason != "unknown_id":
            assert counted(ecu, message)[reason] == n
        check_invalid_window(res, message)
        assert c.messages[message].timeouts == 1


@pytest.mark.parametrize("message", list(MESSAGES))
def test_repeated_and_jumping_alive_counters(clean: list[Frame], message: str) -> None:
    can_id, _, data_id = MESSAGES[message]
    last = [f for f in clean if f.frame_id == can_id and f.timestamp < W0][-1]
    frames, n = corrupt(clean, can_id, lambda f, k: [Frame(f.timestamp, f.frame_id, last.data)])
    ecu, res = replay(frames)
    assert counted(ecu, message)["repeated_counter"] == n
    check_invalid_window(res, message)
    # every frame in the window advances the counter by 3: each one a jump (the receiver re-synchronises)
    c0 = e2e.counter_of(last.data)
    frames, n = corrupt(clean, can_id, lambda f, k: [reprotect(f, data_id, (c0 + 3 * (k + 1)) % 15)])
    ecu, res = replay(frames)
    assert counted(ecu, message)["counter_jump"] >= n
    check_invalid_window(res, message)
    # with max_delta_counter = 3 the same traffic is accepted (a sender that loses 2 of 3 frames)
    ecu, res = replay(frames, max_delta_counter=3)
    rej = counted(ecu, message)
    assert rej["counter_jump"] <= 1 and sum(rej.values()) <= 1  # the first frame after the window may jump
    assert not any(r.detected for r in res)


@pytest.mark.parametrize("message", list(MESSAGES))
def test_out_of_range_counter_and_sender_status(clean: list[Frame], message: str) -> None:
    can_id, _, data_id = MESSAGES[message]
    frames, n = corrupt(clean, can_id, lambda f, k: [reprotect(f, data_id, 15)])
    ecu, res = replay(frames)
    assert counted(ecu, message)["out_of_range"] == n
    check_invalid_window(res, message)
    frames, n = corrupt(clean, can_id, lambda f, k: [reprotect(f, data_id, e2e.counter_of(f.data), status=2)])
    ecu, res = replay(frames)
    assert counted(ecu, message)["sensor_status"] == n
    check_invalid_window(res, message)


@pytest.mark.parametrize("message", list(MESSAGES))
def test_gap_sender_silent(clean: list[Frame], message: str) -> None:
    can_id, _, _ = MESSAGES[message]
    frames = [f for f in clean if not in_window(f, can_id)]
    ecu, res = replay(frames)
    c = ecu.counters()
    assert c.messages[message].timeouts == 1
    assert c.rejected_total <= 1  # the first frame after the gap: counter jump, then re-synchronised
    check_invalid_window(res, message)


def test_burst_at_10x_rate_is_accepted_or_counted(clean: list[Frame], db: CanDatabase) -> None:
    """VelocitySensor at 10x its rate (1 ms) for 1.5 s: with fresh counters every frame is accepted and the
    diagnosis stays quiet and evaluable; as plain copies 9 of 10 are rejected as repeated counters."""
    can_id, _, data_id = MESSAGES["VelocitySensor"]
    cycle = db.cycle_time_ms("VelocitySensor") * 1e-3
    fresh: list[Frame] = []
    counter = 0
    n_window = 0
    for f in clean:
        if f.frame_id != can_id:
            fresh.append(f)
            continue
        copies = 10 if W0 <= f.timestamp < W1 else 1
        n_window += copies > 1
        for i in range(copies):
            fresh.append(reprotect(Frame(f.timestamp + i * cycle / 10, can_id, f.data), data_id, counter))
            counter = e2e.next_counter(counter)
    fresh.sort(key=lambda f: f.timestamp)
    ecu, res = replay(fresh)
    m = ecu.counters().messages["VelocitySensor"]
    assert m.received == m.accepted and m.accepted == sum(1 for f in fresh if f.frame_id == can_id)
    assert not any(r.detected for r in res)
    tab = ecu.table
    assert all(r.evaluable_mask == (1 << tab.n_tests) - 1 for r in res if r.t_us * 1e-6 > 3.5)
    copies, n = corrupt(clean, can_id, lambda f, k: [Frame(f.timestamp + i * cycle / 10, can_id, f.data)
                                                       for i in range(10)])
    copies.sort(key=lambda f: f.timestamp)
    ecu, res = replay(copies)
    assert counted(ecu, "VelocitySensor")["repeated_counter"] == 9 * n
    assert not any(r.detected for r in res)


def test_reordered_frames(clean: list[Frame]) -> None:
    """Pairs of VelocitySensor frames swapped in the window: the late one is a counter jump backwards,
    counted; the values stay fault-free: no detection, counters consistent."""
    can_id = MESSAGES["VelocitySensor"][0]
    out = list(clean)
    idx = [i for i, f in enumerate(out) if in_window(f, can_id)]
    for a, b in zip(idx[::2], idx[1::2], strict=False):
        fa, fb = out[a], out[b]
        out[a], out[b] = Frame(fa.timestamp, can_id, fb.data), Frame(fb.timestamp, can_id, fa.data)
    ecu, res = replay(out)
    rej = counted(ecu, "VelocitySensor")
    assert rej["counter_jump"] + rej["repeated_counter"] >= len(idx) // 2
    assert set(REASONS) >= {r for r, v in rej.items() if v}
    assert not any(r.detected or r.isolated for r in res)
    assert res[-1].evaluable_mask == 0b1111
