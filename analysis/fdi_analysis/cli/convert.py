"""`fdi-analyze convert MODEL --to-fdt OUT`: move structures to and from Fault Diagnosis Toolbox JSON."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from fdi_analysis.model_loader import export_fdt_json, load_model

EXAMPLE = "example: fdi-analyze convert analysis/models/romo_grouped.toml --to-fdt romo_grouped.json"


def register(sub: Any) -> None:
    p = sub.add_parser(
        "convert",
        help="export a model's structure as FDT JSON (X, F, Z and name lists)",
        description="Write the incidence structure of MODEL in the JSON form Fault Diagnosis Toolbox users "
        "hold (MatrixStruc: X with differential markings 2/3, F, Z, name lists). An FDT JSON file is "
        "itself a valid MODEL for every fdi-analyze command.",
        epilog=EXAMPLE,
    )
    p.add_argument("model", type=Path, help="model file (.toml) or FDT structure (.json)")
    p.add_argument("--to-fdt", type=Path, required=True, metavar="OUT", help="output JSON file")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    model = load_model(args.model)
    export_fdt_json(model, args.to_fdt)
    c = model.counts()
    print(f"wrote {args.to_fdt}: {c['equations']} equations, {c['unknowns']} unknowns, "
          f"{c['knowns']} knowns, {c['faults']} faults")
    return 0
