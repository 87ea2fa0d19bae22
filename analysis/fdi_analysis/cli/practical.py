"""`fdi-analyze practical MODEL --screening FILE`: the selection by practical isolability, its report and the
structural next to the practical isolability matrix; writes the selection to the thresholds file."""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from fdi_analysis.cli.common import fail
from fdi_analysis.export.thresholds import with_selection
from fdi_analysis.model_loader import load_model
from fdi_analysis.names import in_order
from fdi_analysis.plots import plot_budget_sweep, plot_practical_isolability, save
from fdi_analysis.selection.budget import BudgetSelection, budget_sweep, select_within_budget
from fdi_analysis.selection.practical import (
    PracticalSelection,
    Screening,
    Unmet,
    UnmetKind,
    practical_matrix,
    select_practical,
    structural_matrix,
)

EXAMPLE = ("example: fdi-analyze practical analysis/models/romo_grouped.toml --screening "
           "analysis/models/romo_screening.json.gz --thresholds analysis/models/romo_thresholds.toml -o out/practical")


def register(sub: Any) -> None:
    p = sub.add_parser(
        "practical",
        help="select the cheapest realizable tests that practically separate every structurally isolable fault "
        "pair and detect every fault in every manoeuvre (from fdi-tune screen's file)",
        description="Read the screening of every realizable candidate (fdi-tune screen: per fault and manoeuvre "
        "the share of operating points where the test's fault-to-noise ratio at the required fault size clears "
        "the gate with margin) and select exactly (MaxSAT over CaDiCaL when python-sat is installed, else a "
        "0-1 program with HiGHS) the cheapest set of tests that, in every manoeuvre, practically detects every "
        "fault and practically separates every pair the realizable candidates isolate structurally (one test "
        "detects one fault of the pair and is blind to the other). Requirements no candidate meets are "
        "reported with the reason. Writes the selection as the [selection] table of --thresholds (what "
        "calibrate and export-c then use) and practical.json, practical.md, practical_isolability.png to -o.",
        epilog=EXAMPLE,
    )
    p.add_argument("model", type=Path, help="model file (.toml)")
    p.add_argument("--screening", type=Path, required=True, help="the screening file of fdi-tune screen")
    p.add_argument("--thresholds", type=Path, default=None, help="thresholds file to write the selection to")
    p.add_argument("-o", "--out", type=Path, default=None, help="report folder")
    p.add_argument("--solver", choices=("auto", "rc2", "highs"), default="auto",
                   help="exact solver (default: rc2 when python-sat is installed, else highs)")
    p.add_argument("--budget", type=_non_negative, default=None, metavar="OPS",
                   help="select instead, at a summed cost (operations per step, as listed) of at most OPS, the tests "
                   "that detect the most, then separate the most (HiGHS, exact), and list the requirements of the "
                   "complete selection they give up")
    p.add_argument("--budget-sweep", type=_non_negative, default=0, metavar="N",
                   help="also select within N budgets evenly spaced up to the cost of the complete selection and "
                   "write budget_sweep.json, .md and .png to -o: requirements met against cost")
    p.set_defaults(func=run)


def _non_negative(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"{value} is negative")
    return value


