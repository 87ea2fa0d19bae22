"""Reports of the diagnosis quality suite: JSON (every case and fault-free drive) and a Markdown table."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

from fdi_host.quality.suite import (
    DELAY_GOAL_S,
    DETECTION_GOAL_FAULTS,
    ISOLATION_GOAL_FAULTS,
    ISOLATION_GOAL_S,
    SuiteResult,
    scenario_goals,
    summary_rows,
)


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
        "isolation_goal_s": ISOLATION_GOAL_S,
        "sizes": result.sizes,
        "not_in_table": result.not_in_table,
        "goals": scenario_goals(result),
        "summary": summary_rows(result),
        "fault_free": fault_free_totals(result),
        "cases": [dataclasses.asdict(c) for c in result.cases],
        "fault_free_drives": [dataclasses.asdict(d) for d in result.fault_free],
    }


def write_json(result: SuiteResult, path: Path) -> None:
    path.write_text(json.dumps(to_dict(result), indent=1) + "\n", encoding="utf-8")


def _yes(v: object) -> str:
    return "yes" if v else "**NO**"


def markdown(result: SuiteResult) -> str:
    cfg = result.config
    ff = fault_free_totals(result)
    n_f = len({c.fault for c in result.cases})
    lines = [
        f"## Diagnosis quality, table `{result.table.name}`",
        "",
        f"Scenarios {', '.join(cfg.scenarios)}; noise seeds {', '.join(map(str, cfg.seeds))} (no calibration "
        f"used them); {', '.join(cfg.shapes)} faults at x{', x'.join(f'{m:g}' for m in cfg.multipliers)} the "
        f"required size (`{cfg.sizes_file.name}` [requirement]). A fault meets a goal in a scenario when every "
        f"case there does: detected within {1000 * DELAY_GOAL_S:.0f} ms of the onset; isolated to exactly its "
        f"structural class (method B over the tests on board) within {ISOLATION_GOAL_S:g} s of the detection; "
        "never a wrong class.",
        *(["", f"ECU settings other than the defaults: {', '.join(f'{k} = {v}' for k, v in cfg.ecu)}.", ""]
          if cfg.ecu else [""]),
        f"| scenario | detected in time (goal >= {DETECTION_GOAL_FAULTS}) | isolated in time "
        f"(goal >= {ISOLATION_GOAL_FAULTS}) | wrong class | faults not detected in time | faults not isolated "
        "in time |",
        "|---|---|---|---|---|---|",
    ]
    for g in scenario_goals(result):
        miss_d = g["not_detected_in_time"]
        miss_i = g["not_isolated_in_time"]
        assert isinstance(miss_d, list) and isinstance(miss_i, list) and isinstance(g["wrong_class"], list)
        lines.append(
            f"| {g['scenario']} | {g['detected_in_time']}/{n_f} {_yes(g['goal_detection'])} | "
            f"{g['isolated_in_time']}/{n_f} {_yes(g['goal_isolation'])} | "
            f"{', '.join(g['wrong_class']) or 'none'} | {', '.join(miss_d) or '-'} | {', '.join(miss_i) or '-'} |")
    lines += [
        "",
        "| fault | size | detected | within 300 ms | delay median / max [ms] | structural class | exact | "
        "within 1 s | isolation delay median / max [ms] | wrong | not isolated | missed | exact share |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in summary_rows(result):
        lines.append(
            f"| {r['fault']} | {r['size']:g} | {r['detected']}/{r['cases']} | {r['detected_in_time']} | "
            f"{_ms(r['delay_median_s'])} / {_ms(r['delay_max_s'])} | "
            f"{{{', '.join(r['expected_class'])}}} | {r['isolation_exact']} | "  # type: ignore[arg-type]
            f"{r['isolated_in_time']} | {_ms(r['isolation_delay_median_s'])} / {_ms(r['isolation_delay_max_s'])} | "
            f"{r['isolation_wrong']} | {r['isolation_not_isolated']} | {r['isolation_missed']} | "
            f"{100 * _num(r['exact_share_mean']):.0f} % |"
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
        + ("met." if goal else "**NOT met**" + (" (under 30 minutes driven)." if ff["minutes"] < 30 else ".")),
    ]
    pre = sum(c.pre_onset_detections for c in result.cases)
    lines.append(f"Detections before the fault onset in the fault cases: {pre}.")
    bad = [c for c in result.cases if not c.isolated_in_time]
    if bad:
        lines += ["", "Cases not isolated exactly within the goal:", "",
                  "| fault | scenario | seed | outcome | delay [ms] | isolation delay [ms] | candidates at the end |",
                  "|---|---|---|---|---|---|---|"]
        for c in bad:
            lines.append(f"| {c.fault} | {c.scenario} | {c.seed} | {c.outcome} | {_ms(c.delay_s)} | "
                         f"{_ms(c.isolation_delay_s)} | {{{', '.join(c.final_candidates)}}} |")
    return "\n".join(lines) + "\n"


def write_markdown(result: SuiteResult, path: Path) -> None:
    path.write_text(markdown(result), encoding="utf-8")
