"""The on-line rule's linearisation over many cases: where do the tests' departures from s F exceed its margin?

A quiet test q clears fault j when |s_qj| F reaches sensitivity_margin (m) gates, at the size F that an alarmed
test a implies, (|r_a| - allowance) / |s_aj|. With the settled responses rho_a s_aj F and rho_q s_qj F of a fault
of size F (linearity.py), the implied size is at most rho_a F, and q stays quiet only while rho_q |s_qj| F is below
its gate; so q can clear the true fault only where rho_a / rho_q > m at the same step. The survey measures, per case
(fault x scenario x seed of the suite), every test's rho where the rule may use its s F (from gate sigma / m on)
and, per step, the spread max rho / min rho over the tests that count there (infinite where a test responds against
its prediction). A spread above m is where the margin does not cover the linearisation: had the test of the larger
rho alarmed while the other stayed quiet, the single-test clearing could have cleared the true fault. Whether the
rule did (its alarm memory, noise allowance, confirmation and the latch of the first class isolated come on top) is
the quality suite's count of wrong classes; the survey says where the margin alone does not hold.

`fdi-quality --vehicle romo --linearity [--seeds ...] [--out DIR]` (without --trace) runs it.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from fdi_host.ecu.bindings import table_info
from fdi_host.quality.linearity import SETTLE_S, FloatArray, Linearity, TestResponse, check_case
from fdi_host.quality.suite import QualityError, SuiteConfig, fault_cases, load_fault_sizes
from fdi_host.sim.faults import FAULT_IDS


@dataclass(frozen=True)
class RhoSummary:
    """One test's rho for one fault over the counted steps of one case or of all cases (pooled)."""

    test: str
    fault: str
    steps: int
    p5: float
    median: float
    p95: float
    within: float  # share of the steps with 1 / m <= rho <= m


@dataclass(frozen=True)
class CaseSpread:
    """The largest ratio between two tests' rho at the same step of one case."""

    fault: str
    scenario: str
    seed: int
    tests: tuple[RhoSummary, ...]  # the tests with counted steps
    shared_steps: int  # steps at which at least two tests count
    spread: float  # max over those steps of max rho / min rho (inf: a test responds against s F); nan: no such step
    at_s: float  # time after the onset of that step (nan without one)
    between: tuple[str, str]  # the tests of the largest and the smallest rho there
    over_margin: float  # share of the shared steps whose spread exceeds the margin


@dataclass(frozen=True)
class Survey:
    table: str
    margin: float
    seeds: tuple[int, ...]
    scenarios: tuple[str, ...]
    cases: tuple[CaseSpread, ...]
    pooled: tuple[RhoSummary, ...]  # per (test, fault), every case pooled, in table and fault order


def summarise(test: str, fault: str, rho: FloatArray, margin: float) -> RhoSummary:
    """Quantiles of rho and the share within [1 / margin, margin] (NaN quantiles without steps)."""
    if rho.size == 0:
        return RhoSummary(test, fault, 0, math.nan, math.nan, math.nan, math.nan)
    p5, med, p95 = (float(x) for x in np.percentile(rho, [5.0, 50.0, 95.0]))
    inside = (rho >= 1.0 / margin) & (rho <= margin)
    return RhoSummary(test, fault, int(rho.size), p5, med, p95, float(np.mean(inside)))


