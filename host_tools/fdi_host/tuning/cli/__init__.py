"""`fdi-tune`: the closed-loop steps between the structural analysis and the firmware, each on simulated drives
(one module per subcommand): calibrate the gates, sweep the fault sizes, add tests for practical
detectability, compute the generated residuals on a CAN log, calibrate the hand-written kinematic table."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from fdi_analysis.export.fault_sizes import FaultSizesError
from fdi_analysis.export.table import ExportError
from fdi_analysis.model import ModelError
from fdi_analysis.residuals.reasons import NotRealizableError
from fdi_analysis.residuals.selected import AugmentError
from fdi_analysis.structure import StructureError
from fdi_host.tuning.cli import augment, calibrate, kin, residuals

SUBCOMMANDS = (calibrate, augment, residuals, kin)

EPILOG = """examples:
  fdi-tune calibrate analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml
  fdi-tune fault-sizes analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml \\
      --sizes host_tools/scenarios/fault_sizes.toml
  fdi-tune augment analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml \\
      --sizes host_tools/scenarios/fault_sizes.toml
  fdi-tune residuals analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml \\
      --log out/drive.blf --plot out/residuals.png --compare-ecu
  fdi-tune kin-calibration --out fw/generated/fdi_kin_calibration.h
"""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fdi-tune",
        description="Closed-loop tuning of the diagnosis on simulated drives: gates, fault sizes, added tests, "
        "residuals on a log.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for mod in SUBCOMMANDS:
        mod.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        code: int = args.func(args)
    except (ModelError, StructureError, ExportError, FaultSizesError, AugmentError, NotRealizableError) as exc:
        print(f"fdi-tune: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("fdi-tune: interrupted", file=sys.stderr)
        return 130
    return code


if __name__ == "__main__":
    sys.exit(main())
