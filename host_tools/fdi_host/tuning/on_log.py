"""The generated residuals computed offline on a CAN log, as the ECU computes them, and compared with the ECU.

The log's frames become the signals the ECU's fixed steps see (fdi_host.can.ecu_view); each generator runs on
them inside its operating domain with the diagnoser's warm-up (evaluate.evaluable_segments). The ECU core
(fdi_host.ecu.bindings, the committed generated table) can replay the same frames: `compare_with_ecu` reports,
per test, the largest deviation on the steps both evaluate, relative to the residual's fault-free sigma.
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from fdi_analysis.residuals.evaluate import FilterDesign, evaluable_segments
from fdi_analysis.residuals.generator import Generator
from fdi_host.errors import FdiHostError
from fdi_host.tuning.calibrate import first_alarm

FloatArray = NDArray[np.float64]


class LogError(FdiHostError, ValueError):
    """A log that the generators cannot be evaluated on."""


@dataclass(frozen=True)
class TestTrace:
    name: str
    sigma: float
    r: FloatArray  # residual per step, NaN where the diagnoser does not evaluate the test
    first_alarm_s: float | None  # first raw alarm (gate or CUSUM), None if none

    @property
    def evaluated(self) -> int:
        return int(np.count_nonzero(np.isfinite(self.r)))

    @property
    def peak_ratio(self) -> float:
        return float(np.nanmax(np.abs(self.r)) / self.sigma) if self.evaluated else 0.0

    @property
    def rms_ratio(self) -> float:
        return float(np.sqrt(np.nanmean(self.r**2)) / self.sigma) if self.evaluated else 0.0


@dataclass(frozen=True)
class LogResiduals:
    t: FloatArray  # step times [s]
    gate: float
    tests: list[TestTrace]


def log_residuals(gens: Sequence[Generator], sigmas: Sequence[float], gate: float, t: FloatArray,
                  signals: dict[str, FloatArray], design: FilterDesign, warmup_steps: int) -> LogResiduals:
    """Each generator on the ECU view (t, signals) of a log, where the diagnoser evaluates it."""
    tests = []
    for g, sigma in zip(gens, sigmas, strict=True):
        missing = [k for k in g.knowns if k not in signals]
        if missing:
            raise LogError(f"{g.name} needs {', '.join(missing)}, which no frame of the log carries")
        r = np.full(t.size, np.nan)
        alarm: float | None = None
        for a, seg in evaluable_segments(g, signals, warmup_steps, design):
            r[a:a + seg.size] = seg
            k = first_alarm(seg, sigma, gate)
            if k >= 0 and alarm is None:
                alarm = float(t[a + k])
        tests.append(TestTrace(g.name, sigma, r, alarm))
    return LogResiduals(t, gate, tests)


@dataclass(frozen=True)
class Deviation:
    name: str
    compared: int  # steps both evaluate
    max_dev_sigma: float  # largest |python - ECU| / sigma there


def compare_with_ecu(res: LogResiduals, ecu_residuals: FloatArray, ecu_evaluable: NDArray[np.bool_],
                     skip_steps: int) -> list[Deviation]:
    """Per test: the deviation from the ECU's residuals (one row per ECU step, aligned with res.t), on the
    steps both evaluate, leaving out the first `skip_steps` after each restart of the ECU's evaluation (the
    ECU re-arms a generator on validity, the offline run on the operating domain alone: both settle)."""
    n = min(res.t.size, ecu_residuals.shape[0])
    out = []
    for i, tr in enumerate(res.tests):
        ev = ecu_evaluable[:n, i].copy()
        starts = np.flatnonzero(np.diff(np.concatenate(([False], ev)).astype(np.int8)) == 1)
        for s in starts.tolist():
            ev[s:s + skip_steps] = False
        both = ev & np.isfinite(tr.r[:n])
        dev = np.abs(tr.r[:n][both] - ecu_residuals[:n, i][both])
        out.append(Deviation(tr.name, int(both.sum()), float(dev.max() / tr.sigma) if dev.size else 0.0))
    return out


def write_csv(res: LogResiduals, path: Path) -> None:
    """t, then per test its residual (empty where not evaluated)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(["t_s", *[tr.name for tr in res.tests]])
        for k in range(res.t.size):
            w.writerow([f"{res.t[k]:.6f}", *["" if not np.isfinite(tr.r[k]) else f"{tr.r[k]:.9g}"
                                             for tr in res.tests]])


def plot(res: LogResiduals, path: Path, title: str) -> None:
    """|r| / sigma per test over time with the gate; the first raw alarm marked."""
    import matplotlib.pyplot as plt

    n = len(res.tests)
    fig, axes = plt.subplots(n, 1, figsize=(10, 1.6 * n + 0.8), sharex=True, squeeze=False)
    for ax, tr in zip(axes[:, 0], res.tests, strict=True):
        ax.plot(res.t, np.abs(tr.r) / tr.sigma, lw=0.7, color="tab:blue")
        ax.axhline(res.gate, color="tab:red", lw=0.8, ls="--")
        if tr.first_alarm_s is not None:
            ax.axvline(tr.first_alarm_s, color="tab:orange", lw=0.8)
        ax.set_ylabel(f"{tr.name}\n|r|/sigma", fontsize=7)
        ax.tick_params(labelsize=7)
    axes[-1, 0].set_xlabel("t [s]")
    fig.suptitle(f"{title}: generated residuals (dashed: gate; orange: first raw alarm)", fontsize=9)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
