"""Render a structural `Summary` as a JSON report (for machines) and a Markdown report (for people)."""

from __future__ import annotations

import json
from pathlib import Path

from fdi_analysis.summary import Summary


def write_json(summary: Summary, path: Path) -> None:
    path.write_text(json.dumps(summary.to_dict(), indent=2) + "\n", encoding="utf-8")


def markdown(summary: Summary, plots: dict[str, str] | None = None) -> str:
    d = summary.to_dict()
    c = d["counts"]
    st = summary.structure
    iso = summary.isolability
    lines = [
        f"# Structural analysis: {d['model']}",
        "",
        d["description"] or "",
        "",
        "## Counts",
        "",
        "| equations | normal | measurement | differential constraints | unknowns | knowns | faults | redundancy |",
        "|---|---|---|---|---|---|---|---|",
        f"| {c['equations']} | {c['normal_equations']} | {c['measurement_equations']} | "
        f"{c['differential_constraints']} | {c['unknowns']} | {c['knowns']} | {c['faults']} | "
        f"{d['structural_redundancy']} |",
        "",
        "## Dulmage-Mendelsohn decomposition (mixed causality)",
        "",
        f"- overdetermined part M+: {len(summary.dm.plus_eqs)} equations, {len(summary.dm.plus_vars)} unknowns, "
        f"redundancy {summary.redundancy}, {len(summary.equivalence_classes)} equivalence classes",
        f"- just-determined part M0: {len(summary.dm.zero_eqs)} equations in {len(summary.dm.zero_blocks)} blocks",
        f"- underdetermined part M-: {len(summary.dm.minus_eqs)} equations, {len(summary.dm.minus_vars)} unknowns",
        "",
        "Equivalence classes of M+ with more than one equation:",
        "",
    ]
    multi = [cl for cl in d["dm"]["equivalence_classes"] if len(cl) > 1]
    lines += [f"- {{{', '.join(cl)}}}" for cl in multi] or ["- none"]
    lines += ["", "## Faults", ""]
    nd = d["faults"]["not_detectable"]
    lines.append(f"- structurally detectable: {len(d['faults']['detectable'])} of {st.nf}"
                 + (f" (not detectable: {', '.join(nd)})" if nd else ""))
    pairs = d["faults"]["non_isolable_pairs"]
    lines.append("- single faults that cannot be isolated from each other: "
                 + (", ".join("{" + ", ".join(p) + "}" for p in pairs) if pairs else "none"))
    one_way = d["faults"]["one_way_pairs"]
    lines.append("- isolable one way only (a -> b: a cannot be isolated from b, b can be isolated from a): "
                 + (", ".join(f"{a} -> {b}" for a, b in one_way) if one_way else "none"))
    lines += ["", "### Isolability classes", "", "| class | faults | meaning |", "|---|---|---|"]
    fault_desc = {f.name: f.desc for f in summary.model.faults}
    for k, cl in enumerate(iso.classes, 1):
        names = [st.faults[i] for i in cl]
        lines.append(f"| {k} | {', '.join(names)} | {'; '.join(fault_desc.get(n, '') for n in names)} |")
    if plots:
        lines += ["", "## Plots", ""]
        lines += [f"![{title}]({path})" for title, path in plots.items()]
    lines.append("")
    return "\n".join(lines)


def write_markdown(summary: Summary, path: Path, plots: dict[str, str] | None = None) -> None:
    path.write_text(markdown(summary, plots), encoding="utf-8")
