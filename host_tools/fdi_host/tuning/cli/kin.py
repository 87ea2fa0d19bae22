"""`fdi-tune kin-calibration`: the hand-written kinematic table's variances and reaction sizes
(fw/vehicles/romo/generated/fdi_kin_calibration.h) from simulated drives through the C ECU core."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from fdi_host.tuning import kin_calibration
from fdi_host.tuning.kin_calibration import COMMAND


def register(sub: Any) -> None:
    p = sub.add_parser(
        "kin-calibration",
        help="calibrate the hand-written kinematic table (variances, reaction sizes) through the C ECU core",
        description=kin_calibration.__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    g = p.add_mutually_exclusive_group(required=True)
    g.add_argument("--out", type=Path, help="write the header here")
    g.add_argument("--check", type=Path, help="compare with this committed header; exit 1 when it is stale")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    def progress(text: str) -> None:
        print(f"  {text}", file=sys.stderr)

    cals = kin_calibration.calibrations(progress)
    text = kin_calibration.render(cals, kin_calibration.reaction_sizes(kin_calibration.variances(cals), progress))
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")
        print(f"wrote {args.out}")
        return 0
    if not args.check.is_file() or args.check.read_text(encoding="utf-8") != text:
        print(f"{args.check} is stale: run {COMMAND}", file=sys.stderr)
        return 1
    print(f"{args.check} is up to date")
    return 0
