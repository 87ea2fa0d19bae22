"""`fdi-analyze practical MODEL --screening FILE`: the selection by practical isolability, its report and the
structural next to the practical isolability matrix; writes the selection to the thresholds file."""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from fdi_analysis.export.thresholds import with_selection
from fdi_analysis.model_loader import load_model
from fdi_analysis.plots import plot_practical_isolability, save
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
           "analysis/models/romo_screening.json --thresholds analysis/models/romo_thresholds.toml -o out/practical")


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
    p.set_defaults(func=run)


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
    print(f"selected {len(sel.tests)} tests, cost {sel.cost} (optimal, {sel.solver}):")
    by_label = {c.label: c for c in scr.candidates}
    for t in sel.tests:
        c = by_label[t.label]
        print(f"  {t.label:<9} cost {t.cost:>5}  sigma {c.sigma:<8.3g} faults {' '.join(sorted(t.faults, key=_num))}")
    for line in unmet_lines(sel):
        print(line)
    if args.thresholds is not None:
        rows = [(by_label[t.label].equations, f"{t.label}: sigma {by_label[t.label].sigma:.3g}, cost {t.cost}, "
                 f"faults {' '.join(sorted(t.faults, key=_num))}") for t in sel.tests]
        provenance = (f"fdi-analyze practical {args.model.as_posix()} --screening {args.screening.as_posix()}: "
                      f"optimal ({sel.solver}), cost {sel.cost}")
        text = args.thresholds.read_text(encoding="utf-8")
        args.thresholds.write_text(with_selection(text, rows, provenance), encoding="utf-8")
        print(f"wrote the [selection] table of {args.thresholds}")
    if args.out is not None:
        write_report(args.out, model.name, faults, sel, scr)
    return 0


def _num(f: str) -> int:
    return int(f[1:]) if f[1:].isdigit() else 0


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
                shown = ", ".join(_unmet_item(u) for u in pairs[:12])
                out.append(f"    separate {shown}{f' and {len(pairs) - 12} more pairs' if len(pairs) > 12 else ''}")
    return out


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
        "tests": [{"label": t.label, "cost": t.cost, "faults": sorted(t.faults, key=_num),
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
    lines += [f"| {t.label} | {t.cost} | {', '.join(sorted(t.faults, key=_num))} |" for t in sel.tests]
    lines += ["", "## Requirements no realizable test meets", "", *unmet_lines(sel), "",
              "![structural and practical isolability](practical_isolability.png)", ""]
    (out / "practical.md").write_text("\n".join(lines), encoding="utf-8")
    print(f"wrote {out / 'practical.json'}, practical.md, practical_isolability.png")
