"""The C ECU core through its Python bindings (fdi_host.ecu.bindings), fed with the simulator's CAN frames.

A drifting vx sensor (f4, ramp) on the kinematic table must be detected and isolated as f4 (and nothing else),
the fault-free drive must give no detection at all; the diagnosis frames must decode with the DBC (cantools)
into what the C result says; bad frames are counted by reason and do not change the diagnosis; a silent
message makes the tests that read it "not evaluable".
"""

from __future__ import annotations

import collections
import itertools

import pytest

from fdi_host.can import e2e
from fdi_host.can.dbc import CanDatabase
from fdi_host.can.frame import Frame
from fdi_host.can.traffic import build_frames
from fdi_host.ecu.bindings import DIAG_ID, REASONS, Ecu, EcuError, bus_info, table_info
from fdi_host.sim.faults import FaultSpec
from fdi_host.sim.scenario import load_scenario
from fdi_host.sim.vehicle_sim import simulate

DURATION = 13.0
ONSET = 6.0


def _frames(faults: list[FaultSpec]) -> list[Frame]:
    res = simulate(load_scenario("fig6"), faults, duration=DURATION)
    return build_frames(res)


@pytest.fixture(scope="module")
def clean_frames() -> list[Frame]:
    return _frames([])


@pytest.fixture(scope="module")
def f4_frames() -> list[Frame]:
    return _frames([FaultSpec("f4", ONSET, 2.0, shape="ramp", ramp=4.0)])


def _run(ecu: Ecu, frames: list[Frame]) -> list[tuple[float, object, bytes]]:
    """Replay frames; per diagnosis frame: time, the C result at that step, the frame bytes."""
    out: list[tuple[float, object, bytes]] = []
    for f in frames:
        ecu.rx(f.frame_id, f.data, f.timestamp)
        for fid, data in ecu.poll(f.timestamp):
            assert fid == DIAG_ID
            out.append((f.timestamp, ecu.result(), data))
    return out


def test_tables_are_exposed() -> None:
    kin = table_info("kin")
    assert kin.n_tests == 4 and kin.n_faults == 5 and all(kin.has_generator)
    assert kin.dt == pytest.approx(0.01)
    romo = table_info("romo")
    assert romo.n_faults == 25 and romo.n_tests >= 1
    assert romo.iso_class[9] == romo.iso_class[13]  # f10 / f14 share a class (M_TM + M_DB)
    with pytest.raises(ValueError, match="no vehicle 'nope'"):
        Ecu("nope")


def test_fault_free_drive_gives_no_detection(clean_frames: list[Frame]) -> None:
    ecu = Ecu("kin")
    diag = _run(ecu, clean_frames)
    steps = round(clean_frames[-1].timestamp / ecu.step_s)
    assert abs(len(diag) - steps) <= 1  # one diagnosis frame per 10 ms step
    assert not any(r.detected for _, r, _ in diag)  # type: ignore[attr-defined]
    last = diag[-1][1]
    assert last.status_name == "NO_FAULT" and last.evaluable_mask == 0b1111  # type: ignore[attr-defined]
    c = ecu.counters()
    assert c.rejected_total == 0
    assert c.messages["IMU_Motion"].accepted == c.messages["IMU_Motion"].received > 2000
    assert all(m.timeouts == 0 for m in c.messages.values())


