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


def plot_fault_matrix(fm_a: np.ndarray, fm_b: np.ndarray, faults: tuple[str, ...], title: str, path: Path) -> None:
    """The paper's Fig. 4: method A as 'x', method B as red squares (row = occurred fault, 0 = no fault)."""
    n = fm_a.shape[0]
    labels = ["0", *(f.lstrip("f") for f in faults)]
    fig, ax = plt.subplots(figsize=(max(4.0, 0.3 * n), max(4.0, 0.3 * n)))
    by, bx = np.nonzero(fm_b)
    ax.scatter(bx, by, marker="s", s=70, facecolors="none", edgecolors="tab:red", linewidths=1.2,
               label="method B (signatures identical)")
    ay, ax_ = np.nonzero(fm_a)
    ax.scatter(ax_, ay, marker="x", s=30, c="black", linewidths=0.9, label="method A (signature contained)")
    ax.set_xticks(range(n), labels, fontsize=6)
    ax.set_yticks(range(n), labels, fontsize=6)
    ax.set_xlim(-0.5, n - 0.5)
    ax.set_ylim(n - 0.5, -0.5)
    ax.set_xlabel("interpreted as fault")
    ax.set_ylabel("occurred fault")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.set_title(title, fontsize=9)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def plot_selected_faults(fsm: np.ndarray, faults: tuple[str, ...], row_labels: list[str], title: str,
                         path: Path) -> None:
    """The paper's Fig. 5: which faults affect each selected MSO set (rows = selection index)."""
    nt, nf = fsm.shape
    fig, ax = plt.subplots(figsize=(max(5.0, 0.3 * nf), max(2.5, 0.35 * nt + 1.2)))
    yy, xx = np.nonzero(fsm)
    ax.scatter(xx, yy, marker="s", s=60, c="tab:blue")
    ax.set_xticks(range(nf), [f.lstrip("f") for f in faults], fontsize=7)
    ax.set_yticks(range(nt), row_labels, fontsize=7)
    ax.set_xlim(-0.5, nf - 0.5)
    ax.set_ylim(nt - 0.5, -0.5)
    ax.set_xlabel("fault")
    ax.set_ylabel("selected MSO set")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
