"""fdi-sim end to end: a short faulty drive to every output format, ground truth and plot."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from fdi_host.can.logs import read_log
from fdi_host.can.traffic import decode_frames
from fdi_host.cli import main
from fdi_host.sim.scenario import FLEET_SCENARIOS


def test_help_has_examples(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "fdi-sim --scenario fig6 --fault f4@5s:0.5 --out drive.blf" in out


def test_list_names_the_vehicle_scenarios_only(capsys: pytest.CaptureFixture[str]) -> None:
    """The scenario folder also holds the fault-size files and the three-tank drives of the generic simulator:
    --list shows the vehicle scenarios and nothing else, without an error."""
    assert main(["--list"]) == 0
    out = capsys.readouterr()
    assert [line.split()[0] for line in out.out.splitlines()] == sorted(FLEET_SCENARIOS)
    assert out.err == ""


def test_bad_fault_is_a_usage_error() -> None:
    with pytest.raises(SystemExit) as exc:
        main(["--scenario", "straight", "--fault", "f99@1s:1", "--quiet"])
    assert exc.value.code == 2


def test_short_drive_all_outputs(tmp_path: Path) -> None:
    outs = [tmp_path / "d.blf", tmp_path / "d.asc", tmp_path / "d.log"]
    args = ["--scenario", "slalom", "--duration", "2.0", "--no-scenario-faults", "--fault", "f4@1s:0.5",
            "--fault", "f6@0.5s:0.02:ramp=0.5s", "--npz", str(tmp_path / "raw.npz"),
            "--plot", str(tmp_path / "d.png"), "--quiet"]
    for o in outs:
        args += ["--out", str(o)]
    assert main(args) == 0
    truth = json.loads((tmp_path / "d.truth.json").read_text())
    by_fault = {f["fault"]: f for f in truth["faults"]}
    assert set(by_fault) == {"f4", "f6"}
    assert by_fault["f4"]["intervals"][0]["start"] == pytest.approx(1.0)
    assert by_fault["f4"]["equations"] == ["S4"]
    assert by_fault["f6"]["intervals"][0]["max"] == pytest.approx(0.02)
    frames = [read_log(o) for o in outs]
    assert len({len(f) for f in frames}) == 1
    assert all([x.data for x in f] == [x.data for x in frames[0]] for f in frames)
    dec = decode_frames(frames[0])
    raw = np.load(tmp_path / "raw.npz")
    t = dec.times["VelocitySensor"] - dec.times["VelocitySensor"][0] + 0.001
    idx = np.rint(t / 0.001).astype(int)
    jump = dec.values["vx_m"] - raw["true_vx"][idx] + 0.3 * raw["true_psidot"][idx]  # S4 without fault
    assert abs(jump[t < 1.0].mean()) < 0.01 and abs(jump[t > 1.05].mean() - 0.5) < 0.01
    assert (tmp_path / "d.png").stat().st_size > 10_000