def test_vx_drift_is_isolated_as_f4(f4_frames: list[Frame], db: CanDatabase) -> None:
    ecu = Ecu("kin")
    diag = _run(ecu, f4_frames)
    detected = [(t, r) for t, r, _ in diag if r.detected]  # type: ignore[attr-defined]
    assert detected, "f4 was not detected"
    assert detected[0][0] > ONSET, "detection before the fault"
    assert detected[0][0] - ONSET < 1.0
    isolated = collections.Counter(tuple(r.candidate_labels(ecu.table)) for _, r in detected if r.isolated)
    assert isolated[("f4",)] >= 100  # isolated as f4 for at least 1 s
    assert set(isolated) == {("f4",)}, f"isolated as something else: {isolated}"
    # every frame says what the C result says (decoded with cantools from the DBC)
    for _, r, data in diag:
        dec = db.decode(DIAG_ID, data)  # raises on a bad E2E CRC
        assert dec.signals["FDI_Status"] == r.status  # type: ignore[attr-defined]
        assert dec.signals["FDI_CandidateFaults"] == r.candidates  # type: ignore[attr-defined]
        assert dec.signals["FDI_AlarmMask"] == r.alarm_mask  # type: ignore[attr-defined]
    iso_frames = [db.decode(DIAG_ID, d) for _, r, d in diag if r.isolated]  # type: ignore[attr-defined]
    assert {d.signals["FDI_IsolationClass"] for d in iso_frames} == {4}
    counters = [e2e.counter_of(d) for _, _, d in diag]
    assert all(b == e2e.next_counter(a) for a, b in itertools.pairwise(counters))


