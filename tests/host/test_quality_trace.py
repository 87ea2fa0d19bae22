"""`fdi-quality --trace`: one suite case step by step (host_tools/fdi_host/quality/trace.py)."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import pytest

from fdi_analysis.cli.common import EXIT_ERROR
from fdi_host.quality import trace
from fdi_host.quality.cli import main, parse_ecu_settings
from fdi_host.quality.suite import QualityError, SuiteConfig, case_spec, evaluate_case


@pytest.mark.parametrize("bad", ["f6:straight", "f99:straight:1", "f6:motorway:1", "f6:straight:x"])
def test_bad_case_is_refused(bad: str) -> None:
    with pytest.raises(QualityError, match="FAULT:SCENARIO:SEED"):
        trace.parse_case(bad)


def test_trace_is_the_suite_case_and_names_blind_alarms(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # the trace replays the case as the suite does: its outcome must be the suite's evaluation of the same steps
    case = trace.trace_case("romo", "f4", "cornering", 2001)
    j = case.fault_index
    det, _, outcome, _, _, _, pre = evaluate_case(case.results, case.spec, case.spec.onset, case.table.iso_class[j])
    assert det and pre == 0
    # a sensor fault leaves the vehicle as it was: the same motion as the fault-free drive, and a real one
    assert case.motion[0] == case.motion[1]
    assert case.motion[0][1] > 0.1 and case.motion[0][2] > 5.0
    lines = trace.events(case)
    assert lines and all(" s  " in ln for ln in lines)
    # every alarmed test in the listing is marked blind exactly when its signature lacks f4
    names = [n.split(":")[0] for n in case.table.test_names]
    for i, name in enumerate(names):
        for ln in lines:
            if f" {name} " in ln or f" {name} (blind)" in ln:
                assert (f"{name} (blind)" in ln) == case.blind(i)
    assert ("isolated" in "\n".join(lines)) == (outcome in ("exact", "wrong"))
    # the listing gives |r| / (gate sigma): the square root of the evaluator's ratio r^2 / (gate sigma)^2
    first = next(r for r in case.results if r.detected)
    i = next(i for i in range(case.table.n_tests) if first.alarm_mask >> i & 1)
    assert f"{names[i]} {math.sqrt(first.ratios[i]):.1f}" in "\n".join(lines)
    code = main(["--vehicle", "romo", "--trace", "f4:cornering:2001", "--out", str(tmp_path)])
    assert code == 0
    assert (tmp_path / "trace-f4-cornering-2001.png").stat().st_size > 10_000
    assert "expected class {f4}" in capsys.readouterr().out


def test_trace_reports_how_an_actuator_fault_moves_the_vehicle() -> None:
    # a steering offset under the straight drive's braking yaws the vehicle; the fault-free drive does not
    case = trace.trace_case("romo", "f6", "straight", 2001)
    (vy, yaw, _), (vy0, yaw0, _) = case.motion
    assert yaw > 10 * max(yaw0, 1e-3) and vy > vy0
    assert "largest |yaw rate|" in trace.report(case)


def test_trace_cli_reports_a_bad_case(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--trace", "f4-cornering"]) == EXIT_ERROR
    assert "FAULT:SCENARIO:SEED" in capsys.readouterr().err


def test_trace_needs_a_required_size(tmp_path: Path) -> None:
    sizes = tmp_path / "sizes.toml"
    sizes.write_text("[requirement]\nf1 = 0.5\n", encoding="utf-8")
    with pytest.raises(QualityError, match="no required size for f4"):
        trace.trace_case("romo", "f4", "cornering", 2001, cfg=SuiteConfig(table="romo", sizes_file=sizes))


# The exoneration's logic on the model plant with fixed gates (no on-line estimation, no adaptive threshold: the
# configuration of a table calibrated on its model alone). The default, robust configuration freezes an estimator while
# its test accuses a fault, so a drift's evidence differs; what it achieves is measured by the suites
# (docs/results.md), not pinned here.
FIXED_GATES: tuple[tuple[str, float | int | str], ...] = (("adaptive", False), ("estimate", 0))


@pytest.mark.parametrize(("fault", "scenario"), [("f4", "straight"), ("f5", "straight"), ("f5", "cornering")])
def test_a_drifting_velocity_sensor_is_isolated_to_its_own_class(fault: str, scenario: str) -> None:
    # a vx / vy sensor offset that drifts in over 2 s: the kinematic test that sees it only through its rate
    # (a_x = d vx / dt - ..., a_y = d vy / dt + ...) alarms steadily while it drifts; that alarm must not exclude
    # the drift (it once bounded it as "unbounded", cleared it, and isolated {f3} or nothing)
    cfg = SuiteConfig(table="romo", ecu=FIXED_GATES)
    case = trace.trace_case("romo", fault, scenario, 2001, cfg=cfg, shape="ramp")
    assert case.spec.shape == "ramp" and case.spec.ramp == cfg.ramp_s
    j = case.fault_index
    _, t_ref = case_spec(cfg, fault, case.spec.onset, case.spec.magnitude, "ramp", 1.0)
    assert t_ref == case.spec.onset + cfg.ramp_s  # the ramp reaches the required size
    _, _, outcome, _, _, final, _ = evaluate_case(case.results, case.spec, t_ref, case.table.iso_class[j])
    assert outcome == "exact" and final == (fault,)
    assert "(a ramp over 2 s)" in trace.report(case)


def test_an_ax_offset_is_told_from_a_vx_drift_within_a_second() -> None:
    # f1 (a_x offset): its first alarm, the a_x kinematic test MSO1, is explained by a vx drift (f4) too, which
    # that test sees only through its rate. Each alarmed step bounds how far such a drift has moved ((|r| - 3 sigma)
    # / |rate gain| dt), so f4's implied size grows from the first alarm and the quiet tyre tests, which see a vx
    # offset, clear it: {f1} within 1 s of the detection (it took 1.45 s without the rate bound)
    case = trace.trace_case("romo", "f1", "straight", 2001, cfg=SuiteConfig(table="romo", ecu=FIXED_GATES))
    j4 = 3
    det, _, outcome, iso_delay, _, final, _ = evaluate_case(case.results, case.spec, case.spec.onset,
                                                            case.table.iso_class[0])
    assert det and outcome == "exact" and final == ("f1",)
    # (within 1 s with the model plant's sigmas; with the fleet's, wider for the tyre tests that clear f4, 3.4 s:
    # the suites measure it, docs/results.md)
    assert iso_delay is not None and iso_delay <= 5.0
    before = list(itertools.takewhile(lambda re_: not re_[0].isolated,
                                      ((r, e) for r, e in zip(case.results, case.evidence, strict=True)
                                       if r.detected)))
    bounds = [e.implied[j4] for _, e in before]
    assert bounds and bounds[0] > 0.0  # from the first alarmed step
    assert all(b2 >= b1 for b1, b2 in itertools.pairwise(bounds))  # it only grows while MSO1 alarms alone
    # at most the drift that a 0.5 m/s^2 offset, integrated from the detection to the isolation, allows
    assert 0.1 < bounds[-1] < 0.5 * iso_delay


def test_trace_cli_follows_the_first_shape(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--vehicle", "romo", "--shapes", "ramp", "step", "--trace", "f5:straight:2001",
                 "--out", str(tmp_path)]) == 0
    assert (tmp_path / "trace-f5-straight-2001-ramp.png").stat().st_size > 10_000
    assert "f5 at 0.6 (a ramp over 2 s)" in capsys.readouterr().out


def test_trace_refuses_an_unknown_shape() -> None:
    with pytest.raises(QualityError, match="unknown fault shape"):
        trace.trace_case("romo", "f4", "straight", 2001, shape="intermittent")


@pytest.fixture(scope="module")
def f13_fig6() -> trace.CaseTrace:
    # f13 (wheel 4 drive torque) in Fig. 6: several faults explain the first alarms and leave one by one
    return trace.trace_case("romo", "f13", "fig6", 2001, cfg=SuiteConfig(table="romo", ecu=FIXED_GATES))


def test_trace_shows_the_evidence_of_the_exoneration(f13_fig6: trace.CaseTrace) -> None:
    case = f13_fig6
    steps = list(zip(case.results, case.evidence, strict=True))
    assert len(steps) == len(case.results) > 100
    left_any = False
    for r, e in steps:
        if not r.detected:
            assert e.episode_age == 0 and e.undecided == 0 and not any(e.implied) and e.cleared == 0
            continue
        assert e.episode_age > 0
        # a candidate is either latched (the class isolated first) or still undecided, and never cleared
        assert r.candidates & ~(e.undecided | e.latched) == 0
        assert r.candidates & e.cleared == 0
        # entries of decided faults read 0
        assert all(e.implied[k] == 0.0 and e.cleared_run[k] == 0 for k in range(case.table.n_faults)
                   if not e.undecided >> k & 1)
    for (r0, _), (r1, e1) in itertools.pairwise(steps):
        left = r0.candidates & ~r1.candidates
        if left and r0.accused_mask == r1.accused_mask:
            # with the same accused tests a fault leaves only as exonerated: by the on-line rule after 0.1 s of
            # clearing (10 steps at 10 ms), or by reaction sizes
            assert left & ~e1.cleared == 0
            left_any = True
    assert left_any
    # a fault leaves after the rule cleared it for 10 steps in a row (0.1 s at 10 ms), and the report says so
    runs = [[e.cleared_run[k] for e in case.evidence] for k in range(case.table.n_faults)]
    tenths = [(k, r.index(10)) for k, r in enumerate(runs) if 10 in r]
    assert tenths
    for k, tenth in tenths:
        assert runs[k][tenth - 9:tenth + 1] == list(range(1, 11))
        assert case.evidence[tenth].cleared >> k & 1
    assert "undecided candidates every 0.1 s" in trace.report(case)


def test_ecu_settings_reach_the_ecu(f13_fig6: trace.CaseTrace, capsys: pytest.CaptureFixture[str]) -> None:
    # a smaller noise allowance subtracts less from the alarms: larger implied sizes at the same steps
    cfg = SuiteConfig(table="romo", ecu=FIXED_GATES + parse_ecu_settings("romo", ["noise_allowance=2"]))
    assert cfg.ecu == (*FIXED_GATES, ("noise_allowance", 2))
    assert parse_ecu_settings("romo", ["sensitivities=false", "cusum_h=120.5", "mode=exoneration"]) == (
        ("sensitivities", False), ("cusum_h", 120.5), ("mode", "exoneration"))
    study = trace.trace_case("romo", "f13", "fig6", 2001, cfg=cfg)
    pairs = [(a.implied[k], b.implied[k]) for a, b in zip(f13_fig6.evidence, study.evidence, strict=True)
             for k in range(f13_fig6.table.n_faults) if a.implied[k] > 0.0 and b.implied[k] > 0.0]
    assert pairs and all(b > a for a, b in pairs[:20])
    # the CLI refuses what the ECU does not know, naming it
    for bad, what in (("bogus=1", "bogus"), ("noise_allowance", "KEY=VALUE"), ("mode=weird", "weird")):
        assert main(["--vehicle", "romo", "--ecu", bad, "--quick"]) == EXIT_ERROR
        assert what in capsys.readouterr().err
