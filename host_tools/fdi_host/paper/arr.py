"""The paper's analytic redundancy relations ARR3 and ARR4 (eq. 8-10), with filtered derivatives.

From the model (K1: ax = dvx - vy*w, K2: ay = dvy + vx*w, S4: vx_m = vx - d_y*w, S5: vy_m = vy + d_x*w,
w = psidot; tests/host/test_arr_paper.py re-derives both with sympy from the model file):

ARR3 (MSO 3, no v_y measurement):   vx = vx_m + d_y*w,  p = d/dt vx - ax_m   (= vy*w)
    r3 = w*dp/dt - p*dw/dt - (ay_m - vx*w)*w^2
ARR4 (MSO 4, no v_x measurement):   vy = vy_m - d_x*w,  q = d/dt vy - ay_m   (= -vx*w)
    r4 = w*dq/dt - q*dw/dt + (ax_m + vy*w)*w^2

Derivatives. Every input passes the same low-pass F(s) = (wc^2 / (s^2 + 2*zeta*wc*s + wc^2))^2, two
cascaded second-order state-variable filters; the SVF chain delivers F*u, d/dt(F*u) and d^2/dt^2(F*u) as
states, so all terms of a residual see the same filter and the same delay (discretised with the bilinear
transform). p' needs the second derivative of vx, which is why two stages are used.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.signal import bilinear, lfilter, lfilter_zi

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class SVFDerivative:
    """Two cascaded second-order state-variable filters: outputs F*u, (F*u)', (F*u)''."""

    cutoff_hz: float = 1.0
    zeta: float = 1.0 / math.sqrt(2.0)

    def apply(self, u: FloatArray, dt: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        wc = 2.0 * math.pi * self.cutoff_hz
        sec = np.array([1.0, 2.0 * self.zeta * wc, wc * wc])
        den = np.polymul(sec, sec)
        outs = []
        for k in range(3):
            num = np.zeros(k + 1)
            num[0] = wc**4  # wc^4 * s^k
            b, a = bilinear(num, den, fs=1.0 / dt)
            zi = lfilter_zi(b, a) * u[0]
            outs.append(np.asarray(lfilter(b, a, u, zi=zi)[0], dtype=float))
        return outs[0], outs[1], outs[2]


@dataclass(frozen=True)
class ArrInputs:
    """The five body-motion measurements on a uniform time grid."""

    t: FloatArray
    vx_m: FloatArray
    vy_m: FloatArray
    ax_m: FloatArray
    ay_m: FloatArray
    psidot_m: FloatArray

    @property
    def dt(self) -> float:
        return float(self.t[1] - self.t[0])


def arr3_arr4(
    z: ArrInputs, d_x: float, d_y: float, filt: SVFDerivative | None = None
) -> tuple[FloatArray, FloatArray]:
    """Residuals r3, r4 (unit m/s^4... precisely (m/s^2)*(rad/s)^2) on the grid of `z`."""
    filt = filt or SVFDerivative()
    dt = z.dt
    w, dw, _ = filt.apply(z.psidot_m, dt)
    vxm, dvxm, ddvxm = filt.apply(z.vx_m, dt)
    vym, dvym, ddvym = filt.apply(z.vy_m, dt)
    ax, dax, _ = filt.apply(z.ax_m, dt)
    ay, day, _ = filt.apply(z.ay_m, dt)
    _, ddw_unused, ddw = filt.apply(z.psidot_m, dt)
    del ddw_unused
    # ARR3
    vx = vxm + d_y * w
    dvx, ddvx = dvxm + d_y * dw, ddvxm + d_y * ddw
    p, dp = dvx - ax, ddvx - dax
    r3 = w * dp - p * dw - (ay - vx * w) * w**2
    # ARR4
    vy = vym - d_x * w
    dvy, ddvy = dvym - d_x * dw, ddvym - d_x * ddw
    q, dq = dvy - ay, ddvy - day
    r4 = w * dq - q * dw + (ax + vy * w) * w**2
    return r3, r4


def zoh_resample(t_src: FloatArray, x: FloatArray, t_dst: FloatArray) -> FloatArray:
    """Latest sample at or before each destination time (the first sample before the first one)."""
    idx = np.searchsorted(t_src, t_dst + 1e-9, side="right") - 1
    return np.asarray(x[np.clip(idx, 0, x.size - 1)], dtype=float)
