"""The on-line estimator and the evaluator with an adaptive threshold, as the C diagnoser runs them
(fw/include/fdi_est.h, fdi_eval.h), for calibrating on drives: compiled with numba, in double precision.

`innovations` runs a test's Kalman filter over its regressors and residual (never frozen: on a calibration drive
there is no alarm to freeze it); `raw_alarm` is the evaluator's raw alarm (gate or two-sided CUSUM) on the residual's
excess over a per-sample spread (the adaptive threshold: e = r shrunk towards 0 by the spread)."""

from __future__ import annotations

from collections.abc import Sequence

import numba
import numpy as np
from numpy.typing import NDArray

from fdi_analysis.residuals.estimation import Estimated

FloatArray = NDArray[np.float64]
DECORRELATION = 10.0  # fdi_diag_config_t.estimate_decorrelation's default (fw/src/fdi_diag.c)


@numba.njit(cache=True)
def _kalman(h: FloatArray, r: FloatArray, mean: FloatArray, var: FloatArray, q: FloatArray, lo: FloatArray,
            hi: FloatArray, step: FloatArray, noise: float, q_scale: float) -> tuple[FloatArray, FloatArray]:
    n, m = h.shape
    theta = mean.copy()
    p = np.diag(var.copy())
    nu = np.empty(n)
    spread = np.empty(n)
    ph = np.empty(m)
    for k in range(n):
        for i in range(m):
            room = var[i] - p[i, i]
            qi = q_scale * q[i]
            if room > 0.0:
                p[i, i] += qi if qi < room else room
        pred = 0.0
        hph = 0.0
        for i in range(m):
            pred += h[k, i] * theta[i]
        for i in range(m):
            s = 0.0
            for j in range(m):
                s += p[i, j] * h[k, j]
            ph[i] = s
            hph += h[k, i] * s
        if hph < 0.0:
            hph = 0.0
        nu[k] = r[k] - pred
        spread[k] = np.sqrt(hph)
        if hph > 0.0:
            inv = 1.0 / (hph + noise)
            for i in range(m):
                move = ph[i] * inv * nu[k]
                cut = 0.0
                if move > step[i]:
                    cut = move - step[i]
                    move = step[i]
                elif move < -step[i]:
                    cut = -step[i] - move
                    move = -step[i]
                theta[i] = min(max(theta[i] + move, lo[i]), hi[i])
                for j in range(m):
                    p[i, j] -= ph[i] * ph[j] * inv
                if p[i, i] < 0.0:
                    p[i, i] = 0.0
                p[i, i] = min(p[i, i] + cut * cut, var[i])
    return nu, spread


def innovations(regressors: FloatArray, r: FloatArray, estimated: Sequence[Estimated], variance: float,
                decorrelation: float = DECORRELATION) -> tuple[FloatArray, FloatArray]:
    """(innovation r - h . theta, prediction spread sqrt(h' P h)) at every sample of a test whose estimator follows
    `estimated` (regressors: one column per quantity, in that order); variance: the residual's (sigma^2), taken times
    `decorrelation` per sample, the declared q alike (fdi_est.h)."""
    if not estimated:
        return np.asarray(r, dtype=float), np.zeros(len(r))
    h = np.ascontiguousarray(regressors, dtype=float).reshape(len(r), len(estimated))

    def col(attr: str) -> FloatArray:
        return np.array([getattr(e, attr) for e in estimated], dtype=float)

    return _kalman(h, np.asarray(r, dtype=float), col("mean"), col("var"), col("q"), col("lo"), col("hi"),
                   col("step"), float(variance) * decorrelation, float(decorrelation))


@numba.njit(cache=True)
def _first_raw(r: FloatArray, spread: FloatArray, starts: NDArray[np.bool_], sigma: float, gate: float, k: float,
               h: float) -> int:
    gp = 0.0
    gm = 0.0
    limit = gate * sigma
    for i in range(r.shape[0]):
        if starts[i]:
            gp = 0.0
            gm = 0.0
        a = spread[i]
        e = r[i] - a if r[i] > a else (r[i] + a if r[i] < -a else 0.0)
        if abs(e) > limit:
            return i
        z = e / sigma
        gp = min(max(0.0, gp + z - k), 2.0 * h)
        gm = min(max(0.0, gm - z - k), 2.0 * h)
        if gp > h or gm > h:
            return i
    return -1


def first_raw_alarm(r: FloatArray, spread: FloatArray, starts: NDArray[np.bool_], sigma: float, gate: float,
                    k: float, h: float) -> int:
    """Index of the first raw alarm (|e| > gate sigma, or a CUSUM of e / sigma beyond h), e the residual's excess
    over the spread; the CUSUM restarts where `starts` is set (an evaluable segment's first sample). -1: none."""
    return int(_first_raw(np.asarray(r, dtype=float), np.asarray(spread, dtype=float), np.asarray(starts, dtype=bool),
                          float(sigma), float(gate), float(k), float(h)))
