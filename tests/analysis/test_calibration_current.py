"""The calibrated sigmas of the generated residuals (analysis/models/romo_thresholds.toml [generated]) are
reproducible and up to date: `fdi-analyze calibrate --check` recomputes them from the fault-free drives as the
ECU sees them and finds the committed table equal (~1.5 min); a stale table is reported and left untouched."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from fdi_analysis.cli import main

MODEL = "analysis/models/romo_grouped.toml"
THRESHOLDS = "analysis/models/romo_thresholds.toml"


def test_committed_sigmas_are_up_to_date(repo: Path, capsys: pytest.CaptureFixture[str],
                                         monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(repo)  # the file's provenance line names the model as scripts/generate.sh does
    code = main(["calibrate", MODEL, "--thresholds", THRESHOLDS, "--check"])
    assert code == 0, capsys.readouterr().err


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
