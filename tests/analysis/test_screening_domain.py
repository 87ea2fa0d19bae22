"""The screening's operating domain as a study parameter (`fdi-tune screen --domain-factor`): a tyre-law test,
never evaluable in the low-speed manoeuvre with the generators' own domain (|vx| >= 4 v_eps = 2 m/s), is
screened there at standstill when the factor is 0: its sigma comes from those drives and every fault of its
signature gets a share and a median fault-to-noise ratio. A test whose residual is not finite there (MSO338, at
standstill) is rejected with the reason, not written as NaN."""

from __future__ import annotations

import gzip
import json
import math
from pathlib import Path

import numpy as np
from test_sensitivity import MSO7

from fdi_analysis.export.fault_sizes import FaultSizes
from fdi_analysis.export.thresholds import Thresholds
from fdi_analysis.fault_matrix import Candidate
from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.evaluate import FilterDesign
from fdi_analysis.residuals.generator import DOMAIN_FACTOR
from fdi_analysis.residuals.solvability import Solver
from fdi_analysis.selection.practical import MARGIN, CandidateScreen
from fdi_host.tuning.drives import drive, observer_reference
from fdi_host.tuning.screening import NodeBank, ScreenSetup, screen_candidate


def test_domain_factor_screens_a_tyre_law_test_at_standstill(repo: Path) -> None:
    model = load_model(repo / "analysis/models/romo_grouped.toml")
    th = Thresholds.load(repo / "analysis/models/romo_thresholds.toml")
    design = FilterDesign(th.design[0], th.design[1], th.design[2])
    sizes = dict(FaultSizes.load(repo / "host_tools/scenarios/fault_sizes.toml").requirement)
    drives = [drive("low_speed", seed=seed, as_ecu_sees=True)[1] for seed in (None, 1001)]
    names = [e.id for e in model.equations]
    screening = json.loads(gzip.decompress((repo / "analysis/models/romo_screening.json.gz").read_bytes()))
    mso338 = next(c["equations"].split() for c in screening["candidates"] if c["label"] == "MSO338")

    def screened(eqs: list[str], label: str, factor: float) -> CandidateScreen:
        setup = ScreenSetup(model, observer_reference(th), th.gate, design, sizes, drives, {"low_speed": 0}, MARGIN,
                            factor)
        cand = Candidate(sum(1 << names.index(e) for e in eqs), 0, len(eqs), label)
        with np.errstate(all="ignore"):  # as the screening's workers: a NaN residual is a result here
            return screen_candidate(setup, cand, Solver(model), Solver(model, keep_faults=True),
                                    NodeBank(drives, design))

    out = {factor: screened(MSO7, "MSO7", factor) for factor in (DOMAIN_FACTOR, 0.0)}
    own, study = out[DOMAIN_FACTOR], out[0.0]
    assert own.min_speed == 2.0  # 4 x v_eps = 0.5 m/s
    assert max(float(abs(d["vx_m"]).max()) for d in drives) < own.min_speed
    assert own.rejected == "never evaluable on the calibration drives" and not own.per_fault
    assert study.min_speed == 0.0 and not study.rejected
    assert study.evaluable["low_speed"] >= 0.85  # the whole drive after its 3 s warm-up
    assert math.isfinite(study.sigma) and study.sigma > 0.0
    assert set(study.per_fault) == set(study.faults) and "f23" in study.faults  # the wheel-2 speed sensor
    for fs in study.per_fault.values():
        assert 0.0 <= fs.share["low_speed"] <= 1.0 and fs.median_fnr["low_speed"] >= 0.0
    nan = screened(mso338, "MSO338", 0.0)
    assert nan.rejected == "residual not finite on the calibration drives" and not nan.per_fault
    assert screened(mso338, "MSO338", DOMAIN_FACTOR).rejected == "never evaluable on the calibration drives"
