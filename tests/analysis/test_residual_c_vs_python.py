"""The emitted C generators (fw/vehicles/romo/generated/fdi_romo_generators.c through their descriptors on the
generic core) and the Python evaluation of the same generators agree sample by sample on a simulated drive with
faults, for the plain sequential generators and for those with an observer state (float C against double Python,
the observer's error pole keeps the rounding differences from accumulating); so do their fault sensitivities
d r / d f (the C computes them on request from the residual's common subexpressions, the Python twin is
`evaluate.sensitivity_series`), and their adaptive threshold's spread over the model's uncertainty (the Python twin
`uncertainty_sensitivity.spread_series`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from residual_harness import build_harness, committed_generators, run_harness

from fdi_analysis.export.thresholds import Thresholds
from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.evaluate import residual, sensitivity_series
from fdi_analysis.residuals.sensitivity import with_sensitivities
from fdi_analysis.residuals.solvability import Solver
from fdi_analysis.residuals.uncertainty_sensitivity import (
    UncertaintySolver,
    half_widths,
    spread_series,
    with_uncertainty,
)
from fdi_host.tuning.drives import drive


def test_c_and_python_generators_agree(repo: Path, tmp_path: Path) -> None:
    model = load_model(repo / "analysis/models/romo_grouped.toml")
    gens = committed_generators(repo, model)
    # the selection holds generators with integral causality (an observer state in the C instance)
    assert any(g.observer is not None for g in gens) and any(g.observer is None for g in gens)
    _, sig = drive("slalom", duration=12.0, faults=[("f3", 4.0, 0.02), ("f19", 8.0, 400.0)])
    h = build_harness(repo, tmp_path, [f"&fdi_romo_generators[{k}]" for k in range(len(gens))])
    c = run_harness(h, sig).residuals
    assert c.shape == (len(sig["ax_m"]), len(gens))
    for k, g in enumerate(gens):
        py = residual(g, sig)
        scale = float(np.max(np.abs(py)))
        err = float(np.max(np.abs(c[:, k] - py)))
        assert scale > 0.0 and err < 1e-3 * scale, f"{g.name}: C vs Python max deviation {err:.3g}, scale {scale:.3g}"


def test_c_and_python_sensitivities_agree(repo: Path, tmp_path: Path) -> None:
    """d r / d f of the generated C (sens requested) against `sensitivity_series`, for the plain generators and
    one observer generator of the committed table (each fault of its sens_mask, ascending): within 1e-3 of the
    sensitivity's scale on 99.9 % of the samples and within 2e-2 everywhere (a sample where a Max or an Abs of the
    observer's gain switches between the float and the double estimate). With sensitivities requested the
    residuals are the same as without (bit for bit)."""
    model = load_model(repo / "analysis/models/romo_grouped.toml")
    committed = committed_generators(repo, model)
    plain = [k for k, g in enumerate(committed) if g.observer is None]
    observer = [k for k, g in enumerate(committed) if g.observer is not None][:1]
    chosen = sorted(plain + observer)
    solver = Solver(model, keep_faults=True)
    gens = [with_sensitivities(model, committed[k], solver) for k in chosen]
    assert gens and any(g.observer is not None for g in gens) and all(g.sensitivities for g in gens)
    faults = [f.name for f in model.faults]
    _, sig = drive("slalom", duration=12.0, faults=[("f3", 4.0, 0.02), ("f19", 8.0, 400.0)])
    h = build_harness(repo, tmp_path, [f"&fdi_romo_generators[{k}]" for k in chosen],
                      sens_counts=[len(g.sensitivities) for g in gens])
    with_sens = run_harness(h, sig, sens=True)
    assert np.array_equal(with_sens.residuals, run_harness(h, sig).residuals)
    for k, g in enumerate(gens):
        py = sensitivity_series(g, sig)
        order = sorted(py, key=faults.index)
        assert with_sens.sensitivities[k].shape[1] == len(order)
        for j, f in enumerate(order):
            c, p = with_sens.sensitivities[k][1:, j], py[f][1:]
            scale = float(np.max(np.abs(p)))
            assert scale > 0.0, f"{g.name} d r / d {f} is 0 on the drive"
            err = np.abs(c - p) / scale
            assert float(np.quantile(err, 0.999)) < 1e-3 and float(np.max(err)) < 2e-2, \
                f"{g.name} d r / d {f}: C vs Python {float(np.max(err)):.3g} of its scale"


def test_c_and_python_spreads_agree(repo: Path, tmp_path: Path) -> None:
    """The adaptive threshold's term of the generated C, sum |d r / d theta| w_theta over the quantities the test
    does not estimate on line (the thresholds file's [estimation]; the estimated ones are the estimator's, fdi_est.h),
    against `spread_series` of the same generators over the same quantities: the inertial tests estimate all of
    theirs, so their C spread is 0 at every sample; two tyre-law tests (a dozen quantities through the tyre law,
    three of them estimated) within 1e-3 of its scale on 99.9 % of the samples. With the spread requested the
    residuals are the same as without (bit for bit); it moves with the operating point (not a constant) where a
    sensitivity does."""
    model = load_model(repo / "analysis/models/romo_grouped.toml")
    th = Thresholds.load(repo / "analysis/models/romo_thresholds.toml")
    committed = committed_generators(repo, model)
    chosen = [k for k, g in enumerate(committed) if g.name in ("MSO1", "MSO2", "MSO12", "MSO39")]
    assert len(chosen) == 4
    us = UncertaintySolver(model)
    gens = [with_uncertainty(model, committed[k], us) for k in chosen]
    assert all(g.uncertainty for g in gens)
    widths = half_widths(model)
    _, sig = drive("slalom", duration=8.0, faults=[("f3", 4.0, 0.02)])
    h = build_harness(repo, tmp_path, [f"&fdi_romo_generators[{k}]" for k in chosen])
    out = run_harness(h, sig, spread=True)
    assert out.spreads is not None
    assert np.array_equal(out.residuals, run_harness(h, sig).residuals)
    for k, g in enumerate(gens):
        estimated = {q for group in th.estimation[" ".join(g.equations)] for q in group}
        rest = tuple((q, e) for q, e in g.uncertainty if q not in estimated)
        c = out.spreads[1:, k]
        if not rest:
            assert g.name in ("MSO1", "MSO2") and float(np.max(np.abs(c))) == 0.0, g.name
            continue
        assert len(rest) >= 5, (g.name, rest)
        py, _ = spread_series(g, rest, widths, sig)
        p = py[1:]
        scale = float(np.max(p))
        assert scale > 0.0 and float(np.min(c)) >= 0.0
        assert float(np.ptp(p)) > 1e-3 * scale, f"{g.name}: the spread does not move with the operating point"
        err = np.abs(c - p) / scale
        assert float(np.quantile(err, 0.999)) < 1e-3, f"{g.name}: spread C vs Python {float(np.max(err)):.3g}"
