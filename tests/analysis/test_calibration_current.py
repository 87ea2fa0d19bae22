"""The calibrated sigmas of the generated residuals and what each test estimates on line
(analysis/models/romo_thresholds.toml [generated], [estimation], [envelope_limits]) are reproducible and up to date:
`fdi-tune calibrate --fleet 12 --check` recomputes them (in another process, on another floating-point path) from the
truth-plant calibration fleet's fault-free drives as the ECU sees them and finds the committed tables equal (~7 min);
a stale table is reported and left untouched."""

from __future__ import annotations

import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from fdi_host.tuning.cli import main

MODEL = "analysis/models/romo_grouped.toml"
THRESHOLDS = "analysis/models/romo_thresholds.toml"
FLEET = 12  # calibration vehicles (scripts/generate.sh)


def test_committed_sigmas_are_up_to_date(
        other_fp_path: Callable[[list[str]], subprocess.CompletedProcess[str]]) -> None:
    # in another process on another floating-point path (OpenBLAS kernel and threads, no numpy SIMD): the
    # committed sigmas must come out the same on any machine; from the repository root, as scripts/generate.sh
    res = other_fp_path([sys.executable, "-m", "fdi_host.tuning.cli", "calibrate", MODEL, "--thresholds", THRESHOLDS,
                         "--fleet", str(FLEET), "--check"])
    assert res.returncode == 0, res.stderr


def test_stale_sigmas_are_reported_and_kept(repo: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    copy = tmp_path / "thresholds.toml"
    shutil.copy(repo / THRESHOLDS, copy)
    before = copy.read_text(encoding="utf-8")
    # another set of drives gives other sigmas: the committed table is stale for them
    code = main(["calibrate", str(repo / MODEL), "--thresholds", str(copy), "--check", "--scenarios", "straight",
                 "--duration", "8", "--seeds"])
    assert code == 1
    assert "is stale: run scripts/generate.sh" in capsys.readouterr().err
    assert copy.read_text(encoding="utf-8") == before


def test_envelope_limits_are_rounded_up() -> None:
    """The written limit never lies below what it covers (margin x the largest magnitude), to 3 digits."""
    from fdi_host.tuning.cli.calibrate import round_up

    for x, up in ((0.9925, 0.993), (0.993, 0.993), (6.7625, 6.77), (0.0641001, 0.0642), (1234.5, 1240.0)):
        assert round_up(x) == pytest.approx(up, rel=1e-12) and round_up(x) >= x * (1 - 1e-12)
    assert round_up(0.0) == 0.0
