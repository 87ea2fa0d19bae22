"""Fault injection: parsing, shapes, and that each Table I fault acts where the model puts it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fdi_analysis.names import natural_sorted
from fdi_host.can.traffic import build_frames, decode_frames
from fdi_host.sim.faults import FAULT_IDS, FaultSpec, FaultSpecError, fault_matrix, parse_fault
from fdi_host.sim.scenario import Scenario, load_scenario
from fdi_host.sim.vehicle_sim import SimResult, simulate

ONSET = 1.5
SENSOR_FAULTS = {"f1": "ax_m", "f2": "ay_m", "f3": "psidot_m", "f4": "vx_m", "f5": "vy_m",
                 "f22": "omega1_m", "f23": "omega2_m", "f24": "omega3_m", "f25": "omega4_m"}
MAGNITUDE = {"f1": 0.5, "f2": 0.5, "f3": 0.05, "f4": 0.5, "f5": 0.5, "f22": 2.0, "f23": 2.0, "f24": 2.0,
             "f25": 2.0, **{f"f{k}": 0.05 for k in range(6, 10)}, **{f"f{k}": -100.0 for k in range(10, 14)},
             **{f"f{k}": -100.0 for k in range(14, 18)}, **{f"f{k}": -400.0 for k in range(18, 22)}}


def test_parse_examples() -> None:
    assert parse_fault("f4@5s:0.5") == FaultSpec("f4", 5.0, 0.5)
    s = parse_fault("f6@10s:0.02:ramp=2s")
    assert (s.shape, s.ramp, s.magnitude) == ("ramp", 2.0, 0.02)
    s = parse_fault("f22@4:2:intermittent=1s/0.3:end=9s")
    assert (s.shape, s.period, s.duty, s.end) == ("intermittent", 1.0, 0.3, 9.0)
    assert parse_fault("f10@250ms:-80:for=2s").end == pytest.approx(2.25)
    for bad in ("f26@1s:1", "f4:1", "f4@1s:x", "f4@1s:1:bogus=3", "f4@5s:1:end=2s", "f6@1s:1:ramp=0s"):
        with pytest.raises(FaultSpecError):
            parse_fault(bad)


def test_shapes() -> None:
    t = np.arange(0.0, 10.0, 0.001)
    step = FaultSpec("f1", 2.0, 3.0, end=5.0).profile(t)
    assert step[t < 2.0].max() == 0 and np.all(step[(t >= 2.0) & (t < 5.0)] == 3.0) and step[t >= 5.0].max() == 0
    ramp = FaultSpec("f1", 2.0, 4.0, shape="ramp", ramp=2.0).profile(t)
    assert ramp[np.searchsorted(t, 3.0)] == pytest.approx(2.0) and ramp[-1] == 4.0
    inter = FaultSpec("f1", 1.0, 1.0, shape="intermittent", period=1.0, duty=0.3, end=9.0).profile(t)
    assert inter[(t >= 1.0) & (t < 9.0)].mean() == pytest.approx(0.3, abs=0.01)
    F = fault_matrix([FaultSpec("f7", 0.0, 1.0), FaultSpec("f7", 5.0, 1.0)], t)
    assert F[:, FAULT_IDS.index("f7")].max() == 2.0 and np.count_nonzero(F.any(axis=0)) == 1


@pytest.fixture(scope="module")
def short() -> Scenario:
    return dataclasses.replace(load_scenario("slalom"), duration=3.5, seed=5)


@pytest.fixture(scope="module")
def reference(short: Scenario) -> SimResult:
    return simulate(short, faults=[])


def _run(short: Scenario, fid: str) -> SimResult:
    return simulate(short, faults=[FaultSpec(fid, ONSET, MAGNITUDE[fid])])


@pytest.mark.parametrize("fid", natural_sorted(SENSOR_FAULTS))
def test_sensor_fault_moves_exactly_its_can_signal(short: Scenario, reference: SimResult, fid: str) -> None:
    faulty = _run(short, fid)
    ref_dec = decode_frames(build_frames(reference))
    bad_dec = decode_frames(build_frames(faulty))
    target = SENSOR_FAULTS[fid]
    for name, ref_vals in ref_dec.values.items():
        diff = bad_dec.values[name] - ref_vals
        if name == target:
            t = bad_dec.times[bad_dec.message_of[name]]
            after = t >= ONSET + 0.01
            np.testing.assert_allclose(diff[after], MAGNITUDE[fid], atol=0.6 * 0.01 + 1e-3)
            assert np.all(diff[t < ONSET - 1e-9] == 0.0)
        else:
            assert np.all(diff == 0.0), f"{fid} moved {name}"
    # and the motion itself is untouched
    for s in ("vx", "vy", "psidot", "omega1"):
        assert np.array_equal(faulty.true[s], reference.true[s])


@pytest.mark.parametrize("fid", [f"f{k}" for k in range(6, 10)])
def test_steering_fault_offsets_the_true_angle_not_the_measured_one(
    short: Scenario, reference: SimResult, fid: str
) -> None:
    i = int(fid[1:]) - 5
    faulty = _run(short, fid)
    after = faulty.t >= ONSET
    np.testing.assert_allclose(faulty.clean[f"delta{i}_m"], reference.clean[f"delta{i}_m"], atol=1e-12)
    np.testing.assert_allclose(faulty.true[f"delta{i}"][after] - faulty.clean[f"delta{i}_m"][after],
                               MAGNITUDE[fid], atol=1e-12)
    # the vehicle reacts: the lateral motion changes well beyond sensor noise
    dpsi = np.abs(faulty.true["psidot"] - reference.true["psidot"])
    assert dpsi[~after].max() == 0.0 and dpsi.max() > 0.01


@pytest.mark.parametrize("fid", [f"f{k}" for k in range(10, 22)])
def test_actuator_and_tyre_faults_change_the_dynamics_at_their_wheel(
    short: Scenario, reference: SimResult, fid: str
) -> None:
    wheel = (int(fid[1:]) - 10) % 4 + 1
    faulty = _run(short, fid)
    before = faulty.t < ONSET
    ds = {i: np.abs(faulty.true[f"sL{i}"] - reference.true[f"sL{i}"]).max() for i in (1, 2, 3, 4)}
    assert max(ds, key=lambda i: ds[i]) == wheel, ds
    assert ds[wheel] > 1e-3
    assert np.array_equal(faulty.true["omega1"][before], reference.true["omega1"][before])
    # it shows on the bus: the wheel's speed signal departs from the fault-free drive beyond its noise
    dw = np.abs(faulty.measured[f"omega{wheel}_m"] - reference.measured[f"omega{wheel}_m"])
    assert dw.max() > 0.1
