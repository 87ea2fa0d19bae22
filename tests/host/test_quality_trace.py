"""`fdi-quality --trace`: one suite case step by step (host_tools/fdi_host/quality/trace.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from fdi_analysis.cli.common import EXIT_ERROR
from fdi_host.quality import trace
from fdi_host.quality.cli import main
from fdi_host.quality.suite import QualityError, SuiteConfig, evaluate_case


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
    code = main(["--table", "romo", "--trace", "f4:cornering:2001", "--out", str(tmp_path)])
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
