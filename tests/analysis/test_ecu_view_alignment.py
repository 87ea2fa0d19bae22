"""Why the ECU aligns a step's signals in time (fdi_ecu.h, fdi_host.can.ecu_view): on the simulator's noise-free
straight drive with a rear-left steering offset (f8 at its required 0.06 rad, the vehicle spins), the kinematic
test MSO2 (ay = d/dt vy + vx psidot, structurally blind to f8) computed on each message's last frame at the ECU's
steps shows a residual of its own, larger than its gate; on the signals of one instant it is what the same
generator gives on the true samples at the step instants."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fdi_analysis.export.thresholds import Thresholds
from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.causality import synthesize
from fdi_analysis.residuals.evaluate import FilterDesign, residual
from fdi_host.can.ecu_view import bus_align, ecu_view
from fdi_host.can.traffic import build_frames
from fdi_host.sim.faults import FaultSpec
from fdi_host.sim.scenario import load_scenario
from fdi_host.sim.vehicle_sim import SimConfig, simulate
from fdi_host.tuning.drives import observer_reference

KINEMATIC_Y = ["K2", "D2", "S2", "S3", "S4", "S5"]
ONSET, END = 11.0, 15.0


def test_aligned_signals_remove_the_sampling_residual_of_a_spin(repo: Path) -> None:
    romo = load_model(repo / "analysis/models/romo_grouped.toml")
    th = Thresholds.load(repo / "analysis/models/romo_thresholds.toml")
    design = FilterDesign(th.design[0], th.design[1], th.design[2])
    g = synthesize(romo, KINEMATIC_Y, "MSO2", reference=observer_reference())
    sim = simulate(load_scenario("straight"), [FaultSpec("f8", ONSET, 0.06)], duration=END, seed=2001,
                   config=SimConfig(noise_scale=0.0))
    frames = build_frames(sim)
    step = round(design.dt / sim.config.dt)

    def peak(t: np.ndarray, sig: dict[str, np.ndarray]) -> float:
        r = np.abs(residual(g, sig, design))
        return float(r[(t > ONSET) & (t < END)].max())

    true = peak(sim.t[::step], {k: np.asarray(v[::step], dtype=float) for k, v in sim.measured.items()})
    held = peak(*ecu_view(frames, design.dt))
    aligned = peak(*ecu_view(frames, design.dt, align=bus_align()))
    gate = th.gate * float(np.sqrt(th.generated[" ".join(KINEMATIC_Y)]))
    print(f"MSO2 peak after the f8 onset: true samples {true:.4f}, last frames {held:.4f}, aligned {aligned:.4f} "
          f"m/s^2; gate x sigma {gate:.4f}")
    assert held > 5.0 * aligned and held > gate  # sample-and-hold alone would exclude f8
    assert aligned == pytest.approx(true, rel=0.1)
