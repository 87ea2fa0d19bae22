"""The fleet quality suite (issue 44) in its quick form: truth-plant vehicles and the model plant through the C ECU,
and the shared fault-free part of a truth-plant fault case."""

from __future__ import annotations

import numpy as np

from fdi_host.quality import fleet_report
from fdi_host.quality.fleet import MODEL, TRUTH, quick_config, run_fleet_suite
from fdi_host.sim.faults import FaultSpec
from fdi_host.sim.scenario import load_scenario
from fdi_host.sim.truth_sim import faulty_truth_drive, simulate_truth
from fdi_host.sim.vehicle_envelope import draw_vehicle


def test_fault_case_from_a_snapshot_equals_the_whole_faulty_drive() -> None:
    sc = load_scenario("cornering")
    v = draw_vehicle(5001)
    base = simulate_truth(sc, [], vehicle=v, seed=5, snapshots=[11.0])
    for spec in (FaultSpec("f10", 11.0, 150.0), FaultSpec("f4", 11.0, 0.6)):
        case = faulty_truth_drive(base, spec, until=13.0)
        whole = simulate_truth(sc, [spec], vehicle=v, seed=5, duration=13.0)
        for name in ("vx_m", "omega1_m", "iTM1_m", "ay_m"):
            np.testing.assert_allclose(case.measured[name], whole.measured[name], rtol=0, atol=1e-9)


def test_quick_fleet_suite_scores_both_plants() -> None:
    cfg = quick_config("romo", faults=("f1", "f4", "f10", "f22"), scenarios=("cornering",), workers=1)
    result = run_fleet_suite(cfg)
    assert not result.errors
    truth = [c for c in result.cases if c.plant == TRUTH]
    model = [c for c in result.cases if c.plant == MODEL]
    assert len(truth) == 2 * 4 and len(model) == 4
    # the model plant is the diagnosis' own model: every fault detected within 500 ms
    assert all(c.detected_in_time for c in model)
    assert {d.plant for d in result.fault_free} == {TRUTH, MODEL}
    md = fleet_report.markdown(result)
    assert "truth plant" in md.lower() and "model plant" in md.lower()
    for c in truth:  # a masked case is never counted as detected
        assert not (c.outcome == "masked" and c.detected_in_time)
