"""Pictures of the structure: the DM-ordered incidence matrix, the single-fault isolability matrix, the paper's
fault matrix (Fig. 4) and selected-faults chart (Fig. 5), the structural next to the practical isolability of a
selection, and the cost of decoupling the residuals from a model's nuisances. Each function draws into a given
Axes (`ax=`, for notebooks) or a new figure, and returns the figure; `save` writes it to a file. No backend is
chosen here."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from fdi_analysis.names import axis_labels
from fdi_analysis.robustness import RobustnessReport
from fdi_analysis.summary import Summary


def _figure(ax: Axes | None, size: tuple[float, float]) -> tuple[Figure, Axes]:
    if ax is None:
        fig, new = plt.subplots(figsize=size)
        return fig, new
    owner = ax.get_figure()
    assert isinstance(owner, Figure)
    return owner, ax


def plot_dm(summary: Summary, ax: Axes | None = None) -> Figure:
    """Incidence matrix with rows/columns in DM order (M-, M0 blocks, M+), the faults as columns of their own on the
    right (past a grey line)."""
    st = summary.structure
    dm = summary.dm
    rows = [*dm.minus_eqs, *dm.zero_eqs, *dm.plus_eqs]
    cols = [*dm.minus_vars, *dm.zero_vars, *dm.plus_vars]
    X = st.X[np.ix_(rows, cols)] != 0
    Fm = st.F[rows] != 0
    nc = len(cols)
    fig, ax = _figure(ax, (max(6.0, 0.11 * (nc + st.nf)) + 2, max(4.0, 0.11 * len(rows))))
    yy, xx = np.nonzero(X)
    ax.scatter(xx, yy, s=6, c="tab:blue", marker="s")
    fy, fx = np.nonzero(Fm)
    ax.scatter(fx + nc + 1, fy, s=8, c="tab:orange", marker="o")
    off = len(dm.minus_eqs) + len(dm.zero_eqs) - 0.5
    offc = len(dm.minus_vars) + len(dm.zero_vars) - 0.5
    ax.axhline(off, color="tab:red", lw=0.8)
    ax.axvline(offc, color="tab:red", lw=0.8)
    ax.axvline(nc, color="grey", lw=0.8)
    ax.set_xlim(-0.5, nc + st.nf + 0.5)
    ax.set_ylim(len(rows) - 0.5, -0.5)
    ax.set_yticks(range(len(rows)), [st.equations[r] for r in rows], fontsize=5)
    ax.set_xticks([*range(nc), *range(nc + 1, nc + 1 + st.nf)], [*(st.unknowns[c] for c in cols), *st.faults],
                  fontsize=5, rotation=90)
    for label in ax.get_xticklabels()[nc:]:
        label.set_color("tab:orange")
    ax.set_title(f"{summary.model.name}: DM decomposition (M+ below/right of the red lines; faults right of the grey "
                 "line)", fontsize=8)
    fig.tight_layout()
    return fig


def plot_isolability(summary: Summary, ax: Axes | None = None) -> Figure:
    """Single-fault isolability: a filled cell (row i, column j) means fault i cannot be isolated from j."""
    st = summary.structure
    iso = summary.isolability
    n = st.nf
    M = ~iso.isolable
    fig, ax = _figure(ax, (max(4.0, 0.28 * n), max(4.0, 0.28 * n)))
    ax.imshow(M, cmap="Blues", vmin=0, vmax=1.6)
    ax.set_xticks(range(n), list(st.faults), fontsize=6, rotation=90)
    ax.set_yticks(range(n), list(st.faults), fontsize=6)
    ax.set_xlabel("fault j")
    ax.set_ylabel("fault i (not isolable from j)")
    ax.set_title(f"{summary.model.name}: single-fault isolability", fontsize=9)
    fig.tight_layout()
    return fig


def plot_fault_matrix(fm_a: np.ndarray, fm_b: np.ndarray, faults: Sequence[str], title: str,
                      ax: Axes | None = None) -> Figure:
    """The paper's Fig. 4: method A as 'x', method B as red squares (row = occurred fault, 0 = no fault)."""
    n = fm_a.shape[0]
    labels = ["0", *axis_labels(faults)]
    fig, ax = _figure(ax, (max(4.0, 0.3 * n), max(4.0, 0.3 * n)))
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
    return fig


def plot_selected_faults(fsm: np.ndarray, faults: Sequence[str], row_labels: list[str], title: str,
                         ax: Axes | None = None) -> Figure:
    """The paper's Fig. 5: which faults affect each selected MSO set (rows = selection index)."""
    nt, nf = fsm.shape
    fig, ax = _figure(ax, (max(5.0, 0.3 * nf), max(2.5, 0.35 * nt + 1.2)))
    yy, xx = np.nonzero(fsm)
    ax.scatter(xx, yy, marker="s", s=60, c="tab:blue")
    ax.set_xticks(range(nf), axis_labels(faults), fontsize=7)
    ax.set_yticks(range(nt), row_labels, fontsize=7)
    ax.set_xlim(-0.5, nf - 0.5)
    ax.set_ylim(nt - 0.5, -0.5)
    ax.set_xlabel("fault")
    ax.set_ylabel("selected MSO set")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return fig


