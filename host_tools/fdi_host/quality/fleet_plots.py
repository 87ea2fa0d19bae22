"""Plots of a fleet quality run, drawn from its saved report (`fleet.json`, `fleet_report.to_dict`), so that a
finished run can be redrawn without driving again (`fdi-quality --replot fleet.json`). One figure, four panels,
every panel titled with the plant its figures came from:

1. per fault, the share of truth-plant vehicles on which it was detected / isolated in time, beside the model
   plant's share of cases;
2. per fault, the minimum detectable fault as a multiple of the required size, against the requirement (1x) and
   the goal (1.5x); a fault with no detectable size (masked by false alarms, or never detected) is marked at the top;
3. false detections and isolations per hour of fault-free driving, per truth-plant vehicle and on the model plant;
4. the share of fault-free steps in alarm per scenario, truth plant against model plant."""

from __future__ import annotations

import json
from collections import defaultdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fdi_host.errors import FdiHostError
from fdi_host.quality.fleet import MODEL, TRUTH

if TYPE_CHECKING:
    from matplotlib.figure import Figure

MDF_GOAL = 1.5  # issue 45's goal: minimum detectable fault at most 1.5x the required size


class FleetReportError(FdiHostError, ValueError):
    """A saved fleet report that cannot be drawn (not a fleet.json, or one without the keys a plot needs)."""


