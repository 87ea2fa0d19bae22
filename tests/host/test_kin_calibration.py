"""The kinematic table's calibration header (fw/vehicles/romo/generated/fdi_kin_calibration.h) is reproducible and
up to date: the committed copy equals what `fdi-tune kin-calibration` computes now (variances from fault-free
simulated drives, reaction sizes from step faults, both through the C ECU core). ~4 min."""

from __future__ import annotations

import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from fdi_host.tuning.cli import main

HEADER = Path(__file__).resolve().parents[2] / "fw" / "vehicles" / "romo" / "generated" / "fdi_kin_calibration.h"


def test_committed_header_is_up_to_date(
        other_fp_path: Callable[[list[str]], subprocess.CompletedProcess[str]]) -> None:
    # in another process on another floating-point path (OpenBLAS kernel and threads, no numpy SIMD): the
    # committed header must come out the same on any machine
    res = other_fp_path([sys.executable, "-m", "fdi_host.tuning.cli", "kin-calibration", "--check", str(HEADER)])
    assert res.returncode == 0, res.stderr
    text = HEADER.read_text(encoding="utf-8")
    variances = [float(v) for v in re.findall(r"#define FDI_KIN_VARIANCE_\d (\S+)f", text)]
    assert len(variances) == 4 and all(v > 0 for v in variances)
    # the known weak pair: MSO1 sees the yaw rate offset f3 only through vy * f3
    sizes = re.search(r"0\.\d+f, 0\.\d+f, 0\.\d+f, 0\.\d+f, /\* f3 \*/", text)
    assert sizes is not None


def test_stale_header_is_reported(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                  monkeypatch: pytest.MonkeyPatch) -> None:
    import fdi_host.tuning.kin_calibration as kc

    monkeypatch.setattr(kc, "calibrations", lambda progress=None: [])
    monkeypatch.setattr(kc, "variances", lambda cals: [])
    monkeypatch.setattr(kc, "reaction_sizes", lambda variance, progress=None: [])
    monkeypatch.setattr(kc, "render", lambda cals, sizes: "new text\n")
    old = tmp_path / "h.h"
    old.write_text("old text\n", encoding="utf-8")
    assert main(["kin-calibration", "--check", str(old)]) == 1
    assert "is stale: run fdi-tune kin-calibration" in capsys.readouterr().err
    assert main(["kin-calibration", "--out", str(old)]) == 0 and old.read_text(encoding="utf-8") == "new text\n"
