"""`fdi-analyze export-c MODEL`: the firmware's diagnosis table (selected MSOs, signatures, classes) as C."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from fdi_analysis.candidates import mso_candidates
from fdi_analysis.export_c import Thresholds, render, write
from fdi_analysis.model_loader import load_model
from fdi_analysis.selection import optimal

EXAMPLE = ("example: fdi-analyze export-c analysis/models/romo_grouped.toml "
           "--thresholds analysis/models/romo_thresholds.toml --out fw/generated")


def register(sub: Any) -> None:
    p = sub.add_parser(
        "export-c",
        help="write the C diagnosis table (fdi_table_t) of the optimal method-B MSO selection",
        description="Select the optimal MSO set of MODEL (method B, fewest tests then fewest unknowns) and "
        "write NAME.h / NAME.c for fw/: tests with fault bitmasks, signals, generator kinds, gates and "
        "variances, fault names, the signature matrix and the isolability classes.",
        epilog=EXAMPLE,
    )
    p.add_argument("model", type=Path, help="model file (.toml) or FDT structure (.json)")
    p.add_argument("--thresholds", type=Path, required=True, help="gates, variances and generator design point")
    p.add_argument("--out", type=Path, required=True, help="output folder (fw/generated)")
    p.add_argument("--name", default="fdi_romo_table", help="C name of the table (default fdi_romo_table)")
    p.add_argument("--workers", type=int, default=2, help="worker processes of the MSO search (default 2)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def command_line(model: Path, thresholds: Path, out: Path, name: str) -> str:
    return f"fdi-analyze export-c {model.as_posix()} --thresholds {thresholds.as_posix()} --out {out.as_posix()}" + (
        f" --name {name}" if name != "fdi_romo_table" else "")


def generate(model_path: Path, thresholds_path: Path, out: Path, name: str, workers: int = 2,
             progress: bool = False) -> tuple[str, str]:
    model = load_model(model_path)
    st = model.structure()
    _, cands = mso_candidates(st, workers=workers, progress=progress)
    sel = optimal(cands, st.nf, "B")
    return render(model, sel.tests, Thresholds.load(thresholds_path), name,
                  command_line(model_path, thresholds_path, out, name))


def run(args: argparse.Namespace) -> int:
    header, source = generate(args.model, args.thresholds, args.out, args.name, args.workers,
                              not args.no_progress)
    for path in write(args.out, args.name, header, source):
        print(f"wrote {path}")
    return 0
