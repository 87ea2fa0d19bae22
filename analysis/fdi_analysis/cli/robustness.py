"""`fdi-analyze robustness MODEL`: what decoupling the residuals from the model's unknown parameters and inputs
costs (redundancy, detectability, isolability, MSO sets), nuisance by nuisance, and the set decoupled for free."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from fdi_analysis.model import ModelError
from fdi_analysis.model_loader import load_model
from fdi_analysis.plots import plot_decoupling_cost, save
from fdi_analysis.robustness import analyse, markdown

EXAMPLE = """examples:
  fdi-analyze robustness romo_grouped --mso -o out/robustness   # with the MSO sets counted (a few seconds)
  fdi-analyze robustness romo_full_vertical                       # structure only (the MSO count takes minutes)"""


def register(sub: Any) -> None:
    p = sub.add_parser(
        "robustness",
        help="cost of decoupling the residuals from the model's unknown parameters and inputs; the free set",
        description="For each unknown parameter and unknown input the model declares, and for all of them: what "
        "decoupling the residuals from it costs against the nominal model (structural redundancy, faults that "
        "lose detectability, pairs that lose isolability, MSO sets with --mso); and the largest set decoupled at "
        "no cost. Writes robustness.json, robustness.md and robustness.png with -o.",
        epilog=EXAMPLE, formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("model", type=Path, help="model file (.toml) declaring [[unknown_parameter]] / [[unknown_input]]")
    p.add_argument("--mso", action="store_true",
                   help="also count the MSO sets of the nominal, the chosen and the all-decoupled models")
    p.add_argument("--workers", type=int, default=2, help="worker processes of the MSO count (default 2)")
    p.add_argument("-o", "--out", type=Path, default=None, help="folder for robustness.json, .md and .png")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    model = load_model(args.model)
    if not model.nuisances:
        raise ModelError("the model declares no [[unknown_parameter]] or [[unknown_input]]; there is nothing to "
                         "decouple", file=str(args.model))
    if args.mso:
        print(f"{model.name}: counting MSO sets of three models ...", flush=True)
    report = analyse(model, mso_workers=max(1, args.workers) if args.mso else 0)
    text = markdown(report)
    print(text)
    if args.out is not None:
        out: Path = args.out
        out.mkdir(parents=True, exist_ok=True)
        (out / "robustness.json").write_text(json.dumps(report.to_dict(), indent=1) + "\n", encoding="utf-8")
        (out / "robustness.md").write_text(text, encoding="utf-8")
        save(plot_decoupling_cost(report), out / "robustness.png")
        print(f"wrote {out / 'robustness.json'}, {out / 'robustness.md'} and {out / 'robustness.png'}")
    return 0
