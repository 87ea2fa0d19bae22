"""The DBC: tooling works on it, ranges and resolutions fit the simulator, every frame round-trips."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fdi_host.can import e2e
from fdi_host.can.dbc import DEFAULT_DBC, SIGNAL_MAP, SIMULATED_MESSAGES, CanDatabase, E2EError
from fdi_host.sim.sensors import DEMAND_RANGES, SENSOR_BY_KNOWN, SENSORS


def test_cantools_dump_works() -> None:
    out = subprocess.run([sys.executable, "-m", "cantools", "dump", str(DEFAULT_DBC)],
                         capture_output=True, text=True, check=True).stdout
    for name in (*SIMULATED_MESSAGES, "FDI_Diagnosis"):
        assert name in out


@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc not installed")
def test_generated_c_source_compiles_warning_free(tmp_path: Path) -> None:
    subprocess.run([sys.executable, "-m", "cantools", "generate_c_source", str(DEFAULT_DBC), "-o", str(tmp_path)],
                   check=True, capture_output=True)
    sources = list(tmp_path.glob("*.c"))
    assert sources
    for c in sources:
        subprocess.run(["gcc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-c", str(c), "-o",
                        str(tmp_path / (c.stem + ".o"))], check=True)


def test_required_messages_and_cycle_times(db: CanDatabase) -> None:
    ct = {m: db.cycle_time_ms(m) for m in (*SIMULATED_MESSAGES, "FDI_Diagnosis")}
    assert 5 <= ct["IMU_Motion"] <= 10
    assert all(5 <= ct[f"WheelRobot{i}"] <= 10 for i in (1, 2, 3, 4))
    assert ct["BrakeByWire"] == 20 and ct["FDI_Diagnosis"] == 10  # one frame per diagnosis step
    diag = db.message("FDI_Diagnosis")
    assert diag.get_signal_by_name("FDI_CandidateFaults").length == 25


def test_every_sim_signal_has_a_sensor_spec_and_vice_versa() -> None:
    mapped = {sm.sim for sm in SIGNAL_MAP}
    assert {s.known for s in SENSORS} | set(DEMAND_RANGES) == mapped


@pytest.mark.parametrize("sm", SIGNAL_MAP, ids=lambda s: s.sim)
def test_range_and_resolution(db: CanDatabase, sm: object) -> None:
    from fdi_host.can.dbc import SignalMap

    assert isinstance(sm, SignalMap)
    sig = db.message(sm.message).get_signal_by_name(sm.signal)
    spec = SENSOR_BY_KNOWN.get(sm.sim)
    lo, hi = (spec.op_min, spec.op_max) if spec else DEMAND_RANGES[sm.sim]
    # declared physical range covers the operating range
    assert sig.minimum <= lo * sm.factor and sig.maximum >= hi * sm.factor
    # the raw integer range carries it too: encode the extremes and get them back (no saturation)
    bits = sig.length
    raw_lo, raw_hi = (-(2 ** (bits - 1)), 2 ** (bits - 1) - 1) if sig.is_signed else (0, 2**bits - 1)
    assert raw_lo * sig.scale + sig.offset <= lo * sm.factor
    assert raw_hi * sig.scale + sig.offset >= hi * sm.factor
    for v in (lo, hi):
        frame = db.encode_sim(sm.message, {m.sim: v if m.sim == sm.sim else 0.0
                                           for m in db.maps_by_message[sm.message]}, 0)
        back = db.decode_sim(db.message(sm.message).frame_id, frame)[sm.sim]
        assert abs(back - v) <= 0.51 * sig.scale / sm.factor
    # resolution below the noise (1 sigma) of the sensor
    if spec:
        assert sig.scale / sm.factor < spec.sigma


def test_e2e_on_every_message_with_unique_data_ids(db: CanDatabase) -> None:
    ids = [db.data_id(m) for m in (*SIMULATED_MESSAGES, "FDI_Diagnosis")]
    assert None not in ids and len(set(ids)) == len(ids)


@pytest.mark.parametrize("name", [*SIMULATED_MESSAGES, "FDI_Diagnosis"])
def test_round_trip_every_message(db: CanDatabase, name: str) -> None:
    rng = np.random.default_rng(len(name))
    msg = db.message(name)
    pre = db.prefix(name)
    payload_signals = [s for s in msg.signals if s.name not in (f"{pre}_CRC", f"{pre}_Counter", f"{pre}_Status")]
    for counter in (0, 7, 14):
        vals = {}
        for s in payload_signals:
            if s.scale == 1 and s.offset == 0:  # integer (bitmask) signals
                vals[s.name] = float(rng.integers(0, 2**s.length))
            else:
                vals[s.name] = float(rng.uniform(s.minimum, s.maximum))
        data = db.encode(name, vals, counter, status=1)
        dec = db.decode(msg.frame_id, data)
        assert dec.counter == counter and dec.signals[f"{pre}_Status"] == 1
        for s in payload_signals:
            assert abs(dec.signals[s.name] - vals[s.name]) <= 0.51 * s.scale
        assert data[0] == e2e.p11_crc(data, db.data_id(name) or 0)
        bad = bytearray(data)
        bad[0] ^= 0x01
        with pytest.raises(E2EError):
            db.decode(msg.frame_id, bytes(bad))
        bad = bytearray(data)
        bad[6] ^= 0x80
        with pytest.raises(E2EError):
            db.decode(msg.frame_id, bytes(bad))


def test_candidate_bitmask_carries_all_25_faults(db: CanDatabase) -> None:
    msg = db.message("FDI_Diagnosis")
    for mask in (0x1FFFFFF, 1, 1 << 24, 0x0AAAAAA):
        data = db.encode("FDI_Diagnosis", {"FDI_CandidateFaults": mask, "FDI_AlarmMask": 0xFFF,
                                           "FDI_IsolationClass": 255}, 3)
        dec = db.decode(msg.frame_id, data)
        assert int(dec.signals["FDI_CandidateFaults"]) == mask
        assert int(dec.signals["FDI_AlarmMask"]) == 0xFFF
