"""The committed screening (analysis/models/romo_screening.json.gz, `fdi-tune screen`, ~25 min, regenerated only
with FDI_SCREEN=1) was made with this code's criterion and inputs: the gate of the thresholds file, the detection
margin, share and detection time of fdi_analysis.selection.practical, the required fault sizes, and sigmas over the
calibration's noise seeds, so that the practical selection judges each selected test by the sigma it ships with.
A screening file without its criterion (an older `fdi-tune screen`) is refused with the reason."""

from __future__ import annotations

import gzip
import json
import math
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


def test_selected_tests_were_judged_by_their_shipped_sigma(repo: Path) -> None:
    """Each test of the practical selection: the screening's sigma equals the calibrated one ([generated]) up to
    the rounding of the two files (3 and 4 significant digits)."""
    scr = Screening.load(repo / SCREENING)
    th = Thresholds.load(repo / THRESHOLDS)
    by_eqs = {c.equations: c for c in scr.candidates}
    assert th.selection
    for eqs in th.selection:
        shipped = math.sqrt(th.generated[eqs])
        assert by_eqs[eqs].sigma == pytest.approx(shipped, rel=2e-3), eqs


def test_screening_without_its_criterion_is_refused(repo: Path, tmp_path: Path) -> None:
    doc = json.loads(gzip.decompress((repo / SCREENING).read_bytes()))
    del doc["seeds"]
    old = tmp_path / "old.json"
    old.write_text(json.dumps(doc), encoding="utf-8")
    with pytest.raises(ScreeningError, match=r"old\.json: no seeds: made by an older `fdi-tune screen`"):
        Screening.load(old)
