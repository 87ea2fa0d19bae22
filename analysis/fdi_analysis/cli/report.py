"""`fdi-analyze report MODEL`: structural summary on the terminal, JSON + Markdown report and plots."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from fdi_analysis.model_loader import load_model
from fdi_analysis.plots import plot_dm, plot_isolability, save
from fdi_analysis.report import write_json, write_markdown
from fdi_analysis.summary import Summary, summarize

EXAMPLE = "example: fdi-analyze report analysis/models/romo_quasistatic.toml -o out/romo"


def register(sub: Any) -> None:
    p = sub.add_parser(
        "report",
        help="summary, DM decomposition, detectability and isolability; JSON + Markdown report",
        description="Print the structural summary of MODEL and write report.json, report.md and plots.",
        epilog=EXAMPLE,
    )
    p.add_argument("model", type=Path, help="model file (.toml) or FDT structure (.json)")
    p.add_argument("-o", "--out", type=Path, default=None,
                   help="output folder for report.json, report.md and PNG plots (default: print only)")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    p.set_defaults(func=run)


def print_summary(s: Summary) -> None:
    c = s.model.counts()
    st = s.structure
    iso = s.isolability
    print(f"model {s.model.name}: {c['equations']} equations ({c['normal_equations']} normal, "
          f"{c['measurement_equations']} measurement, {c['differential_constraints']} differential), "
          f"{c['unknowns']} unknowns, {c['knowns']} knowns, {c['faults']} faults")
    print(f"structural redundancy {s.redundancy}; M+ {len(s.dm.plus_eqs)} eq / {len(s.dm.plus_vars)} var, "
          f"M0 {len(s.dm.zero_eqs)} eq, M- {len(s.dm.minus_eqs)} eq; "
          f"{len(s.equivalence_classes)} equivalence classes")
    nd = [f for f, d in zip(st.faults, iso.detectable, strict=True) if not d]
    print(f"detectable faults: {int(iso.detectable.sum())}/{st.nf}" + (f" (not: {', '.join(nd)})" if nd else ""))
    print(f"isolability classes: {len(iso.classes)}")
    for cl in iso.classes:
        if len(cl) > 1:
            print("  not isolable from each other: " + ", ".join(st.faults[i] for i in cl))
    one_way = iso.one_way_pairs()
    print(f"isolable one way only (a -> b: a cannot be isolated from b, b can be from a): {len(one_way)} pairs"
          + (": " + ", ".join(f"{st.faults[i]} -> {st.faults[j]}" for i, j in one_way) if one_way else ""))


def run(args: argparse.Namespace) -> int:
    model = load_model(args.model)
    s = summarize(model)
    print_summary(s)
    if args.out is not None:
        out: Path = args.out
        out.mkdir(parents=True, exist_ok=True)
        plots: dict[str, str] = {}
        if not args.no_plots:
            save(plot_dm(s), out / "dm.png")
            save(plot_isolability(s), out / "isolability.png")
            plots = {"DM decomposition": "dm.png", "Single-fault isolability": "isolability.png"}
        write_json(s, out / "report.json")
        write_markdown(s, out / "report.md", plots)
        print(f"wrote {out / 'report.json'}, {out / 'report.md'}" + (" and plots" if plots else ""))
    return 0