def save(fig: Figure, path: Path) -> Path:
    """Write a figure made by one of these functions to `path` (PNG) and close it."""
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


def plot_practical_isolability(faults: Sequence[str], structural: Mapping[tuple[str, str], bool],
                               practical: Mapping[tuple[str, str], int], n_scenarios: int, title: str,
                               ax: Axes | None = None) -> Figure:
    """Structural next to practical isolability of a selection: cell (i, j) white when the tests practically
    separate faults i and j in every manoeuvre, shaded by the number of manoeuvres where they do not,
    crossed when the tests cannot separate them even structurally (method B)."""
    n = len(faults)
    fig, ax = _figure(ax, (max(5.0, 0.3 * n + 1.5), max(4.5, 0.3 * n + 1.0)))
    missing = np.zeros((n, n))
    for i, a in enumerate(faults):
        for j, b in enumerate(faults):
            if i != j:
                missing[i, j] = n_scenarios - practical.get((a, b), 0)
    im = ax.imshow(missing, cmap="Oranges", vmin=0, vmax=max(1, n_scenarios))
    sy, sx = np.nonzero([[i != j and not structural.get((a, b), False) for j, b in enumerate(faults)]
                         for i, a in enumerate(faults)])
    ax.scatter(sx, sy, marker="x", s=25, c="black", linewidths=0.8, label="not isolable structurally")
    ax.set_xticks(range(n), axis_labels(faults), fontsize=6)
    ax.set_yticks(range(n), axis_labels(faults), fontsize=6)
    ax.set_xlabel("fault")
    ax.set_ylabel("fault")
    ax.set_title(title, fontsize=9)
    cb = fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04)
    cb.set_label(f"manoeuvres (of {n_scenarios}) without practical separation", fontsize=7)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.08), fontsize=7)
    fig.tight_layout()
    return fig


def plot_budget_sweep(costs: Sequence[int], detections: Sequence[int], separations: Sequence[int],
                      meetable_detections: int, meetable_separations: int, complete_cost: int, title: str,
                      ax: Axes | None = None) -> Figure:
    """Requirements met (share of those the complete practical selection meets) against the summed cost of the
    best selection within each budget (`selection.budget.budget_sweep`)."""
    fig, ax = _figure(ax, (6.0, 4.0))
    order = np.argsort(np.asarray(costs, dtype=float), kind="stable")
    x = np.asarray(costs, dtype=float)[order]
    for values, total, label in ((detections, meetable_detections, "detections"),
                                 (separations, meetable_separations, "pair separations"),
                                 ([d + s for d, s in zip(detections, separations, strict=True)],
                                  meetable_detections + meetable_separations, "all requirements")):
        if total > 0:
            ax.step(x, 100.0 * np.asarray(values, dtype=float)[order] / total, where="post", marker="o",
                    markersize=3, label=f"{label} ({total})")
    ax.axvline(complete_cost, color="grey", linestyle=":", label=f"complete selection ({complete_cost})")
    ax.set_xlabel("summed cost of the selected tests [operations per step]")
    ax.set_ylabel("requirements met [%]")
    ax.set_ylim(0.0, 102.0)
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    return fig


def plot_decoupling_cost(report: RobustnessReport, ax: Axes | None = None) -> Figure:
    """What decoupling each nuisance costs, per fault: a dark cell where the fault loses detectability, a light
    one where it loses isolability from some fault (rows: each nuisance alone, the strict rows of the constant and
    slow parameters, every nuisance, the chosen set)."""
    rows = [(f"{c.nuisances[0]}", c) for c in report.each]
    rows += [(f"{c.nuisances[0]} strict", c) for c in report.each_strict]
    rows += [("every nuisance", report.everything), ("chosen: " + ", ".join(report.chosen.nuisances), report.chosen)]
    faults = list(report.nominal.detectable)
    M = np.zeros((len(rows), len(faults)))
    for r, (_, c) in enumerate(rows):
        for f in {a for a, _ in c.lost_isolability}:
            M[r, faults.index(f)] = 1.0
        for f in c.lost_detectability:
            M[r, faults.index(f)] = 2.0
    fig, ax = _figure(ax, (max(6.0, 0.3 * len(faults) + 3.0), max(3.0, 0.3 * len(rows) + 1.5)))
    ax.imshow(M, cmap="Reds", vmin=0, vmax=2.4, aspect="auto")
    ax.set_xticks(range(len(faults)), faults, fontsize=6, rotation=90)
    ax.set_yticks(range(len(rows)), [label for label, _ in rows], fontsize=6)
    ax.set_title(f"{report.model}: cost of decoupling (dark: detectability lost, light: isolability lost)",
                 fontsize=8)
    fig.tight_layout()
    return fig
