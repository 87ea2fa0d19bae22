"""Reports of the diagnosis quality suite: JSON (every case and fault-free drive) and a Markdown table."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

from fdi_host.quality.suite import DELAY_GOAL_S, SuiteResult, summary_rows


def _ms(v: object) -> str:
    return "-" if not isinstance(v, float) else f"{1000 * v:.0f}"


def _num(v: object) -> float:
    return float(v) if isinstance(v, int | float) else 0.0


def fault_free_totals(result: SuiteResult) -> dict[str, Any]:
    ff = result.fault_free
    return {
        "drives": len(ff),
        "minutes": sum(d.duration_s for d in ff) / 60.0,
        "detection_events": sum(d.detection_events for d in ff),
        "isolation_events": sum(d.isolation_events for d in ff),
        "alarm_steps": sum(d.alarm_steps for d in ff),
        "scenarios": sorted({d.scenario for d in ff}),
    }


def to_dict(result: SuiteResult) -> dict[str, Any]:
    cfg = dataclasses.asdict(result.config)
    cfg["sizes_file"] = str(result.config.sizes_file)
    return {
        "table": result.table.name,
        "config": cfg,
        "delay_goal_s": DELAY_GOAL_S,
        "sizes": result.sizes,
        "not_in_table": result.not_in_table,
        "summary": summary_rows(result),
        "fault_free": fault_free_totals(result),
        "cases": [dataclasses.asdict(c) for c in result.cases],
        "fault_free_drives": [dataclasses.asdict(d) for d in result.fault_free],
    }


def write_json(result: SuiteResult, path: Path) -> None:
    path.write_text(json.dumps(to_dict(result), indent=1) + "\n", encoding="utf-8")


def markdown(result: SuiteResult) -> str:
    cfg = result.config
    ff = fault_free_totals(result)
    lines = [
        f"## Diagnosis quality, table `{result.table.name}`",
        "",
        f"Scenarios {', '.join(cfg.scenarios)}; sizes x{', x'.join(f'{m:g}' for m in cfg.multipliers)} the minimal "
        f"size of `{cfg.sizes_file.name}`; shapes {', '.join(cfg.shapes)} (ramp to full size in {cfg.ramp_s:g} s; "
        "its delay counts from the time it reaches the minimal size, 0 = detected before). "
        "Isolation: *exact* = some step isolates exactly the fault's structural class and none another class; "
        "*exact share* = mean share of the steps after the detection with that exact isolation. "
        "Goal marks: **yes** met, **NO** not met.",
        "",
        "| fault | size | detected | delay step median / max [ms] | delay ramp median / max [ms] | "
        "structural class | exact | wrong | not isolated | missed | isolation delay median [ms] | exact share | "
        "detection | delay < 300 ms | exact class | never wrong |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]

    def yes(v: object) -> str:
        return "yes" if v else "**NO**"

    for r in summary_rows(result):
        lines.append(
            f"| {r['fault']} | {r['size']:g} | {r['detected']}/{r['cases']} | "
            f"{_ms(r['delay_step_median_s'])} / {_ms(r['delay_step_max_s'])} | "
            f"{_ms(r['delay_ramp_median_s'])} / {_ms(r['delay_ramp_max_s'])} | "
            f"{{{', '.join(r['expected_class'])}}} | {r['isolation_exact']} | {r['isolation_wrong']} | "  # type: ignore[arg-type]
            f"{r['isolation_not_isolated']} | {r['isolation_missed']} | {_ms(r['isolation_delay_median_s'])} | "
            f"{100 * _num(r['exact_share_mean']):.0f} % | {yes(r['goal_detection'])} | "
            f"{yes(r['goal_delay'])} | {yes(r['goal_isolation_exact'])} | {yes(r['goal_never_wrong'])} |"
        )
    if result.not_in_table:
        lines += ["", "Not covered by any test of this table with an on-board generator (not run): "
                  f"{', '.join(result.not_in_table)}."]
    goal = ff["detection_events"] == 0 and ff["minutes"] >= 30.0
    lines += [
        "",
        f"Fault-free: {ff['drives']} drives, {ff['minutes']:.1f} simulated minutes ({', '.join(ff['scenarios'])}): "
        f"{ff['detection_events']} false detections, {ff['isolation_events']} false isolations, "
        f"{ff['alarm_steps']} steps with an alarm. Goal (0 over >= 30 min): "
        + ("met." if goal else "**NOT met**" + (" (under 30 minutes: quick mode)." if ff["minutes"] < 30 else ".")),
    ]
    pre = sum(c.pre_onset_detections for c in result.cases)
    lines.append(f"Detections before the fault onset in the fault cases: {pre}.")
    bad = [c for c in result.cases if c.outcome != "exact"]
    if bad:
        lines += ["", "Cases not isolated exactly:", "",
                  "| fault | scenario | shape | size | outcome | candidates at the end |", "|---|---|---|---|---|---|"]
        for c in bad:
            lines.append(f"| {c.fault} | {c.scenario} | {c.shape} | {c.magnitude:g} | {c.outcome} | "
                         f"{{{', '.join(c.final_candidates)}}} |")
    return "\n".join(lines) + "\n"


def write_markdown(result: SuiteResult, path: Path) -> None:
    path.write_text(markdown(result), encoding="utf-8")
