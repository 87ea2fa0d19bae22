"""The committed screening (analysis/models/romo_screening.json.gz, `fdi-tune screen`, ~25 min, regenerated only
with FDI_SCREEN=1) was made with this code's criterion and inputs: the gate of the thresholds file, the detection
margin, share and detection time of fdi_analysis.selection.practical, the required fault sizes, and sigmas over the
calibration's noise seeds on the model plant (the fault-to-noise ratio; the shipped sigmas come from the truth-plant
calibration fleet).
A screening file without its criterion (an older `fdi-tune screen`) is refused with the reason."""

from __future__ import annotations

import gzip
import json
from pathlib import Path

import pytest

from fdi_analysis.export.fault_sizes import FaultSizes
from fdi_analysis.export.thresholds import Thresholds
from fdi_analysis.selection.practical import DETECT_S, MARGIN, SHARE, Screening, ScreeningError
from fdi_host.tuning.cli.calibrate import CALIBRATION_SEEDS

SCREENING = "analysis/models/romo_screening.json.gz"
THRESHOLDS = "analysis/models/romo_thresholds.toml"
SIZES = "host_tools/scenarios/fault_sizes.toml"


def test_committed_screening_has_this_codes_criterion(repo: Path) -> None:
    scr = Screening.load(repo / SCREENING)
    th = Thresholds.load(repo / THRESHOLDS)
    assert (scr.gate, scr.margin, scr.share, scr.detect_s) == (th.gate, MARGIN, SHARE, DETECT_S)
    assert scr.seeds == CALIBRATION_SEEDS
    assert scr.sizes == dict(FaultSizes.load(repo / SIZES).requirement)


def test_screening_sigma_is_the_model_plants_noise(repo: Path) -> None:
    """The screening judges candidates by their fault-to-noise ratio on the model plant: its sigma is the fixed-gate
    calibration's on the model plant's fault-free drives of the calibration seeds (`fdi-tune calibrate` without
    --fleet). The shipped sigma ([generated]) comes from the truth-plant calibration fleet instead, with estimators and
    adaptive thresholds (docs/robust_diagnosis.md), so the two differ; recomputed here for the kinematic test MSO1
    (cheap: six equations) up to the rounding of the file (4 significant digits)."""
    from fdi_analysis.model_loader import load_model
    from fdi_analysis.residuals.causality import synthesize
    from fdi_analysis.residuals.evaluate import FilterDesign
    from fdi_host.sim.scenario import SCENARIOS
    from fdi_host.tuning.calibrate import calibrate
    from fdi_host.tuning.cli.calibrate import CALIBRATION_WARMUP
    from fdi_host.tuning.drives import fault_free_drives, residual_segments

    scr = Screening.load(repo / SCREENING)
    th = Thresholds.load(repo / THRESHOLDS)
    mso1 = "K1 D1 S1 S3 S4 S5"
    assert mso1 in th.selection
    screened = {c.equations: c for c in scr.candidates}[mso1].sigma
    design = FilterDesign(th.design[0], th.design[1], th.design[2])
    g = synthesize(load_model(repo / "analysis/models/romo_grouped.toml"), mso1.split(), "MSO1")
    drives = fault_free_drives(scr.scenarios, [None, *CALIBRATION_SEEDS], None, design.dt)
    assert set(scr.scenarios) <= set(SCENARIOS)
    sigma = calibrate(residual_segments(g, drives, round(CALIBRATION_WARMUP / design.dt), design), th.gate).sigma
    assert screened == pytest.approx(sigma, rel=2e-3)


def test_screening_without_its_criterion_is_refused(repo: Path, tmp_path: Path) -> None:
    doc = json.loads(gzip.decompress((repo / SCREENING).read_bytes()))
    del doc["seeds"]
    old = tmp_path / "old.json"
    old.write_text(json.dumps(doc), encoding="utf-8")
    with pytest.raises(ScreeningError, match=r"old\.json: no seeds: made by an older `fdi-tune screen`"):
        Screening.load(old)
