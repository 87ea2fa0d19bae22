"""Pictures of a step-by-step diagnosis (the arrays of `fdi_host.diagnosis.Diagnosis`): the candidate faults over
time and the test ratios against their gate. Each draws into a given Axes (`ax=`) or a new figure and returns the
figure; no backend is chosen here."""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import NDArray


def _figure(ax: Axes | None, size: tuple[float, float]) -> tuple[Figure, Axes]:
    if ax is None:
        fig, new = plt.subplots(figsize=size)
        return fig, new
    owner = ax.get_figure()
    assert isinstance(owner, Figure)
    return owner, ax


def plot_candidates(time: NDArray[np.float64], detected: NDArray[np.bool_], candidates: NDArray[np.bool_],
                    faults: Sequence[str], title: str, ax: Axes | None = None) -> Figure:
    """Rows: the detection on top, then the faults (`candidates[step, j]` for `faults[j]`); a filled cell where the
    ECU detects / the fault is a candidate after the step."""
    n = time.size
    grid = np.column_stack([detected, candidates]).T if n else np.zeros((len(faults) + 1, 0), dtype=bool)
    fig, ax = _figure(ax, (9.0, max(2.0, 0.3 * len(faults) + 1.2)))
    if n:
        dt = float(np.median(np.diff(time))) if n > 1 else 0.01
        ax.imshow(grid, aspect="auto", interpolation="nearest", cmap="Blues", vmin=0, vmax=1.3,
                  extent=(float(time[0]) - dt / 2, float(time[-1]) + dt / 2, len(faults) + 0.5, -0.5))
    ax.set_yticks(range(len(faults) + 1), ["detected", *faults], fontsize=7)
    ax.axhline(0.5, color="grey", lw=0.6)
    ax.set_xlabel("time [s]")
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return fig


def plot_ratios(time: NDArray[np.float64], ratios: NDArray[np.float64], evaluable: NDArray[np.bool_],
                tests: Sequence[str], title: str, ax: Axes | None = None) -> Figure:
    """Per test (`ratios[step, i]` for `tests[i]`) its ratio over time where evaluable, the gate at +-1."""
    fig, ax = _figure(ax, (9.0, 3.5))
    for i, name in enumerate(tests):
        ax.plot(time, np.where(evaluable[:, i], ratios[:, i], np.nan), lw=0.8, label=name)
    for y in (-1.0, 1.0):
        ax.axhline(y, color="black", lw=0.6, ls="--")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("residual / gate")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    if tests:
        ax.legend(fontsize=6, ncol=max(1, len(tests) // 6), loc="upper left")
    fig.tight_layout()
    return fig
