"""The ECU's view of CAN traffic: the signal values each fixed diagnosis step works on.

The ECU core (fw/ecu/src/fdi_ecu.c) runs its steps at T_k = t_0 + k * step (t_0: the first frame it
receives, k >= 1); step k sees exactly the frames with timestamp <= T_k, and each signal holds the value of
the last such frame of its message (sample-and-hold). Messages come at their own cycle times and offsets
(dbc/romo.dbc: IMU and wheel robots 5 ms, velocity sensor 10 ms, brake-by-wire 20 ms), so the values of one
step are up to one cycle old and not of the same instant, and they carry the DBC quantisation. Residuals
computed offline on this view equal the ECU's sample by sample (tests/analysis/test_residual_c_vs_python.py),
which is why thresholds and fault sizes are calibrated on it (fdi-tune calibrate, fault-sizes).

Frames with a bad E2E CRC are dropped (as the ECU drops them). Validity is not modelled: before the first
frame of a message its first value is used (the ECU would mark the signal invalid there), so use this view
on logs whose messages all start within the diagnoser's warm-up.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from fdi_host.can.dbc import RomoDatabase
from fdi_host.can.frame import Frame
from fdi_host.can.traffic import decode_frames

FloatArray = NDArray[np.float64]


def step_times(frames: Sequence[Frame], step: float) -> FloatArray:
    """T_k = t_0 + k * step for every k >= 1 the ECU runs (a step runs once a later frame arrives)."""
    if not step > 0.0:
        raise ValueError(f"step must be positive, got {step!r}")
    if not frames:
        return np.zeros(0)
    t0 = frames[0].timestamp
    n = int(np.floor((frames[-1].timestamp - t0) / step - 1e-9))
    return np.asarray(t0 + step * np.arange(1, max(n, 0) + 1), dtype=np.float64)


def ecu_view(frames: Sequence[Frame], step: float = 0.01,
             db: RomoDatabase | None = None) -> tuple[FloatArray, dict[str, FloatArray]]:
    """(step times, simulator signal name -> value at each step) of time-ordered frames."""
    dec = decode_frames(frames, db)
    t = step_times(frames, step)
    out: dict[str, FloatArray] = {}
    for name, values in dec.values.items():
        times = dec.times[dec.message_of[name]]
        idx = np.searchsorted(times, t + 1e-9, side="right") - 1  # last frame with timestamp <= T_k
        out[name] = np.asarray(values[np.maximum(idx, 0)], dtype=float)
    return t, out