def run(args: argparse.Namespace) -> int:
    model = load_model(args.model)
    faults = list(model.structure().faults)
    scr = Screening.load(args.screening)
    cands = scr.practical_candidates()
    rejected = [c for c in scr.candidates if c.rejected]
    print(f"{model.name}: {len(cands)} screened candidates ({len(rejected)} without a generator), required sizes "
          f"of {args.screening}, FNR >= {scr.gate:g} x {scr.margin:g} (more where a slow generator needs it to alarm "
          f"in time) at {scr.share:.0%} of the operating points")
    sel = select_practical(cands, faults, scr.scenarios, args.solver)
    if args.budget is not None or args.budget_sweep > 0:
        print(f"the complete selection: {len(sel.tests)} tests, cost {sel.cost}")
    if args.budget_sweep > 0:
        if args.out is None:
            return fail("fdi-analyze practical", "--budget-sweep writes budget_sweep.json, .md and .png: give -o")
        write_budget_sweep(args.out, model.name, budget_sweep(
            cands, faults, scr.scenarios, [round(sel.cost * (k + 1) / args.budget_sweep)
                                           for k in range(args.budget_sweep)], progress=_print_budget), sel.cost)
    if args.budget is not None:
        within = select_within_budget(cands, faults, scr.scenarios, args.budget)
        print(f"within the budget of {args.budget}: {len(within.tests)} tests, cost {within.cost}, they meet "
              f"{within.met} of the {within.meetable} requirements the complete selection meets (detections "
              f"{within.detections}/{within.meetable_detections}, separations "
              f"{within.separations}/{within.meetable_separations}; optimal, highs)")
        for line in given_up_lines(within):
            print(line)
        sel = PracticalSelection(within.tests, within.cost, f"highs, within a budget of {args.budget}", sel.unmet,
                                 sel.pairs, sel.scenarios)
    else:
        print(f"selected {len(sel.tests)} tests, cost {sel.cost} (optimal, {sel.solver}):")
    by_label = {c.label: c for c in scr.candidates}
    for t in sel.tests:
        c = by_label[t.label]
        print(f"  {t.label:<9} cost {t.cost:>5}  sigma {c.sigma:<8.3g} faults {' '.join(in_order(t.faults, faults))}")
    for line in unmet_lines(sel):
        print(line)
    if args.thresholds is not None:
        rows = [(by_label[t.label].equations, f"{t.label}: sigma {by_label[t.label].sigma:.3g}, cost {t.cost}, "
                 f"faults {' '.join(in_order(t.faults, faults))}") for t in sel.tests]
        provenance = (f"fdi-analyze practical {args.model.as_posix()} --screening {args.screening.as_posix()}: "
                      f"optimal ({sel.solver}), cost {sel.cost}")
        text = args.thresholds.read_text(encoding="utf-8")
        args.thresholds.write_text(with_selection(text, rows, provenance), encoding="utf-8")
        print(f"wrote the [selection] table of {args.thresholds}")
    if args.out is not None:
        write_report(args.out, model.name, faults, sel, scr)
    return 0


def _print_budget(b: BudgetSelection) -> None:
    print(f"  budget {b.budget:>6}: {len(b.tests):>2} tests, cost {b.cost:>5}, requirements met {b.met}/{b.meetable} "
          f"(detections {b.detections}/{b.meetable_detections}, separations {b.separations}/{b.meetable_separations})",
          flush=True)


def given_up_lines(within: BudgetSelection) -> list[str]:
    """The requirements of the complete selection that a selection within a budget gives up, per manoeuvre."""
    if not within.given_up:
        return []
    out = [f"{len(within.given_up)} requirements of the complete selection given up within the budget:"]
    for sc in dict.fromkeys(r.scenario for r in within.given_up):
        det = [r.fault_a for r in within.given_up if r.scenario == sc and not r.fault_b]
        pairs = [f"{r.fault_a}/{r.fault_b}" for r in within.given_up if r.scenario == sc and r.fault_b]
        out.append(f"  {sc}:" + (f" detect {', '.join(det)};" if det else "") +
                   (f" separate {_some_pairs(pairs)}" if pairs else ""))
    return out


def write_budget_sweep(out: Path, name: str, sweep: Sequence[BudgetSelection], complete_cost: int) -> None:
    """budget_sweep.json, .md and .png: per budget the best selection's tests, cost and requirements met."""
    out.mkdir(parents=True, exist_ok=True)
    doc = {"model": name, "complete_selection_cost": complete_cost,
           "budgets": [{"budget": b.budget, "cost": b.cost, "tests": [t.label for t in b.tests],
                        "detections": b.detections, "meetable_detections": b.meetable_detections,
                        "separations": b.separations, "meetable_separations": b.meetable_separations}
                       for b in sweep]}
    (out / "budget_sweep.json").write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    save(plot_budget_sweep([b.cost for b in sweep], [b.detections for b in sweep], [b.separations for b in sweep],
                           sweep[0].meetable_detections if sweep else 0, sweep[0].meetable_separations if sweep else 0,
                           complete_cost, f"{name}: requirements met within a cost budget"),
         out / "budget_sweep.png")
    lines = [f"# Selection within a cost budget: {name}", "",
             f"The complete practical selection costs {complete_cost} operations per step. Per budget, the tests "
             "that meet the most of its requirements (exact, HiGHS):", "",
             "| budget | cost | tests | detections met | separations met | all met |", "|---|---|---|---|---|---|"]
    lines += [f"| {b.budget} | {b.cost} | {len(b.tests)} | {b.detections}/{b.meetable_detections} | "
              f"{b.separations}/{b.meetable_separations} | {b.met / b.meetable:.1%} |" if b.meetable else
              f"| {b.budget} | {b.cost} | {len(b.tests)} | 0/0 | 0/0 | - |" for b in sweep]
    lines += ["", "![requirements met within a cost budget](budget_sweep.png)", ""]
    (out / "budget_sweep.md").write_text("\n".join(lines), encoding="utf-8")
    print(f"wrote {out / 'budget_sweep.json'}, budget_sweep.md, budget_sweep.png")


