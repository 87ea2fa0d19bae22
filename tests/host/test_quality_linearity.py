"""`fdi-quality --trace CASE --linearity`: a test's response to the fault against its linearised s F
(host_tools/fdi_host/quality/linearity.py), and the survey over many cases (linearity_survey.py)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from fdi_analysis.export.fault_sizes import SENSITIVITY_MARGIN
from fdi_host.ecu.bindings import table_info
from fdi_host.quality import linearity, linearity_survey
from fdi_host.quality.cli import main
from fdi_host.quality.suite import SuiteConfig


def test_counted_steps_are_settled_and_stand_out_of_the_floor() -> None:
    t = np.array([0.0, 0.5, 1.0, 1.5, 2.0, 2.5])
    predicted = np.array([10.0, 10.0, 10.0, 0.5, -10.0, 10.0])
    response = np.array([0.0, 5.0, 12.0, 3.0, -20.0, 10.0])
    tr = linearity.TestResponse("MSOx", t, response, predicted, floor=1.0)
    # before SETTLE_S (1 s) nothing counts; at 1.5 s s F = 0.5 is within 3 x the floor
    assert tr.counted().tolist() == [False, False, True, False, True, True]
    assert tr.ratios().tolist() == pytest.approx([1.2, 2.0, 1.0])
    # below the level where the rule may use s F (gate x sigma / margin) nothing counts either
    low = linearity.TestResponse("MSOx", t, response, predicted, floor=1.0, gate=7.0, sigma=3.0, margin=2.0)
    assert not low.counted().any()


def test_the_table_states_its_margin_gates_and_sigmas() -> None:
    romo = table_info("romo")
    assert romo.sensitivity_margin == pytest.approx(SENSITIVITY_MARGIN)
    assert len(romo.gates) == len(romo.sigmas) == romo.n_tests
    assert all(g > 0.0 for g in romo.gates) and all(s > 0.0 for s in romo.sigmas)
    # the kinematic table exonerates by reaction sizes: no on-line rule, margin 1
    assert table_info("kin").sensitivity_margin == pytest.approx(1.0)


# The linearisation concerns the generators' residuals; with on-line estimation the evaluated innovation also holds
# what the estimator learnt of the fault before its test alarmed (fdi_est.h), so these cases run with fixed gates.
FIXED_GATES: tuple[tuple[str, float | int | str], ...] = (("adaptive", False), ("estimate", 0))
FIXED_ARGS = ["--ecu", "adaptive=false", "--ecu", "estimate=0"]


def test_an_additive_sensor_offset_is_linear() -> None:
    # f2 (a_y sensor offset) enters the kinematic test MSO2 additively: its settled response is exactly s F
    lin = linearity.check_case("romo", "f2", "straight", 2001, cfg=SuiteConfig(table="romo", ecu=FIXED_GATES))
    assert lin.spec.fault == "f2" and lin.spec.magnitude == pytest.approx(0.5)
    mso2 = next(tr for tr in lin.tests if tr.name == "MSO2")
    rho = mso2.ratios()
    assert rho.size > 200
    assert float(np.min(rho)) > 0.97 and float(np.max(rho)) < 1.03
    # only tests with a sensitivity to the fault are listed
    assert all(tr.name != "MSO1" for tr in lin.tests)


def test_a_steering_offset_in_the_slalom_departs_from_its_linearisation() -> None:
    # through the tyre law near its peak force the slope at the measured angle is not the mean slope over the
    # offset: the strongest test's settled response departs from s F by more than the rule's margin (1.5)
    lin = linearity.check_case("romo", "f6", "slalom", 2001)
    strongest = max(lin.tests, key=lambda tr: float(np.max(np.abs(tr.predicted))))
    rho = strongest.ratios()
    assert rho.size > 100
    assert float(np.max(rho)) > 1.5 or float(np.min(rho)) < 1.0 / 1.5
    text = linearity.report(lin)
    assert f"{strongest.name}: rho median" in text


def test_cli_linearity_of_one_case_writes_its_plot(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--vehicle", "romo", "--trace", "f2:straight:2001", "--linearity", "--out", str(tmp_path),
                 *FIXED_ARGS]) == 0
    assert "MSO2: rho median 1.00" in capsys.readouterr().out
    assert (tmp_path / "linearity-f2-straight-2001.png").stat().st_size > 10_000


def _response(name: str, rho: list[float], predicted: float = 100.0) -> linearity.TestResponse:
    t = np.array([1.0, 1.1, 1.2, 1.3])
    pred = np.full(4, predicted)
    return linearity.TestResponse(name, t, np.array(rho) * pred, pred, floor=1.0, gate=5.0, sigma=3.0, margin=1.5)


def test_the_spread_compares_tests_at_the_same_step() -> None:
    a = _response("A", [1.0, 2.0, 1.0, 1.0])
    b = _response("B", [1.0, 1.0, -0.5, 1.0])
    c = _response("C", [1.0, 0.5, 1.0, 1.0], predicted=5.0)  # below its level: never counted
    spread, hi, lo, t = linearity_survey.step_spread([a, b, c])
    assert t.tolist() == pytest.approx([1.0, 1.1, 1.2, 1.3])
    assert spread.tolist() == [1.0, 2.0, float("inf"), 1.0]  # a test against its prediction: no ratio bounds it
    assert (int(hi[1]), int(lo[1])) == (0, 1)
    only_one = linearity_survey.step_spread([a, c])
    assert only_one[0].size == 0  # one counted test per step: nothing to compare


def test_summaries_count_the_share_within_the_margin() -> None:
    rho = np.array([0.5, 0.7, 1.0, 1.4, 1.6])
    s = linearity_survey.summarise("A", "f1", rho, 1.5)
    assert s.steps == 5 and s.median == pytest.approx(1.0)
    assert s.within == pytest.approx(3 / 5)
    assert np.isnan(linearity_survey.summarise("A", "f1", np.zeros(0), 1.5).median)


def test_cli_survey_over_cases_writes_its_files(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # a wheel-4 torque fault enters the tests' wheel equations linearly: both tests that see it stay near rho 1
    # and never differ by the margin
    args = ["--vehicle", "romo", "--linearity", "--faults", "f13", "--scenarios", "fig6", "--seeds", "2001",
            "--out", str(tmp_path), *FIXED_ARGS]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "1 cases, 1 with at least two tests counting at the same step; in 0 of them" in out
    data = json.loads((tmp_path / "linearity.json").read_text())
    assert data["margin"] == pytest.approx(1.5)
    (case,) = data["cases"]
    assert case["fault"] == "f13" and 1.0 <= case["spread"] < 1.5
    assert {r["test"] for r in data["pooled"] if r["steps"] > 0} == set(case["between"])
    assert all(0.8 < r["median"] < 1.2 and r["within"] == 1.0 for r in data["pooled"] if r["steps"] > 0)
    assert (tmp_path / "linearity.md").read_text().startswith("Linearisation of the on-line rule, table romo")
    assert (tmp_path / "linearity.png").stat().st_size > 10_000
