"""Pictures of the structure: the DM-ordered incidence matrix and the single-fault isolability matrix."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from fdi_analysis.summary import Summary


def plot_dm(summary: Summary, path: Path) -> None:
    """Incidence matrix with rows/columns in DM order (M-, M0 blocks, M+), faults on the right."""
    st = summary.structure
    dm = summary.dm
    rows = [*dm.minus_eqs, *dm.zero_eqs, *dm.plus_eqs]
    cols = [*dm.minus_vars, *dm.zero_vars, *dm.plus_vars]
    X = st.X[np.ix_(rows, cols)] != 0
    Fm = st.F[rows] != 0
    fig_h = max(4.0, 0.11 * len(rows))
    fig, (ax, axf) = plt.subplots(1, 2, figsize=(max(6.0, 0.11 * (len(cols) + st.nf)) + 2, fig_h),
                                  gridspec_kw={"width_ratios": [len(cols), max(st.nf, 1)]})
    yy, xx = np.nonzero(X)
    ax.scatter(xx, yy, s=6, c="tab:blue", marker="s")
    off = len(dm.minus_eqs) + len(dm.zero_eqs) - 0.5
    offc = len(dm.minus_vars) + len(dm.zero_vars) - 0.5
    ax.axhline(off, color="tab:red", lw=0.8)
    ax.axvline(offc, color="tab:red", lw=0.8)
    ax.set_xlim(-0.5, len(cols) - 0.5)
    ax.set_ylim(len(rows) - 0.5, -0.5)
    ax.set_yticks(range(len(rows)), [st.equations[r] for r in rows], fontsize=5)
    ax.set_xticks(range(len(cols)), [st.unknowns[c] for c in cols], fontsize=5, rotation=90)
    ax.set_title(f"{summary.model.name}: DM decomposition (M+ below/right of the red lines)", fontsize=8)
    fy, fx = np.nonzero(Fm)
    axf.scatter(fx, fy, s=8, c="tab:orange", marker="o")
    axf.set_xlim(-0.5, st.nf - 0.5)
    axf.set_ylim(len(rows) - 0.5, -0.5)
    axf.set_yticks([])
    axf.set_xticks(range(st.nf), list(st.faults), fontsize=5, rotation=90)
    axf.set_title("faults", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def plot_isolability(summary: Summary, path: Path) -> None:
    """Single-fault isolability: a filled cell (row i, column j) means fault i cannot be isolated from j."""
    st = summary.structure
    iso = summary.isolability
    n = st.nf
    M = ~iso.isolable
    fig, ax = plt.subplots(figsize=(max(4.0, 0.28 * n), max(4.0, 0.28 * n)))
    ax.imshow(M, cmap="Blues", vmin=0, vmax=1.6)
    ax.set_xticks(range(n), list(st.faults), fontsize=6, rotation=90)
    ax.set_yticks(range(n), list(st.faults), fontsize=6)
    ax.set_xlabel("fault j")
    ax.set_ylabel("fault i (not isolable from j)")
    ax.set_title(f"{summary.model.name}: single-fault isolability", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
