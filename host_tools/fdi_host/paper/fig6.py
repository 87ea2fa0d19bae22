"""The paper's Fig. 6 reproduced: ARR3 reacts to f4 only, ARR4 to f5 only, a steering fault f6 leaves both
quiet.

Two drives of the ``fig6`` scenario are simulated: a fault-free one (noise seed A) and one with the
scenario's faults f4, f5, f6 in separate windows (noise seed B). Both go through the CAN path: frames are
encoded with the DBC (quantisation, E2E), decoded again, and the residuals are computed at the velocity
sensor's rate (10 ms) from the decoded signals, the IMU signals held from their latest frame.

Band and excursion. The fault-free band of a residual is max |r| over the fault-free drive after the filter
has settled (t >= 3 s). The excursion of a residual for fault f is max |r| of the faulty drive in f's window
(onset to end + 2 s: the removal transient of the 1 Hz fourth-order filter included), reported as a
multiple of the band. "Reacts" and "quiet" in the tests mean excursion >= 5 bands and <= 1.5 bands.

Run: ``python -m fdi_host.paper.fig6 --out-dir out/fig6`` or ``fdi-sim fig6 --out-dir out/fig6``.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fdi_host.can.traffic import build_frames, decode_frames
from fdi_host.paper.arr import ArrInputs, SVFDerivative, arr3_arr4, zoh_resample
from fdi_host.sim.faults import FAULT_IDS, active_intervals
from fdi_host.sim.scenario import Scenario, load_scenario
from fdi_host.sim.vehicle_sim import SimResult, default_plant, simulate

FloatArray = NDArray[np.float64]
SETTLE_S = 3.0
WINDOW_TAIL_S = 2.0
REACT_BANDS = 5.0
QUIET_BANDS = 1.5


@dataclass(frozen=True)
class ResidualRun:
    t: FloatArray
    inputs: ArrInputs
    r3: FloatArray
    r4: FloatArray


@dataclass(frozen=True)
class Fig6Result:
    scenario: Scenario
    cutoff_hz: float
    free: ResidualRun
    faulty: ResidualRun
    faulty_sim: SimResult
    band: dict[str, float]  # r3, r4
    windows: dict[str, tuple[float, float]]  # fault -> evaluation window
    excursion: dict[str, dict[str, float]]  # fault -> {r3, r4} (absolute max)

    def ratio(self, fault: str, residual: str) -> float:
        return self.excursion[fault][residual] / self.band[residual]

    def summary(self) -> dict[str, Any]:
        return {
            "scenario": self.scenario.name,
            "cutoff_hz": self.cutoff_hz,
            "settle_s": SETTLE_S,
            "band": self.band,
            "windows": {f: list(w) for f, w in self.windows.items()},
            "excursion": self.excursion,
            "excursion_in_bands": {
                f: {r: self.ratio(f, r) for r in ("r3", "r4")} for f in self.excursion
            },
            "faults": [s.describe() for s in self.faulty_sim.faults],
            "seeds": {"fault_free": self.free_seed, "faulty": self.faulty_sim.seed},
        }

    @property
    def free_seed(self) -> int:
        return int(self.scenario.seed)


def residuals_via_can(result: SimResult, cutoff_hz: float) -> ResidualRun:
    """Encode the drive into CAN frames, decode them, and evaluate ARR3/ARR4 on the decoded signals."""
    dec = decode_frames(build_frames(result))
    tg = dec.times["VelocitySensor"]
    ti = dec.times["IMU_Motion"]
    z = ArrInputs(
        tg,
        dec.values["vx_m"],
        dec.values["vy_m"],
        zoh_resample(ti, dec.values["ax_m"], tg),
        zoh_resample(ti, dec.values["ay_m"], tg),
        zoh_resample(ti, dec.values["psidot_m"], tg),
    )
    p = default_plant().params
    r3, r4 = arr3_arr4(z, p["d_x"], p["d_y"], SVFDerivative(cutoff_hz))
    return ResidualRun(tg, z, r3, r4)


def run_fig6(
    scenario: str | Scenario = "fig6", cutoff_hz: float = 1.0, faulty_seed: int | None = None
) -> Fig6Result:
    sc = load_scenario(scenario) if isinstance(scenario, str) else scenario
    free_sim = simulate(sc, faults=[], seed=sc.seed)
    faulty_sim = simulate(sc, seed=sc.seed + 1 if faulty_seed is None else faulty_seed)
    free = residuals_via_can(free_sim, cutoff_hz)
    faulty = residuals_via_can(faulty_sim, cutoff_hz)
    settled = free.t >= SETTLE_S
    band = {"r3": float(np.abs(free.r3[settled]).max()), "r4": float(np.abs(free.r4[settled]).max())}
    windows: dict[str, tuple[float, float]] = {}
    excursion: dict[str, dict[str, float]] = {}
    for j, fid in enumerate(FAULT_IDS):
        iv = active_intervals(faulty_sim.fault_values[:, j], faulty_sim.t)
        if not iv:
            continue
        a, b = iv[0][0], iv[-1][1] + WINDOW_TAIL_S
        windows[fid] = (a, b)
        w = (faulty.t >= a) & (faulty.t < b)
        excursion[fid] = {"r3": float(np.abs(faulty.r3[w]).max()), "r4": float(np.abs(faulty.r4[w]).max())}
    return Fig6Result(sc, cutoff_hz, free, faulty, faulty_sim, band, windows, excursion)


def plot_fig6(res: Fig6Result, path: str | Path) -> Path:
    import matplotlib.pyplot as plt  # the backend is the caller's (fdi-sim fig6 chooses Agg)

    z = res.faulty.inputs
    fig, axs = plt.subplots(3, 1, figsize=(10, 8.5), sharex=True)
    axs[0].plot(z.t, z.vx_m, lw=0.8, label="$v_{x,meas}$ [m/s]")
    axs[0].plot(z.t, z.vy_m, lw=0.8, label="$v_{y,meas}$ [m/s]")
    axs[0].plot(z.t, 10 * z.psidot_m, lw=0.8, label=r"10 $\dot\psi_{meas}$ [rad/s]")
    axs[0].set_ylabel("motion")
    for ax, key, label in ((axs[1], "r3", "ARR3: $r_3$"), (axs[2], "r4", "ARR4: $r_4$")):
        ax.plot(res.faulty.t, getattr(res.faulty, key), lw=0.8, color="C3", label=f"{label} (faults)")
        ax.plot(res.free.t, getattr(res.free, key), lw=0.6, color="0.5", alpha=0.8, label="fault-free")
        b = res.band[key]
        ax.axhline(b, ls="--", color="k", lw=0.7, label=f"fault-free band ±{b:.3g}")
        ax.axhline(-b, ls="--", color="k", lw=0.7)
        lim = 1.5 * max(abs(getattr(res.faulty, key)).max(), b)
        ax.set_ylim(-lim, lim)
        ax.set_ylabel(label)
    colors = {"f4": "C0", "f5": "C1", "f6": "C2"}
    for ax in axs:
        for fid, (a, b) in res.windows.items():
            ax.axvspan(a, b - WINDOW_TAIL_S, color=colors.get(fid, "C4"), alpha=0.15, lw=0)
            if ax is axs[0]:
                ax.text((a + b - WINDOW_TAIL_S) / 2, 0.97, fid, transform=ax.get_xaxis_transform(),
                        ha="center", va="top", fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=7, ncol=4)
    axs[-1].set_xlabel("t [s]")
    ratios = "; ".join(
        f"{f}: r3 {res.ratio(f, 'r3'):.1f}, r4 {res.ratio(f, 'r4'):.1f} bands" for f in res.excursion
    )
    fig.suptitle(f"Isolation of f4 and f5 with ARR3/ARR4 (filter {res.cutoff_hz:g} Hz). {ratios}", fontsize=9)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def markdown(res: Fig6Result) -> str:
    lines = [
        f"# Fig. 6 reproduction ({res.scenario.name}, derivative filter {res.cutoff_hz:g} Hz)",
        "",
        f"Fault-free band (max |r| for t >= {SETTLE_S:g} s): r3 = {res.band['r3']:.4g}, "
        f"r4 = {res.band['r4']:.4g}.",
        "",
        "| fault | window [s] | max abs r3 | r3 / band | max abs r4 | r4 / band |",
        "|---|---|---|---|---|---|",
    ]
    for f, w in res.windows.items():
        e = res.excursion[f]
        lines.append(
            f"| {f} | {w[0]:g}-{w[1]:g} | {e['r3']:.4g} | {res.ratio(f, 'r3'):.2f} | {e['r4']:.4g} | "
            f"{res.ratio(f, 'r4'):.2f} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="fdi-sim fig6",
        description="Reproduce the paper's Fig. 6 (ARR3/ARR4 under f4, f5, f6) into PNG, JSON and Markdown.",
        epilog="example: fdi-sim fig6 --out-dir out/fig6   (or: python -m fdi_host.paper.fig6 --out-dir out/fig6)",
    )
    ap.add_argument("--out-dir", type=Path, default=Path("out/fig6"), help="output folder (default out/fig6)")
    ap.add_argument("--scenario", default="fig6", help="scenario name or TOML path (default fig6)")
    ap.add_argument("--cutoff", type=float, default=1.0, help="derivative filter cutoff in Hz (default 1)")
    args = ap.parse_args(argv)
    try:
        res = run_fig6(args.scenario, args.cutoff)
    except KeyboardInterrupt:
        print("interrupted")
        return 130
    out: Path = args.out_dir
    png = plot_fig6(res, out / "fig6.png")
    (out / "fig6.json").write_text(json.dumps(res.summary(), indent=2) + "\n", encoding="utf-8")
    (out / "fig6.md").write_text(markdown(res), encoding="utf-8")
    print(markdown(res))
    print(f"wrote {png}, {out / 'fig6.json'}, {out / 'fig6.md'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