def unmet_lines(sel: PracticalSelection) -> list[str]:
    """The requirements no realizable test meets, grouped by manoeuvre and kind (detections first, then pairs,
    each with the closest test by detecting share and, for the weak ones, the strongest median fault-to-noise ratio
    against the one that test needs)."""
    if not sel.unmet:
        return ["every requirement is met in every manoeuvre"]
    out = [f"{len(sel.unmet)} requirements no realizable test meets:"]
    for sc in sel.scenarios:
        for kind in UnmetKind:
            items = [u for u in sel.unmet if u.scenario == sc and u.kind is kind]
            if not items:
                continue
            det = [u for u in items if not u.fault_b]
            pairs = [u for u in items if u.fault_b]
            out.append(f"  {sc}, {kind.value}:")
            if det:
                out.append(f"    detect {', '.join(_unmet_item(u) for u in det)}")
            if pairs:
                out.append(f"    separate {_some_pairs([_unmet_item(u) for u in pairs])}")
    return out


def _some_pairs(items: Sequence[str], shown: int = 12) -> str:
    """The first `shown` items, and how many more there are."""
    more = f" and {len(items) - shown} more pairs" if len(items) > shown else ""
    return ", ".join(items[:shown]) + more


def _unmet_item(u: Unmet) -> str:
    what = f"{u.fault_a}/{u.fault_b}" if u.fault_b else u.fault_a
    if u.kind is UnmetKind.WEAK and u.needed_fnr > 0.0:
        ratio = f"FNR {u.strongest_fnr:.2g}/{u.needed_fnr:.2g} {u.strongest_test}"
        return f"{what} ({u.best_test} {u.best_share:.0%}; {ratio})"
    if u.kind is UnmetKind.WEAK:
        return f"{what} ({u.best_test} {u.best_share:.0%})"
    return what


def write_report(out: Path, name: str, faults: Sequence[str], sel: PracticalSelection, scr: Screening) -> None:
    out.mkdir(parents=True, exist_ok=True)
    prac = practical_matrix(sel.tests, faults, sel.scenarios)
    struct = structural_matrix(sel.tests, faults)
    doc = {
        "model": name,
        "solver": sel.solver,
        "cost": sel.cost,
        "criterion": {"gate": scr.gate, "margin": scr.margin, "share": scr.share, "sizes": scr.sizes},
        "scenarios": list(sel.scenarios),
        "tests": [{"label": t.label, "cost": t.cost, "faults": in_order(t.faults, faults),
                   "detects": sorted(f"{f}@{s}" for f, s in t.detects)} for t in sel.tests],
        "unmet": [{"scenario": u.scenario, "faults": [u.fault_a, *([u.fault_b] if u.fault_b else [])],
                   "kind": u.kind.name, "tests": u.tests, "closest_test": u.best_test, "closest_share": u.best_share,
                   "strongest_test": u.strongest_test, "strongest_median_fnr": u.strongest_fnr,
                   "needed_fnr": u.needed_fnr, "reason": u.reason} for u in sel.unmet],
        "structurally_isolable_pairs": len(sel.pairs),
        "pairs": {f"{a}/{b}": {"structural": struct[(a, b)], "practical_scenarios": prac[(a, b)]}
                  for a, b in sel.pairs},
    }
    (out / "practical.json").write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    fig = plot_practical_isolability(faults, struct, prac, len(sel.scenarios),
                                     f"{name}: isolability of the practical selection ({len(sel.tests)} tests)")
    save(fig, out / "practical_isolability.png")
    lines = [f"# Practical selection: {name}", "",
             f"{len(sel.tests)} tests, cost {sel.cost}, optimal ({sel.solver}); criterion: fault-to-noise ratio at "
             f"the required size >= {scr.gate:g} x {scr.margin:g} at {scr.share:.0%} of a manoeuvre's operating "
             "points.", "", "| test | cost | faults |", "|---|---|---|"]
    lines += [f"| {t.label} | {t.cost} | {', '.join(in_order(t.faults, faults))} |" for t in sel.tests]
    lines += ["", "## Requirements no realizable test meets", "", *unmet_lines(sel), "",
              "![structural and practical isolability](practical_isolability.png)", ""]
    (out / "practical.md").write_text("\n".join(lines), encoding="utf-8")
    print(f"wrote {out / 'practical.json'}, practical.md, practical_isolability.png")
