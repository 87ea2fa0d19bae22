"""The emitted C generators (fw/generated/fdi_romo_generators.c through fdi_gen) and the Python evaluation of
the same generators agree sample by sample on a simulated drive with faults, for the plain sequential
generators and for those with an observer state (float C against double Python, the observer's error pole
keeps the rounding differences from accumulating)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from residual_harness import build_harness, committed_generators, run_harness

from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.evaluate import residual
from fdi_host.tuning.drives import drive

FDI_GEN_GENERATED_1 = 7


def test_c_and_python_generators_agree(repo: Path, tmp_path: Path) -> None:
    model = load_model(repo / "analysis/models/romo_grouped.toml")
    gens = committed_generators(repo, model)
    # the selection holds generators with integral causality (an observer state in the C instance)
    assert any(g.observer is not None for g in gens) and any(g.observer is None for g in gens)
    _, sig = drive("slalom", duration=12.0, faults=[("f3", 4.0, 0.02), ("f19", 8.0, 400.0)])
    p = model.parameter_values()
    kinds = [FDI_GEN_GENERATED_1 + k for k in range(len(gens))]
    c = run_harness(build_harness(repo, tmp_path), sig, kinds, p["d_x"], p["d_y"])
    assert c.shape == (len(sig["ax_m"]), len(gens))
    for k, g in enumerate(gens):
        py = residual(g, sig)
        scale = float(np.max(np.abs(py)))
        err = float(np.max(np.abs(c[:, k] - py)))
        assert scale > 0.0 and err < 1e-3 * scale, f"{g.name}: C vs Python max deviation {err:.3g}, scale {scale:.3g}"
