"""Frames on the bus: timing, counters, CRCs, and .log/.asc/.blf written and read back unchanged."""

from __future__ import annotations

import dataclasses
import itertools
from pathlib import Path

import numpy as np
import pytest

from fdi_host.can import e2e
from fdi_host.can.dbc import SIMULATED_MESSAGES, CanDatabase
from fdi_host.can.frame import Frame
from fdi_host.can.logs import read_log, write_log
from fdi_host.can.traffic import build_frames, bus_load, decode_frames
from fdi_host.sim.scenario import load_scenario
from fdi_host.sim.vehicle_sim import SimResult, simulate


@pytest.fixture(scope="module")
def drive() -> SimResult:
    return simulate(dataclasses.replace(load_scenario("slalom"), duration=2.0), faults=[])


@pytest.fixture(scope="module")
def frames(drive: SimResult) -> list[Frame]:
    return build_frames(drive, t0=1000.0)


def test_frames_follow_cycle_times_counters_and_crc(frames: list[Frame], db: CanDatabase) -> None:
    assert all(a.timestamp <= b.timestamp for a, b in itertools.pairwise(frames))
    for name in SIMULATED_MESSAGES:
        fid = db.message(name).frame_id
        mine = [f for f in frames if f.frame_id == fid]
        ts = np.array([f.timestamp for f in mine])
        np.testing.assert_allclose(np.diff(ts), db.cycle_time_ms(name) * 1e-3, atol=1e-9)
        assert ts[0] == pytest.approx(1000.0 + db.start_delay_ms(name) * 1e-3)
        rx = e2e.E2EReceiver(db.data_id(name) or 0)
        statuses = [rx.check(f.data) for f in mine]
        assert statuses[0] is e2e.E2EStatus.INITIAL
        assert all(s is e2e.E2EStatus.OK for s in statuses[1:])


def test_decoded_values_are_the_quantised_measurements(drive: SimResult, frames: list[Frame],
                                                       db: CanDatabase) -> None:
    dec = decode_frames(frames, db)
    assert dec.e2e_errors == 0
    for sm_name, vals in dec.values.items():
        t = dec.times[dec.message_of[sm_name]] - 1000.0
        idx = np.rint(t / drive.config.dt).astype(int)
        src = drive.measured.get(sm_name, drive.true.get(sm_name))
        assert src is not None
        sm = next(m for m in db.maps_by_message[dec.message_of[sm_name]] if m.sim == sm_name)
        sig = db.message(sm.message).get_signal_by_name(sm.signal)
        scale = sig.scale / sm.factor
        # a sensor saturates at its signal range (noise around 0 bar reads as 0 bar)
        expected = np.clip(src[idx], sig.minimum / sm.factor, sig.maximum / sm.factor)
        assert np.abs(vals - expected).max() <= 0.5 * scale + 1e-9


def test_corrupted_frames_are_counted(frames: list[Frame]) -> None:
    bad = list(frames[:50])
    bad[10] = Frame(bad[10].timestamp, bad[10].frame_id, bytes([bad[10].data[0] ^ 0xFF]) + bad[10].data[1:])
    assert decode_frames(bad).e2e_errors == 1


@pytest.mark.parametrize("suffix", [".log", ".asc", ".blf"])
def test_log_round_trip(frames: list[Frame], tmp_path: Path, suffix: str) -> None:
    path = tmp_path / f"drive{suffix}"
    assert write_log(frames, path) == len(frames)
    back = read_log(path)
    assert len(back) == len(frames)
    assert [(f.frame_id, f.data) for f in back] == [(f.frame_id, f.data) for f in frames]
    t_in = np.array([f.timestamp for f in frames])
    t_out = np.array([f.timestamp for f in back])
    np.testing.assert_allclose(t_out - t_out[0], t_in - t_in[0], atol=2e-6)


def test_bus_load_is_reasonable(frames: list[Frame], db: CanDatabase) -> None:
    load = bus_load(frames, db.baudrate(), 2.0)
    assert 0.1 < load < 0.5