def load(path: Path) -> dict[str, Any]:
    """A saved fleet report; a clear error if it is not one."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise FleetReportError(f"{path}: not JSON ({exc})") from exc
    missing = [k for k in ("table", "faults", "fault_free_per_vehicle", "fault_free_drives", "config")
               if not isinstance(data, dict) or k not in data]
    if missing:
        raise FleetReportError(f"{path}: not a fleet report of fdi-quality --fleet (missing {', '.join(missing)})")
    report: dict[str, Any] = data
    return report


def _share(n: int, total: int) -> float:
    return n / total if total else 0.0


def _alarm_share_per_scenario(data: dict[str, Any], plant: str) -> dict[str, float]:
    steps: dict[str, int] = defaultdict(int)
    alarm: dict[str, int] = defaultdict(int)
    for d in data["fault_free_drives"]:
        if d["plant"] == plant:
            steps[d["scenario"]] += d["steps"]
            alarm[d["scenario"]] += d["alarm_steps"]
    return {s: _share(alarm[s], steps[s]) for s in steps}


def plot(data: dict[str, Any], path: Path) -> Path:
    """Draw the four panels of one fleet report into `path` (PNG); returns the path."""
    import matplotlib.pyplot as plt

    fig = figure(data)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def figure(data: dict[str, Any]) -> Figure:
    """The four panels of one fleet report, as a matplotlib figure (for a notebook, or `plot` to save it)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = data["faults"]
    faults = [r["fault"] for r in rows]
    x = list(range(len(faults)))
    n_vehicles = len(data["fault_free_per_vehicle"])
    truth = f"truth plant, {n_vehicles} vehicles"
    model_seeds = ", ".join(str(s) for s in data["config"].get("model_plant_seeds", ())) or "none"
    model = f"model plant (seeds {model_seeds})"

    fig, axes = plt.subplots(4, 1, figsize=(max(9.0, 0.42 * len(faults) + 3.0), 15.0))
    fig.suptitle(f"Fleet quality, table {data['table']}: {truth} vs {model}", fontsize=11)

    ax = axes[0]
    w = 0.2
    series = (
        ([100 * r["truth_vehicle_share_detected"] for r in rows], f"{truth}: vehicles detected in time", "C0"),
        ([100 * r["truth_vehicle_share_isolated"] for r in rows], f"{truth}: vehicles isolated in time", "C1"),
        ([100 * _share(r["model_detected_in_time"], r["model_cases"]) for r in rows],
         f"{model}: cases detected in time", "C2"),
        ([100 * _share(r["model_isolated_in_time"], r["model_cases"]) for r in rows],
         f"{model}: cases isolated in time", "C3"),
    )
    for k, (ys, label, color) in enumerate(series):
        xs = [xi + (k - 1.5) * w for xi in x]
        ax.bar(xs, ys, width=w, label=label, color=color)
        for xi, y in zip(xs, ys, strict=True):  # a zero share is a result: mark it, a bar of height 0 is not seen
            if y == 0.0:
                ax.plot(xi, 1.5, marker="_", color=color, ms=5, mew=2)
    ax.axhline(95.0, color="0.3", lw=0.8, ls="--", label="goal: 95 % of the vehicles")
    ax.set_ylim(0, 135)
    ax.set_ylabel("%")
    ax.set_xticks(x, faults, fontsize=8)
    ax.set_title(f"Faults at the required size, {truth} and {model}: detected within 500 ms, isolated within 1 s "
                 "of the detection", fontsize=9)
    ax.legend(fontsize=7, loc="upper center", ncol=3)

    ax = axes[1]
    found = [(xi, r["mdf_multiplier"]) for xi, r in zip(x, rows, strict=True) if r["mdf_multiplier"] is not None]
    top = max([MDF_GOAL * 1.6] + [m * 1.15 for _, m in found])
    if found:
        ax.bar([xi for xi, _ in found], [m for _, m in found], width=0.6, color="C0",
               label="minimum detectable fault (95 % of the vehicles)")
    none = [(xi, r) for xi, r in zip(x, rows, strict=True) if r["mdf_multiplier"] is None]
    masked = [xi for xi, r in none if "masked" in str(r.get("mdf_reason", ""))]
    other = [xi for xi, r in none if "masked" not in str(r.get("mdf_reason", ""))]
    if masked:
        ax.plot(masked, [top * 0.95] * len(masked), "x", color="C3", ms=8,
                label="none: masked (in false alarm before the onset)")
    if other:
        ax.plot(other, [top * 0.95] * len(other), "v", color="C4", ms=7,
                label="none: no size searched reaches 95 %, or not searched")
    ax.axhline(1.0, color="0.2", lw=1.0, label="required size (1x)")
    ax.axhline(MDF_GOAL, color="C1", lw=1.0, ls="--", label=f"goal ({MDF_GOAL:g}x)")
    ax.set_ylim(0, top)
    ax.set_ylabel("x required size")
    ax.set_xticks(x, faults, fontsize=8)
    ax.set_title(f"Minimum detectable fault, {truth}", fontsize=9)
    ax.legend(fontsize=7, loc="upper left")

    ax = axes[2]
    vehicles = sorted(data["fault_free_per_vehicle"], key=int)
    per_h = [(v, data["fault_free_per_vehicle"][v]) for v in vehicles]
    labels = [*vehicles, "model"]
    mff = data["fault_free"].get(MODEL, {"hours": 0.0, "detections": 0, "isolations": 0})
    hours = [h["hours"] for _, h in per_h] + [mff["hours"]]
    det = [h["detections"] / h["hours"] if h["hours"] else 0.0 for _, h in per_h]
    iso = [h["isolations"] / h["hours"] if h["hours"] else 0.0 for _, h in per_h]
    det.append(mff["detections"] / mff["hours"] if mff["hours"] else 0.0)
    iso.append(mff["isolations"] / mff["hours"] if mff["hours"] else 0.0)
    xv = list(range(len(labels)))
    ax.bar([i - 0.2 for i in xv], det, width=0.4, color="C0", label="false detections per hour")
    ax.bar([i + 0.2 for i in xv], iso, width=0.4, color="C1", label="false isolations per hour")
    ax.set_xticks(xv, labels, fontsize=7, rotation=90)
    ax.set_ylabel("events / h")
    ax.set_title(f"Fault-free driving: {truth} ({sum(hours[:-1]):.2f} h; vehicle seeds) and {model} "
                 f"({hours[-1]:.2f} h, last bar); goal 0", fontsize=9)
    ax.legend(fontsize=7, loc="upper right")

    ax = axes[3]
    t_share = _alarm_share_per_scenario(data, TRUTH)
    m_share = _alarm_share_per_scenario(data, MODEL)
    scenarios = list(dict.fromkeys(list(t_share) + list(m_share)))
    xs = list(range(len(scenarios)))
    for off, share, color, label in ((-0.2, t_share, "C3", truth), (0.2, m_share, "C2", model)):
        ys = [100 * share.get(s, 0.0) for s in scenarios]
        ax.bar([i + off for i in xs], ys, width=0.4, color=color, label=label)
        ax.plot([i + off for i, y in zip(xs, ys, strict=True) if y == 0.0], [1.0] * ys.count(0.0), ls="none",
                marker="_", color=color, ms=8, mew=2)
    ax.set_xticks(xs, scenarios, fontsize=8)
    ax.set_ylim(0, 105)
    ax.set_ylabel("% of steps")
    ax.set_title(f"Fault-free steps with an open alarm, per scenario: {truth} and {model}", fontsize=9)
    ax.legend(fontsize=7, loc="upper right")

    fig.tight_layout(rect=(0.0, 0.0, 1.0, 0.98))
    return fig
