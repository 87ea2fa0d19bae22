"""The residual spread report of `fdi-tune uncertainty` (fdi_host.tuning.uncertainty_report) on one test: its
spread is the sum of the shares, its main contributor one of the quantities it is sensitive to, and its
fault-to-uncertainty ratio the fault effect over that spread."""

from __future__ import annotations

from pathlib import Path

from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.causality import synthesize
from fdi_analysis.residuals.evaluate import FilterDesign
from fdi_analysis.residuals.sensitivity import with_sensitivities
from fdi_analysis.residuals.uncertainty_sensitivity import UncertaintySolver
from fdi_host.tuning.drives import drive
from fdi_host.tuning.uncertainty_report import generator_spread, markdown

MSO7 = ["W2.FL", "W2.dyn", "W2.D", "S1", "S2", "S3", "S4", "S5", "S.omega2"]


def test_spread_of_one_test(repo: Path) -> None:
    m = load_model(repo / "analysis/models/romo_grouped.toml")
    g = with_sensitivities(m, synthesize(m, MSO7, "MSO7"))
    sig = drive("cornering", duration=6.0)[1]
    sigma, gate = 2.0, 5.0
    row = generator_spread(m, g, sigma, gate, {"f7": 0.06, "f23": 3.0}, {"cornering": sig}, FilterDesign(),
                           UncertaintySolver(m))
    assert {"R2", "mu_max", "k_t", "g_x", "M_rr2"} <= set(row.uncertain)
    sc = row.scenarios["cornering"]
    assert sc.steps > 200 and sc.spread_median > 0.0 and sc.spread_p95 >= sc.spread_median
    assert sc.top in row.uncertain and 0.0 < sc.top_share <= sc.spread_p95
    # fault-to-noise over fault-to-uncertainty is spread / sigma: the two ratios are of the same effect
    assert sc.fnr["f23"] > 0.0 and sc.fur["f23"] > 0.0
    assert 0.5 < sc.fnr["f23"] / sc.fur["f23"] / (sc.spread_median * gate) < 2.0
    text = markdown(m, [row], "test")
    assert "| MSO7 |" in text and "| f23 | MSO7 | cornering |" in text
