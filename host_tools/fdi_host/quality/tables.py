"""The quality suite's tables (`fdi_host.quality.suite.SuiteResult`) as pandas DataFrames labelled by fault and
scenario, for a notebook: the per-fault summary of the report, every case, the fault-free drives and the goals per
scenario. pandas is optional (``pip install 'romo-fdi[notebook]'``)."""

from __future__ import annotations

import dataclasses
from typing import Any

from fdi_analysis.tables import require_pandas
from fdi_host.quality.suite import SuiteResult, scenario_goals, summary_rows

CASE_KEYS = ("fault", "scenario", "seed", "shape", "multiplier")  # what tells one case from another


def _text(row: dict[str, object]) -> dict[str, object]:
    """Lists of fault names as text ("f10, f14"): a table cell holds one value."""
    return {k: ", ".join(map(str, v)) if isinstance(v, list | tuple) else v for k, v in row.items()}


def summary_frame(result: SuiteResult) -> Any:
    """One row per fault (the index, in the suite's order): its size, cases, detections, delays and isolation
    outcomes (`summary_rows`, the report's table; the expected class as text)."""
    pd = require_pandas()
    rows = [_text(r) for r in summary_rows(result)]
    columns = list(rows[0]) if rows else ["fault"]
    return pd.DataFrame(rows, columns=columns).set_index("fault")


def cases_frame(result: SuiteResult) -> Any:
    """Every fault case as a row, indexed by (fault, scenario, seed, shape, multiplier); the candidates and the
    expected class as text (fault names joined by ", ")."""
    pd = require_pandas()
    fields = [f.name for f in dataclasses.fields(type(result.cases[0]))] if result.cases else list(CASE_KEYS)
    rows = []
    for c in result.cases:
        row = _text(dataclasses.asdict(c))
        row["detected_in_time"] = c.detected_in_time
        row["isolated_in_time"] = c.isolated_in_time
        rows.append(row)
    columns = [*fields, "detected_in_time", "isolated_in_time"] if result.cases else fields
    return pd.DataFrame(rows, columns=columns).set_index(list(CASE_KEYS))


def fault_free_frame(result: SuiteResult) -> Any:
    """Every fault-free drive as a row, indexed by (scenario, seed): duration, detection and isolation events."""
    pd = require_pandas()
    rows = [dataclasses.asdict(d) for d in result.fault_free]
    columns = list(rows[0]) if rows else ["scenario", "seed"]
    return pd.DataFrame(rows, columns=columns).set_index(["scenario", "seed"])


def goals_frame(result: SuiteResult) -> Any:
    """The goals per scenario (the index): faults detected and isolated in time, those not, wrong classes (fault
    names joined by ", "), and whether each goal holds."""
    pd = require_pandas()
    rows = [_text(g) for g in scenario_goals(result)]
    columns = list(rows[0]) if rows else ["scenario"]
    return pd.DataFrame(rows, columns=columns).set_index("scenario")