def step_spread(tests: Sequence[TestResponse]) -> tuple[FloatArray, NDArray[np.intp], NDArray[np.intp], FloatArray]:
    """Per step with at least two counted tests: max rho / min rho over them (inf where the smallest rho is not
    positive), the indices (into `tests`) of the largest and the smallest rho, and the step's time."""
    if not tests:
        empty = np.zeros(0)
        return empty, np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp), empty
    t = tests[0].t
    for tr in tests:
        if tr.t.shape != t.shape or not np.array_equal(tr.t, t):
            raise QualityError("the tests of one case must share their steps")
    with np.errstate(divide="ignore", invalid="ignore"):
        rho = np.vstack([np.where(tr.counted(), tr.response / tr.predicted, np.nan) for tr in tests])
    shared = np.sum(~np.isnan(rho), axis=0) >= 2
    rho = rho[:, shared]
    hi = np.nanargmax(rho, axis=0) if rho.shape[1] else np.zeros(0, dtype=np.intp)
    lo = np.nanargmin(rho, axis=0) if rho.shape[1] else np.zeros(0, dtype=np.intp)
    cols = np.arange(rho.shape[1])
    top, bottom = rho[hi, cols], rho[lo, cols]
    with np.errstate(divide="ignore"):
        spread = np.where(bottom > 0.0, top / np.where(bottom > 0.0, bottom, 1.0), np.inf)
    return spread, hi, lo, t[shared]


def case_spread(lin: Linearity, margin: float) -> CaseSpread:
    """Per-test rho and the largest spread of one checked case."""
    fault = lin.spec.fault
    counted = [tr for tr in lin.tests if np.any(tr.counted())]
    summaries = tuple(summarise(tr.name, fault, tr.ratios(), margin) for tr in counted)
    spread, hi, lo, t = step_spread(counted)
    if spread.size == 0:
        return CaseSpread(fault, lin.scenario, lin.seed, summaries, 0, math.nan, math.nan, ("", ""), math.nan)
    k = int(np.argmax(spread))
    return CaseSpread(fault, lin.scenario, lin.seed, summaries, int(spread.size), float(spread[k]), float(t[k]),
                      (counted[int(hi[k])].name, counted[int(lo[k])].name), float(np.mean(spread > margin)))


def run_survey(cfg: SuiteConfig, progress: Callable[[str], None] | None = None) -> Survey:
    """Every fault x scenario x seed of `cfg` (its first shape and multiplier), checked and summarised."""
    info = table_info(cfg.table)
    margin = info.sensitivity_margin
    sizes = load_fault_sizes(cfg.sizes_file)
    faults, _ = fault_cases(cfg, info, sizes)
    shape, mult = cfg.shapes[0], cfg.multipliers[0]
    cases: list[CaseSpread] = []
    pooled: dict[tuple[str, str], list[FloatArray]] = {}
    for fault in faults:
        for scenario in cfg.scenarios:
            for seed in cfg.seeds:
                lin = check_case(cfg.table, fault, scenario, seed, mult, cfg, shape)
                case = case_spread(lin, margin)
                cases.append(case)
                for tr in lin.tests:
                    pooled.setdefault((tr.name, fault), []).append(tr.ratios())
                if progress is not None:
                    worst = "-" if math.isnan(case.spread) else f"{case.spread:.2f}"
                    progress(f"{fault} {scenario} {seed}: spread {worst}")
    order = {name.split(":")[0]: i for i, name in enumerate(info.test_names)}
    keys = sorted(pooled, key=lambda k: (order.get(k[0], len(order)), faults.index(k[1])))
    summaries = tuple(summarise(test, fault, np.concatenate(pooled[(test, fault)]), margin) for test, fault in keys)
    return Survey(cfg.table, margin, tuple(cfg.seeds), tuple(cfg.scenarios), tuple(cases), summaries)


def _num(x: float, digits: int = 2) -> str:
    if math.isnan(x):
        return "-"
    return "inf" if math.isinf(x) else f"{x:.{digits}f}"


