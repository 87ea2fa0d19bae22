"""The monitor's outputs: score table (text), report.md, report.json and the PNG plots.

Plots: (1) ``residuals.png`` like the paper's Fig. 6: per test its test ratio (residual over its alarm gate,
from the ECU log; the diagnosis frame carries masks only) with the gate at 1, fault windows shaded;
(2) ``diagnosis.png``: which tests alarm and which faults are candidates over time (from the frames).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt  # no backend chosen here: the command lines choose Agg in their main()
import numpy as np

from fdi_host.ecu.records import DiagRecord, TableClasses
from fdi_host.ecu.session import StepRecord
from fdi_host.monitor.frames import FrameStats
from fdi_host.monitor.gaps import WHAT, Gap, gap_summary
from fdi_host.monitor.score import FaultWindow, Score


def _ms(x: float | None) -> str:
    return "-" if x is None else f"{x * 1e3:.0f} ms"


def score_table(score: Score) -> str:
    """Plain-text table, one line per injected fault, then the false alarms."""
    head = (f"{'fault':6s} {'window [s]':>13s} {'detectable':>10s} {'det. delay':>10s} {'expected':>9s} "
            f"{'iso. delay':>10s} {'iso %':>5s} {'cleared':>9s} {'verdict':>9s} isolation")
    lines = [head, "-" * len(head)]
    for f in score.faults:
        iso = ("-" if f.isolation_correct is None else "ok" if f.isolation_correct else "WRONG" if f.wrong_isolation
               else "unexplained" if f.verdict == "-" else "not isolated")
        if f.not_evaluable:
            iso = f"not evaluable: {f.gap_overlap:.2f} s of its window in gaps"
        elif f.gap_overlap > 0.0:
            iso += f" ({f.gap_overlap:.2f} s of its window in gaps)"
        win = f"{f.start:.2f}-{f.end:.2f}"
        det = _ms(f.detection_delay) if f.detected else "not eval." if f.not_evaluable else "missed"
        lines.append(f"{f.fault:6s} {win:>13s} {'yes' if f.detectable else 'no':>10s} "
                     f"{det:>10s} {f.expected_class:>9s} "
                     f"{_ms(f.isolation_delay):>10s} {100 * f.isolated_fraction:5.0f} "
                     f"{_ms(f.alarm_after_end if f.detected else None):>9s} {f.verdict:>9s} {iso}")
    lines.append("cleared: how long after the fault's end its alarm still held")
    slow = ", ".join(f"{f.fault} {f.alarm_after_end:.2f} s" for f in score.held_beyond_grace)
    lines.append(f"held beyond the {score.grace:g} s grace: {slow or 'none'}")
    lines.append(f"false alarms: {len(score.false_alarms)} episodes, {score.false_alarm_time:.2f} s "
                 f"(over {score.duration:.1f} s, {score.steps} diagnosis steps)")
    lines.append(gap_summary(score.gaps))
    lines += [f"  {g.describe()}" for g in score.gaps]
    return "\n".join(lines)


def frame_table(stats: FrameStats) -> str:
    head = (f"{'id':>5s} {'message':16s} {'received':>8s} {'lost':>5s} {'late':>5s} {'e2e err':>7s} {'max late':>9s} "
            f"{'gaps':>4s} {'gap time':>8s}")
    lines = [head, "-" * len(head)]
    for fid, m in sorted(stats.messages.items()):
        lines.append(f"0x{fid:03X} {m.name:16s} {m.received:8d} {m.lost:5d} {m.late:5d} {m.e2e_errors:7d} "
                     f"{m.max_lateness * 1e3:7.2f}ms {m.gaps:4d} {m.gap_time:7.2f}s")
    return "\n".join(lines)


def write_reports(out_dir: Path, score: Score, stats: FrameStats | None, extra: dict[str, Any]) -> list[Path]:
    out_dir.mkdir(parents=True, exist_ok=True)
    doc = {"score": score.to_json(), "frames": stats.to_json() if stats else None, **extra}
    pj = out_dir / "report.json"
    pj.write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
    md = ["# Diagnosis score", "", *(f"- {k}: {v}" for k, v in extra.items() if not isinstance(v, dict | list)), "",
          "## Per injected fault", "", "```", score_table(score), "```", ""]
    if score.false_alarms:
        md += ["## False alarms", "", "| start [s] | end [s] | tests |", "|---|---|---|"]
        md += [f"| {fa.start:.3f} | {fa.end:.3f} | {fa.tests} |" for fa in score.false_alarms]
        md.append("")
    if score.gaps:
        md += ["## Gaps (silences on the bus)", "", "| stream | what | start [s] | end [s] | duration [s] | resumed |",
               "|---|---|---|---|---|---|"]
        md += [f"| {g.stream} | {WHAT.get(g.stream, g.stream)} | {g.start:.3f} | {g.end:.3f} | {g.duration:.3f} | "
               f"{'yes' if g.resumed else 'no'} |" for g in score.gaps]
        md.append("")
    if stats is not None:
        md += ["## Frames per message", "", "```", frame_table(stats), "```", ""]
    md += ["Plots: residuals.png (test ratios, gate = 1, fault windows shaded), diagnosis.png.", ""]
    pm = out_dir / "report.md"
    pm.write_text("\n".join(md), encoding="utf-8")
    return [pj, pm]


def _shade(ax: Any, windows: Sequence[FaultWindow]) -> None:
    cmap = plt.get_cmap("tab10")
    colors: dict[str, int] = {}
    for w in windows:
        new = w.fault not in colors
        k = colors.setdefault(w.fault, len(colors))
        ax.axvspan(w.start, w.end, color=cmap(k % 10), alpha=0.15, lw=0, label=w.fault if new else None)


def plot_residuals(path: Path, steps: Sequence[StepRecord], windows: Sequence[FaultWindow],
                   classes: TableClasses, origin_lead: float) -> Path | None:
    """Test ratios |r| / gate per test over time (gate at 1), fault windows shaded."""
    if not steps or not steps[0].ratios:
        return None
    n = len(steps[0].ratios)
    t = np.array([s.t - origin_lead for s in steps])
    R = np.array([s.ratios for s in steps], dtype=float)
    fig, axs = plt.subplots(n, 1, figsize=(10, 1.9 * n + 0.8), sharex=True, squeeze=False)
    for i in range(n):
        ax = axs[i, 0]
        ax.plot(t, R[:, i], lw=0.8, color="C0")
        alarm = np.array([s.alarm_mask >> i & 1 for s in steps], dtype=bool)
        ax.plot(t[alarm], R[alarm, i], ".", ms=2, color="C3", label="alarm")
        ax.axhline(1.0, color="k", ls="--", lw=0.8, label="gate")
        ax.set_yscale("symlog", linthresh=1.0)  # the gate and peaks of hundreds on one axis
        ax.set_ylim(bottom=0.0)
        _shade(ax, windows)
        ax.set_ylabel(classes.test_name(i), rotation=0, ha="right")
        ax.grid(alpha=0.3)
        if i == 0:
            ax.legend(loc="upper right", fontsize=7, ncol=6)
    axs[-1, 0].set_xlabel("time [s]")
    fig.suptitle("test ratio per test (alarm when above the gate = 1; symlog scale); fault windows shaded")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_diagnosis(path: Path, records: Sequence[DiagRecord], windows: Sequence[FaultWindow],
                   classes: TableClasses, gaps: Sequence[Gap] = ()) -> Path | None:
    """Alarmed tests and candidate faults over time, as two raster panels; gaps hatched in grey."""
    if not records:
        return None
    t = np.array([r.t for r in records])
    n_tests = max(len(classes.test_names), max(int(r.alarm_mask).bit_length() for r in records), 1)
    windowed = {w.fault for w in windows}
    faults = [j for j, f in enumerate(classes.faults) if any(r.candidates >> j & 1 for r in records) or f in windowed]
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(10, 5), sharex=True)
    for i in range(n_tests):
        on = np.array([r.alarm_mask >> i & 1 for r in records], dtype=bool)
        a1.plot(t[on], np.full(on.sum(), i), "|", color="C3", ms=6)
    a1.set_yticks(range(n_tests), [classes.test_name(i) for i in range(n_tests)])
    a1.set_title("tests in alarm")
    for k, j in enumerate(faults):
        on = np.array([r.candidates >> j & 1 for r in records], dtype=bool)
        a2.plot(t[on], np.full(on.sum(), k), "|", color="C0", ms=6)
    a2.set_yticks(range(len(faults)), [classes.faults[j] for j in faults])
    a2.set_title("candidate faults")
    for ax in (a1, a2):
        _shade(ax, windows)
        for k, g in enumerate(gaps):
            ax.axvspan(g.start, g.end, facecolor="none", edgecolor="0.4", hatch="//", lw=0,
                       label=("gap" if k == 0 and ax is a1 else None))
            if ax is a1:
                ax.text(0.5 * (g.start + g.end), 1.01, "ECU down" if g.stream == "diagnosis" else "sim down",
                        transform=ax.get_xaxis_transform(), ha="center", va="bottom", fontsize=7)
        ax.grid(alpha=0.3)
    if gaps:
        a1.legend(loc="upper right", fontsize=7)
    a2.set_xlabel("time [s]")
    a2.set_xlim(min(0.0, float(t[0])), float(t[-1]))
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