def test_bad_frames_are_counted_and_ignored(clean_frames: list[Frame]) -> None:
    """Every 7th IMU frame corrupted in one way or another: each counted by reason, no detection."""
    kinds = ("crc", "dlc", "repeat", "unknown", "own", "status")
    bad: list[Frame] = []
    expected = collections.Counter[str]()
    n = 0
    prev_imu: Frame | None = None
    for f in clean_frames:
        if f.frame_id == 128 and f.timestamp > 4.0 and prev_imu is not None and n % 7 == 0:
            kind = kinds[(n // 7) % len(kinds)]
            if kind == "crc":
                bad.append(Frame(f.timestamp, f.frame_id, bytes([f.data[0] ^ 0x5A]) + f.data[1:]))
                expected["bad_crc"] += 1
            elif kind == "dlc":
                bad.append(Frame(f.timestamp, f.frame_id, f.data[:6]))
                expected["bad_dlc"] += 1
            elif kind == "repeat":
                bad.append(prev_imu)  # a stale copy of the previous frame: repeated counter
                bad.append(f)
                expected["repeated_counter"] += 1
            elif kind == "unknown":
                bad.append(Frame(f.timestamp, 0x7FF, f.data))
                bad.append(f)
                expected["unknown_id"] += 1
            elif kind == "own":
                bad.append(Frame(f.timestamp, DIAG_ID, f.data))
                bad.append(f)
                expected["own_frame"] += 1
            else:
                raw = bytearray(f.data)
                raw[1] = (raw[1] & 0x0F) | 0x20  # sender status LOCAL_FAULT
                bad.append(Frame(f.timestamp, f.frame_id, e2e.protect(raw, 4224, raw[1] & 0x0F)))
                expected["sensor_status"] += 1
        else:
            bad.append(f)
        if f.frame_id == 128:
            prev_imu = f
            n += 1
    ecu = Ecu("kin")
    diag = _run(ecu, bad)
    c = ecu.counters()
    # a frame lost to a CRC or DLC error makes the next good frame's counter jump by 2: rejected as a jump
    # (the receiver re-synchronises on it), unless max_delta_counter allows it
    for reason in REASONS:
        want = expected.get(reason, 0) + (expected["bad_crc"] + expected["bad_dlc"] if reason == "counter_jump" else 0)
        assert c.rejected[reason] == want, reason
    assert c.messages["IMU_Motion"].rejected == c.rejected | {"unknown_id": 0, "own_frame": 0}
    assert not any(r.detected for _, r, _ in diag)  # type: ignore[attr-defined]


def test_counter_gap_rejected_by_default_accepted_with_max_delta_2(clean_frames: list[Frame]) -> None:
    dropped = [f for i, f in enumerate(clean_frames) if not (f.frame_id == 136 and i % 50 == 0 and f.timestamp > 4)]
    n_drop = len(clean_frames) - len(dropped)
    assert n_drop > 5
    strict, loose = Ecu("kin"), Ecu("kin", max_delta_counter=2)
    _run(strict, dropped)
    _run(loose, dropped)
    assert strict.counters().messages["VelocitySensor"].rejected["counter_jump"] == n_drop
    assert loose.counters().rejected_total == 0


def test_silent_message_makes_its_tests_not_evaluable(clean_frames: list[Frame]) -> None:
    """VelocitySensor silent from 6 s to 8 s: after 3 cycles (30 ms) every kinematic test (they all read vx or
    vy) is not evaluable, the frame says INPUT_INVALID; after it returns the tests warm up and come back."""
    frames = [f for f in clean_frames if not (f.frame_id == 136 and 6.0 <= f.timestamp < 8.0)]
    ecu = Ecu("kin")
    diag = _run(ecu, frames)
    by_ms = {r.t_us // 1000: r for _, r, _ in diag}  # type: ignore[attr-defined]
    assert by_ms[5990].evaluable_mask == 0b1111
    assert by_ms[6020].evaluable_mask == 0b1111  # last frame at 5.991 s: 29 ms old, inside the 30 ms timeout
    assert by_ms[6030].evaluable_mask == 0  # 39 ms old
    assert by_ms[6030].status_name == "INPUT_INVALID"
    assert by_ms[6030].validity & 0b11000 == 0  # vx_m, vy_m invalid
    assert by_ms[8000].evaluable_mask == 0  # back at 8.001 s, then a warm-up of 3.2 s
    assert by_ms[12500].evaluable_mask == 0b1111
    assert ecu.counters().messages["VelocitySensor"].timeouts == 1
    assert not any(r.detected for _, r, _ in diag)  # type: ignore[attr-defined]


def test_result_does_not_depend_on_the_poll_pattern(f4_frames: list[Frame]) -> None:
    """Polling after every frame or only every 50 ms (timer only) gives the same step results."""
    a, b = Ecu("kin"), Ecu("kin")
    ra = {r.step: r for _, r, _ in _run(a, f4_frames)}  # type: ignore[attr-defined]
    rb = {}
    next_poll = 0.0
    for f in f4_frames:
        b.rx(f.frame_id, f.data, f.timestamp)
        if f.timestamp >= next_poll:
            b.poll(f.timestamp)
            rb[b.result().step] = b.result()
            next_poll += 0.05
    common = sorted(set(ra) & set(rb))
    assert len(common) > 200
    for k in common:
        assert ra[k] == rb[k]


def test_bad_arguments() -> None:
    with pytest.raises(TypeError, match="unknown Ecu option"):
        Ecu("kin", cusum=3)
    with pytest.raises(EcuError, match="BAD_ARG"):
        Ecu("kin", warmup_steps=10)  # shorter than the settling time
    with pytest.raises(EcuError, match="BAD_ARG"):
        Ecu("kin", max_delta_counter=0)
    with pytest.raises(ValueError, match="unknown message"):
        Ecu("kin", timeout_s={"Nope": 0.1})
    ecu = Ecu("kin")
    ecu.rx(128, b"", 0.0)  # empty frame: bad dlc, counted
    ecu.rx(128, bytes(64), 0.001)  # CAN FD sized: bad dlc
    assert ecu.counters().rejected["bad_dlc"] == 2


def test_process_in_c_equals_rx_poll_loop(f4_frames: list[Frame]) -> None:
    """Ecu.process (one C call for the whole log) gives the frames and counters of the Python rx/poll loop,
    including for bad frames (an over-long frame and an unknown ID in the middle)."""
    frames = [(f.timestamp, f.frame_id, f.data) for f in f4_frames]
    frames.insert(5000, (frames[5000][0], 128, bytes(12)))
    frames.insert(6000, (frames[6000][0], 0x123, b"\x01\x02"))
    a, b = Ecu("kin"), Ecu("kin")
    batch = a.process(frames)
    loop = []
    for t, can_id, data in frames:
        b.rx(can_id, data, t)
        loop.extend((t, fid, payload) for fid, payload in b.poll(t))
    assert batch == loop and len(batch) > 1000
    assert a.counters() == b.counters()
    assert a.counters().rejected["bad_dlc"] == 1 and a.counters().rejected["unknown_id"] == 1
    assert a.result() == b.result()


def test_bus_is_the_dbc() -> None:
    """The ECU's message table (generated from dbc/romo.dbc into the ROMO target) is the DBC's: the messages node
    FDI receives in ID order with their cycle times and E2E data IDs, each carrying the frame signals the simulator
    maps to it, and the diagnosis frame's ID (the one DIAG_ID of the host tools, also from the DBC)."""
    from fdi_host.can.dbc import DIAG_ID as DBC_DIAG_ID
    from fdi_host.can.dbc import SIGNAL_MAP

    db = CanDatabase()
    bus = bus_info("romo")
    received = sorted((m for m in db.db.messages if "FDI" not in m.senders), key=lambda m: m.frame_id)
    assert bus.messages == tuple((m.name, m.frame_id) for m in received)
    assert bus.cycle_ms == tuple(db.cycle_time_ms(m.name) for m in received)
    assert bus.data_ids == tuple(db.data_id(m.name) for m in received)
    assert bus.diag_id == DIAG_ID == DBC_DIAG_ID == db.message("FDI_Diagnosis").frame_id
    assert bus.diag_data_id == db.data_id("FDI_Diagnosis")
    signals = table_info("romo").signal_names
    for (name, _), mask in zip(bus.messages, bus.signals, strict=True):
        want = sum(1 << signals.index(s.sim) for s in SIGNAL_MAP if s.message == name and s.sim in signals)
        assert mask == want, name


def test_ecu_view_mirrors_the_core() -> None:
    """The offline view that calibrates the gates (fdi_host.can.ecu_view) uses the core's constants: the frames it
    keeps per message, the alignment of the ROMO bus, the default timeouts; the default is sample-and-hold (align
    0, as the view's); an alignment beyond the kept frames is refused."""
    from fdi_host.can import ecu_view
    from fdi_host.ecu.bindings import bus_align, kept_frames

    assert kept_frames() == ecu_view.HISTORY
    assert bus_align("romo") == pytest.approx(ecu_view.bus_align()) and round(bus_align("romo") * 1e6) == 20000
    ecu = Ecu("romo")
    assert ecu.config.align_us == 0
    assert Ecu("romo", align_s=bus_align("romo")).config.align_us == 20000
    bus = bus_info("romo")
    assert list(ecu.config.timeout_us)[: len(bus.cycle_ms)] == [
        ecu_view.TIMEOUT_CYCLES * c * 1000 for c in bus.cycle_ms]
    with pytest.raises(EcuError):
        Ecu("romo", align_s=0.0201)  # the 5 ms messages' kept frames reach back 20 ms


def test_sensitivities_on_request_change_nothing_else(f4_frames: list[Frame]) -> None:
    """With sensitivities requested the ECU's evaluation (residuals, estimates, alarms, detection) is the same as
    without, and each test lists one sensitivity per fault of its generator's sens_mask; without, none are listed.
    (The candidates may differ: with every sensitivity at every step the exoneration reads fresh ones from an
    episode's first step, without it each test's at its turn from the second; fdi_diag.h.)"""
    info = table_info("romo")
    plain, with_sens = Ecu("romo"), Ecu("romo", sensitivities=True)
    a, b = _run(plain, f4_frames), _run(with_sens, f4_frames)
    assert len(a) == len(b) > 0
    for (_, ra, _), (_, rb, _) in zip(a, b, strict=True):
        assert ra.residuals == rb.residuals and ra.offsets == rb.offsets  # type: ignore[attr-defined]
        assert ra.alarm_mask == rb.alarm_mask and ra.detected == rb.detected  # type: ignore[attr-defined]
        assert all(s == () for s in ra.sensitivities)  # type: ignore[attr-defined]
    last = b[-1][1]
    assert [len(s) for s in last.sensitivities] == [len(info.sens_faults(i)) for i in range(info.n_tests)]  # type: ignore[attr-defined]
    assert any(len(s) > 0 for s in last.sensitivities)  # type: ignore[attr-defined]
