"""`fdi-quality --trace CASE --linearity`: a test's response to the fault against its linearised s F
(host_tools/fdi_host/quality/linearity.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fdi_host.quality import linearity
from fdi_host.quality.cli import main


def test_counted_steps_are_settled_and_stand_out_of_the_floor() -> None:
    t = np.array([0.0, 0.5, 1.0, 1.5, 2.0, 2.5])
    predicted = np.array([10.0, 10.0, 10.0, 0.5, -10.0, 10.0])
    response = np.array([0.0, 5.0, 12.0, 3.0, -20.0, 10.0])
    tr = linearity.TestResponse("MSOx", t, response, predicted, floor=1.0)
    # before SETTLE_S (1 s) nothing counts; at 1.5 s s F = 0.5 is within 3 x the floor
    assert tr.counted().tolist() == [False, False, True, False, True, True]
    assert tr.ratios().tolist() == pytest.approx([1.2, 2.0, 1.0])


def test_an_additive_sensor_offset_is_linear() -> None:
    # f2 (a_y sensor offset) enters the kinematic test MSO2 additively: its settled response is exactly s F
    lin = linearity.check_case("romo", "f2", "straight", 2001)
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


def test_cli_linearity_needs_a_trace_and_writes_its_plot(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["--table", "romo", "--linearity"])
    assert exc.value.code == 2
    assert "--linearity needs --trace" in capsys.readouterr().err
    assert main(["--table", "romo", "--trace", "f2:straight:2001", "--linearity", "--out", str(tmp_path)]) == 0
    assert "MSO2: rho median 1.00" in capsys.readouterr().out
    assert (tmp_path / "linearity-f2-straight-2001.png").stat().st_size > 10_000
