"""Threshold calibration: the fault-free noise level of each residual from simulated drives.

The diagnoser (fw/include/fdi_eval.h) raises a raw alarm when |r| > gate * sigma or when a two-sided CUSUM
of z = r / sigma with drift k exceeds h. For each generator, `sigma_for_no_alarm` finds (by bisection) the
smallest sigma with no raw alarm in any fault-free drive after the warm-up; the calibrated sigma is that
times `margin`. Target stated: zero raw alarms on the calibration drives with a margin of 25 % on sigma
(the gate then sits at gate / margin = 4 sigma of the worst fault-free excursion).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

CUSUM_K = 1.5  # fdi_diag default drift [sigma]
CUSUM_H = 150.0  # fdi_diag default threshold [sigma]
MARGIN = 1.25


@dataclass(frozen=True)
class Calibration:
    sigma: float
    rms: float  # fault-free RMS over all drives
    peak: float  # fault-free max |r|

    @property
    def variance(self) -> float:
        return self.sigma**2


def raw_alarm(r: FloatArray, sigma: float, gate: float, k: float = CUSUM_K, h: float = CUSUM_H) -> bool:
    """True when the residual raises a raw alarm anywhere (gate or CUSUM)."""
    z = r / sigma
    if np.any(np.abs(z) > gate):
        return True
    gp = gm = 0.0
    for zk in z.tolist():
        gp = min(max(0.0, gp + zk - k), 2 * h)
        gm = min(max(0.0, gm - zk - k), 2 * h)
        if gp > h or gm > h:
            return True
    return False


def first_alarm(r: FloatArray, sigma: float, gate: float, k: float = CUSUM_K, h: float = CUSUM_H) -> int:
    """Index of the first raw alarm, -1 if none."""
    z = r / sigma
    gp = gm = 0.0
    for i, zk in enumerate(z.tolist()):
        gp = min(max(0.0, gp + zk - k), 2 * h)
        gm = min(max(0.0, gm - zk - k), 2 * h)
        if abs(zk) > gate or gp > h or gm > h:
            return i
    return -1


def sigma_for_no_alarm(drives: Sequence[FloatArray], gate: float) -> float:
    peak = max(float(np.max(np.abs(r))) for r in drives)
    lo, hi = peak / gate / 1e3, peak / gate * 1.0001 + 1e-30
    while any(raw_alarm(r, hi, gate) for r in drives):
        hi *= 2.0
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if any(raw_alarm(r, mid, gate) for r in drives):
            lo = mid
        else:
            hi = mid
    return hi


def calibrate(drives: Sequence[FloatArray], gate: float, margin: float = MARGIN) -> Calibration:
    """Calibration of one residual from its fault-free drives (warm-up already removed)."""
    allr = np.concatenate(list(drives))
    s = sigma_for_no_alarm(drives, gate) * margin
    return Calibration(sigma=float(f"{s:.3g}"), rms=float(np.sqrt(np.mean(allr**2))),
                       peak=float(np.max(np.abs(allr))))
