"""Plot of a simulated drive: motion, actuators and wheel speeds, with the fault windows shaded."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt  # no backend chosen here: the command lines choose Agg in their main()
import numpy as np

from fdi_host.sim.faults import FAULT_IDS, active_intervals
from fdi_host.sim.vehicle_sim import SimResult

_COLORS = [plt.get_cmap("tab10")(k) for k in range(10)]


def shade_faults(ax: object, result: SimResult, labels: bool = True) -> None:
    """Shade the intervals where each fault is active (one colour per fault)."""
    k = 0
    for j, fid in enumerate(FAULT_IDS):
        col = result.fault_values[:, j]
        if not col.any():
            continue
        for n, (a, b) in enumerate(active_intervals(col, result.t)):
            ax.axvspan(a, b, color=_COLORS[k % 10], alpha=0.15, lw=0,  # type: ignore[attr-defined]
                       label=fid if (labels and n == 0) else None)
        k += 1


def plot_drive(result: SimResult, path: str | Path) -> Path:
    """Six panels: speeds, yaw rate, accelerations, steering angles, motor currents and pressures,
    wheel speeds; measured signals (noisy) in colour, true values dashed."""
    t = result.t
    m, tr = result.measured, result.true
    fig, axs = plt.subplots(6, 1, figsize=(11, 14), sharex=True)
    panels: list[tuple[str, list[tuple[str, str]], str]] = [
        ("speed [m/s]", [("vx_m", "vx"), ("vy_m", "vy")], "demand_speed"),
        ("yaw rate [rad/s]", [("psidot_m", "psidot")], "demand_yaw_rate"),
        ("acceleration [m/s^2]", [("ax_m", "ax"), ("ay_m", "ay")], ""),
        ("steering angle [rad]", [(f"delta{i}_m", f"delta{i}") for i in (1, 2, 3, 4)], ""),
        ("motor current [A]", [(f"iTM{i}_m", "") for i in (1, 2, 3, 4)], ""),
        ("wheel speed [rad/s]", [(f"omega{i}_m", f"omega{i}") for i in (1, 2, 3, 4)], ""),
    ]
    for ax, (ylabel, pairs, demand) in zip(axs, panels, strict=True):
        for meas, true in pairs:
            (line,) = ax.plot(t, m[meas], lw=0.7, label=meas)
            if true:
                ax.plot(t, tr[true], "--", lw=0.8, color=line.get_color(), alpha=0.8)
        if demand:
            ax.plot(t, tr[demand], ":", color="k", lw=1.0, label=demand)
        shade_faults(ax, result)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=7, ncol=4)
    ax2 = axs[4].twinx()
    ax2.plot(t, m["P_f_m"] * 1e-5, color="k", lw=0.8, label="P_f_m")
    ax2.plot(t, m["P_r_m"] * 1e-5, color="grey", lw=0.8, label="P_r_m")
    ax2.set_ylabel("pressure [bar]")
    axs[-1].set_xlabel("t [s]")
    faults = ", ".join(s.describe() for s in result.faults) or "none"
    fig.suptitle(f"ROMO drive '{result.scenario.name}' on the {result.label} (seed {result.seed}); faults: {faults}",
                 fontsize=10)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def window_mask(t: np.ndarray, a: float, b: float) -> np.ndarray:
    return (t >= a) & (t < b)
