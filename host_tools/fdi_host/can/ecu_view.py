"""The ECU's view of CAN traffic: the signal values each fixed diagnosis step works on.

The ECU core (fw/ecu/src/fdi_ecu.c) runs its steps at T_k = t_0 + k * step (t_0: the first frame it
receives, k >= 1); step k sees exactly the frames with timestamp <= T_k. Messages come at their own cycle times
and offsets (dbc/romo.dbc: IMU and wheel robots 5 ms, velocity sensor 10 ms, brake-by-wire 20 ms). By default
(align 0, the ECU's default) each signal holds its message's last frame, so the values of one step are up to one
cycle old and not of one instant; in a fast manoeuvre that difference is a residual of its own. With align > 0
(`bus_align`: the longest cycle time of the messages that carry frame signals, 20 ms on ROMO) the ECU takes the
signals of the instant T_k - align instead, each linear between its message's two frames around it (the newer
frame when they are more than the message's timeout apart; the oldest kept frame before the instant is reached).
The values carry the DBC quantisation. Residuals computed offline on this view equal the ECU's sample by sample
(tests/analysis/test_residuals_on_log.py), which is why thresholds and fault sizes are calibrated on it
(fdi-tune calibrate, fault-sizes).

Frames with a bad E2E CRC are dropped (as the ECU drops them). Validity is not modelled: before the first
frame of a message its first value is used (the ECU would mark the signal invalid there), so use this view
on logs whose messages all start within the diagnoser's warm-up.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from fdi_host.can.dbc import CanDatabase
from fdi_host.can.frame import Frame
from fdi_host.can.traffic import decode_frames

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

# The ECU core's constants (fw/ecu/include/fdi_ecu.h FDI_ECU_HISTORY, fdi_ecu.c TIMEOUT_CYCLES): frames kept per
# message, and the default timeout in cycles.
HISTORY = 6
TIMEOUT_CYCLES = 3


def step_times(frames: Sequence[Frame], step: float) -> FloatArray:
    """T_k = t_0 + k * step for every k >= 1 the ECU runs (a step runs once a later frame arrives)."""
    if not step > 0.0:
        raise ValueError(f"step must be positive, got {step!r}")
    if not frames:
        return np.zeros(0)
    t0 = frames[0].timestamp
    n = int(np.floor((frames[-1].timestamp - t0) / step - 1e-9))
    return np.asarray(t0 + step * np.arange(1, max(n, 0) + 1), dtype=np.float64)


def bus_align(db: CanDatabase | None = None) -> float:
    """The alignment in seconds that takes every message's signals at one instant (fdi_ecu_align_us): the longest
    cycle time of the messages that carry frame signals, at most what every such message's kept frames cover
    ((HISTORY - 2) cycles)."""
    db = db or CanDatabase()
    cycles = [db.cycle_time_ms(m) for m in db.simulated_messages]
    return min(max(cycles), (HISTORY - 2) * min(cycles)) * 1e-3


def _us(t: FloatArray) -> IntArray:
    return np.rint(np.asarray(t, dtype=np.float64) * 1e6).astype(np.int64)


def _at_instants(times: IntArray, values: FloatArray, steps: IntArray, s: IntArray, timeout: int) -> FloatArray:
    """Values of one signal at the instants s of the steps (fdi_ecu.c aligned_values): linear between the frames
    around s_k among those the step sees (timestamp <= T_k), the newer one across a gap above the timeout."""
    last = np.searchsorted(times, steps, side="right") - 1  # newest frame the step sees
    before = np.searchsorted(times, s, side="right") - 1  # newest frame at or before s
    seen = last >= 0
    before = np.where(seen, np.minimum(before, last), 0)
    oldest = np.maximum(last - (HISTORY - 1), 0)  # the ECU keeps HISTORY frames
    none_before = before < oldest
    after = np.minimum(before + 1, np.maximum(last, 0))
    b = np.where(none_before, oldest, before)
    a = np.where(none_before, oldest, after)
    span = times[a] - times[b]
    interp = (span > 0) & (span <= timeout)
    w = np.where(interp, (s - times[b]) / np.where(span > 0, span, 1), 1.0)  # a == b: either value
    out = values[b] + w * (values[a] - values[b])
    return np.asarray(np.where(seen, out, values[0]), dtype=float)


def ecu_view(frames: Sequence[Frame], step: float = 0.01, db: CanDatabase | None = None,
             align: float = 0.0) -> tuple[FloatArray, dict[str, FloatArray]]:
    """(step times, simulator signal name -> value at each step) of time-ordered frames; `align` seconds is how far
    behind each step the signals are taken (0, the ECU's default: each message's last frame)."""
    db = db or CanDatabase()
    align = float(align)
    if not align >= 0.0:
        raise ValueError(f"align must be >= 0, got {align!r}")
    dec = decode_frames(frames, db)
    t = step_times(frames, step)
    if not frames:
        return t, {name: np.zeros(0) for name in dec.values}
    steps = round(frames[0].timestamp * 1e6) + np.rint(np.arange(1, t.size + 1) * step * 1e6).astype(np.int64)
    s = steps - round(align * 1e6)
    out: dict[str, FloatArray] = {}
    for name, values in dec.values.items():
        msg = dec.message_of[name]
        timeout = TIMEOUT_CYCLES * db.cycle_time_ms(msg) * 1000
        out[name] = _at_instants(_us(dec.times[msg]), np.asarray(values, dtype=float), steps, s, timeout)
    return t, out