def markdown(s: Survey) -> str:
    m = s.margin
    spreads = [c for c in s.cases if not math.isnan(c.spread)]
    over = sorted((c for c in spreads if c.spread > m), key=lambda c: -c.spread)
    lines = [
        f"Linearisation of the on-line rule, table {s.table}: rho = settled response / (s F) per test (from "
        f"{SETTLE_S:g} s after the onset, where s F stands out of the fault-free residual and reaches gate x sigma / "
        f"m), scenarios {', '.join(s.scenarios)}, seeds {', '.join(str(x) for x in s.seeds)}; sensitivity margin "
        f"m = {m:g}.",
        "",
        f"{len(s.cases)} cases, {len(spreads)} with at least two tests counting at the same step; in {len(over)} of "
        f"them the tests' rho differ there by more than m (largest rho / smallest rho > {m:g}): had the test of the "
        f"larger rho alarmed while the other stayed quiet, a quiet test could have cleared the true fault.",
        "",
        "| fault | scenario | seed | largest spread | at [s] | between (largest / smallest rho) | steps over m |",
        "|---|---|---|---|---|---|---|",
    ]
    lines += [f"| {c.fault} | {c.scenario} | {c.seed} | {_num(c.spread)} | {_num(c.at_s)} | {c.between[0]} / "
              f"{c.between[1]} | {_share(c.over_margin)} |" for c in over]
    if not over:
        lines.append("| - | - | - | - | - | - | - |")
    lines += [
        "",
        "Per test and fault, every case pooled (the pairs with counted steps):",
        "",
        "| test | fault | steps | rho p5 / median / p95 | within [1/m, m] |",
        "|---|---|---|---|---|",
    ]
    lines += [f"| {r.test} | {r.fault} | {r.steps} | {_num(r.p5)} / {_num(r.median)} / {_num(r.p95)} | "
              f"{_share(r.within)} |" for r in s.pooled if r.steps > 0]
    return "\n".join(lines)


def _share(x: float) -> str:
    return "-" if math.isnan(x) else f"{100.0 * x:.0f} %"


def _json_safe(obj: object) -> object:
    """NaN (no value) as null, an infinite spread as "inf": strict JSON."""
    if isinstance(obj, float) and not math.isfinite(obj):
        return None if math.isnan(obj) else "inf"
    if isinstance(obj, dict):
        return {k: _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_json_safe(v) for v in obj]
    return obj


def write_json(s: Survey, path: Path) -> None:
    path.write_text(json.dumps(_json_safe(asdict(s)), indent=1, allow_nan=False) + "\n", encoding="utf-8")


def write_markdown(s: Survey, path: Path) -> None:
    path.write_text(markdown(s) + "\n", encoding="utf-8")


def plot(s: Survey, path: Path) -> None:
    """Per fault (in Table I order), each test's rho (p5 to p95, median marked), every case pooled; the band is
    [1/m, m]; symmetric log scale, so that a test responding against s F (rho < 0) shows below zero."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    faults = sorted({r.fault for r in s.pooled if r.steps > 0}, key=FAULT_IDS.index)
    fig, ax = plt.subplots(figsize=(max(8.0, 0.55 * len(faults) + 2.0), 4.6))
    ax.axhspan(1.0 / s.margin, s.margin, color="0.9", lw=0, label=f"[1/m, m], m = {s.margin:g}")
    ax.axhline(1.0, color="0.6", lw=0.8)
    ax.axhline(0.0, color="0.3", lw=0.8)
    for x, fault in enumerate(faults):
        rows = [r for r in s.pooled if r.fault == fault and r.steps > 0]
        width = min(0.8 / len(rows), 0.15)
        for k, r in enumerate(rows):
            xi = x + (k - (len(rows) - 1) / 2.0) * width
            ax.plot([xi, xi], [r.p5, r.p95], color="C0", lw=2.0)
            ax.plot([xi], [r.median], "o", color="C1", ms=3)
    ax.set_yscale("symlog", linthresh=0.1)
    ax.set_xticks(range(len(faults)), faults, fontsize=8)
    ax.set_ylabel("rho = response / (s F)")
    ax.set_title(f"table {s.table}: each test's rho per fault (bar p5-p95, dot median; scenarios "
                 f"{', '.join(s.scenarios)}; seeds {', '.join(str(x) for x in s.seeds)})", fontsize=9)
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
