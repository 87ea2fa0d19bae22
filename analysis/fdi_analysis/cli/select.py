"""`fdi-analyze select MODEL`: fault matrices and the minimal MSO selections (greedy and optimal, A and B)."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from fdi_analysis.fault_matrix import Method, fault_matrix, signature_matrix
from fdi_analysis.interpretation import interpret
from fdi_analysis.model import Model
from fdi_analysis.model_loader import load_model
from fdi_analysis.mso import bits
from fdi_analysis.plots import plot_fault_matrix, plot_selected_faults, save
from fdi_analysis.residuals.reasons import Reason
from fdi_analysis.selection import Selection, greedy, optimal
from fdi_analysis.selection.candidates import full_isolability_reached, mso_candidates, mtes_candidates

EXAMPLE = (
    "examples:\n  fdi-analyze select analysis/models/romo_grouped.toml -o out/grouped\n"
    "  fdi-analyze select analysis/models/romo_full_vertical.toml --candidates mtes -o out/full_vertical"
)


def register(sub: Any) -> None:
    p = sub.add_parser(
        "select",
        help="fault matrices (methods A/B) and minimal MSO selections: greedy (paper) and optimal (exact)",
        description="Enumerate the MSO sets of MODEL, build the fault matrices of both evaluation methods, and "
        "select minimal sets of MSOs with maximal isolability: the paper's greedy method and an exact optimum "
        "(fewest tests, then fewest unknowns). Writes selection.json, selection.md and the plots "
        "fault_matrix.png (Fig. 4) and selected_faults.png (Fig. 5).",
        epilog=EXAMPLE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("model", type=Path, help="model file (.toml) or FDT structure (.json)")
    p.add_argument("-o", "--out", type=Path, default=None, help="output folder (default: print only)")
    p.add_argument("--candidates", choices=("mso", "mtes"), default="mso",
                   help="candidate tests: every MSO set (enumerated, one per fault signature; default) or the "
                   "MTES (minimal test equation supports) for models too large to enumerate, e.g. the full "
                   "vertical-dynamics model")
    p.add_argument("--realizable", action="store_true",
                   help="keep only candidates that have a sequential residual generator (derivative causality, "
                   "no open-loop integration, solvable equations): the tests `export-c` can put on board")
    p.add_argument("--time-limit", type=float, default=60.0,
                   help="seconds per optimal selection before the best found is reported unproven (default 60)")
    p.add_argument("--workers", type=int, default=2, help="worker processes of the MSO search (default 2)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def selection_rows(model: Model, sel: Selection) -> list[dict[str, Any]]:
    st = model.structure()
    return [
        {
            "mso": t.label,
            "unknowns": t.cost,
            "equations": [st.equations[e] for e in bits(t.equations)],
            "faults": [st.faults[k] for k in bits(t.faults)],
            "interpretation": interpret(model, [st.equations[e] for e in bits(t.equations)]),
        }
        for t in sel.tests
    ]


def rejection_summary(reasons: dict[Reason, int]) -> str:
    """Counts of the rejection reasons by kind, largest first."""
    return ", ".join(f"{n:,} {kind.value}" for kind, n in sorted(reasons.items(), key=lambda kv: (-kv[1], kv[0].name)))


def isolability_loss(kept: list[Any], everything: list[Any], faults: tuple[str, ...], method: Method) -> str:
    """Which fault-matrix elements the kept candidates lose against all candidates (method A or B)."""
    nf = len(faults)
    full = fault_matrix([t.faults for t in everything], nf, method)
    reached = fault_matrix([t.faults for t in kept], nf, method)
    lost = np.argwhere(reached & ~full)  # element set = "cannot be told apart"
    if lost.size == 0:
        return "the realizable candidates reach the fault matrix of all candidates"
    names = ("no fault", *faults)
    pairs = ", ".join(f"{names[i]}/{names[j]}" for i, j in lost[:12])
    more = f" and {len(lost) - 12} more" if len(lost) > 12 else ""
    return f"{len(lost)} fault-matrix elements lost against all candidates: {pairs}{more}"


def optimality(sel: Selection) -> str:
    if sel.kind != "optimal":
        return "-"
    if sel.proven:
        return "count and cost proven"
    if sel.lower_bound == len(sel.tests):
        return "count proven, cost not proven (time limit)"
    return f"not proven: count >= {sel.lower_bound} (time limit)"


def run(args: argparse.Namespace) -> int:
    model = load_model(args.model)
    st = model.structure()
    if args.candidates == "mso":
        summary, cands = mso_candidates(st, workers=args.workers, progress=not args.no_progress)
        n_sets, kind = summary.count, "MSO sets"
        print(f"{model.name}: {summary.count:,} MSO sets, {len(cands):,} distinct fault signatures "
              f"({summary.elapsed_s:.2f} s)")
    else:
        if not args.no_progress:
            print(f"{model.name}: MTES search ...", flush=True)
        result, cands = mtes_candidates(st)
        n_sets, kind = len(result.mtes), "MTES"
        reached = "reach" if full_isolability_reached(st, cands) else "do NOT reach"
        print(f"{model.name}: {len(result.mtes):,} MTES, {len(cands):,} distinct fault supports "
              f"({result.elapsed_s:.2f} s); they {reached} the structural isolability of the model")
    if args.realizable:
        from fdi_analysis.residuals.realizability import realizable_candidates

        all_cands = cands
        observed: list[Any] = []
        cands, reasons = realizable_candidates(model, cands, with_observer=observed)
        print(f"realizable: {len(cands):,} of {len(all_cands):,} candidates ({len(observed):,} with one state "
              f"estimated by an observer); rejected: {rejection_summary(reasons)}")
        if not cands:
            print("no realizable candidate: nothing to select")
            return 1
        for method in ("A", "B"):
            print(f"  method {method}: " + isolability_loss(cands, all_cands, st.faults, method))
    selections: dict[str, Selection] = {}
    timing: dict[str, float] = {}
    methods: tuple[Method, ...] = ("A", "B")
    for method in methods:
        for how in ("greedy", "optimal"):
            t0 = time.perf_counter()
            sel = greedy(cands, st.nf, method) if how == "greedy" else optimal(cands, st.nf, method, args.time_limit)
            selections[f"{how} {method}"] = sel
            timing[f"{how} {method}"] = time.perf_counter() - t0
    print("selection     tests  unknowns    time  optimality")
    for key, sel in selections.items():
        print(f"{key:<12} {len(sel.tests):>6} {sel.total_cost:>9} {timing[key]:>6.2f} s  {optimality(sel)}")
    best = selections["optimal B"]
    print("optimal selection, method B:")
    for row in selection_rows(model, best):
        faults = " ".join(row["faults"])
        print(f"  {row['mso']:<9} {row['unknowns']:>3} unknowns  faults {faults}")
    if args.out is not None:
        write_outputs(args.out, model, n_sets, kind, cands, selections, timing)
    return 0


def write_outputs(out: Path, model: Model, n_sets: int, kind: str, cands: list[Any],
                  selections: dict[str, Selection], timing: dict[str, float]) -> None:
    st = model.structure()
    out.mkdir(parents=True, exist_ok=True)
    all_sets = [t.faults for t in cands]
    save(plot_fault_matrix(fault_matrix(all_sets, st.nf, "A"), fault_matrix(all_sets, st.nf, "B"), st.faults,
                           f"{model.name}: fault matrix of all {n_sets:,} {kind}"), out / "fault_matrix.png")
    best = selections["optimal B"]
    save(plot_selected_faults(signature_matrix(best.tests, st.nf), st.faults,
                              [f"{k + 1}: {t.label}" for k, t in enumerate(best.tests)],
                              f"{model.name}: faults affecting each selected MSO set (optimal, method B)"),
         out / "selected_faults.png")
    data = {
        "model": model.name,
        "candidate_source": kind,
        "candidate_sets": n_sets,
        "distinct_fault_signatures": len(cands),
        "selections": {
            key: {"tests": len(sel.tests), "unknowns": sel.total_cost, "seconds": round(timing[key], 3),
                  "optimality": optimality(sel), "msos": selection_rows(model, sel)}
            for key, sel in selections.items()
        },
    }
    (out / "selection.json").write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    lines = [f"# MSO selection: {model.name}", "",
             f"{n_sets:,} {kind}, {len(cands):,} distinct fault signatures.", "",
             "| selection | tests | unknowns in total | optimality |", "|---|---|---|---|"]
    lines += [f"| {k} | {len(s.tests)} | {s.total_cost} | {optimality(s)} |" for k, s in selections.items()]
    for key, sel in selections.items():
        lines += ["", f"## {key}", "", "| # | MSO | unknowns | faults | interpretation |", "|---|---|---|---|---|"]
        lines += [f"| {i + 1} | {r['mso']} | {r['unknowns']} | {', '.join(r['faults'])} | "
                  f"{r['interpretation']} |" for i, r in enumerate(selection_rows(model, sel))]
    lines += ["", "![fault matrix, method A (x) and B (squares)](fault_matrix.png)", "",
              "![faults per selected MSO](selected_faults.png)", ""]
    (out / "selection.md").write_text("\n".join(lines), encoding="utf-8")
    print(f"wrote {out / 'selection.json'}, {out / 'selection.md'}, fault_matrix.png, selected_faults.png")
