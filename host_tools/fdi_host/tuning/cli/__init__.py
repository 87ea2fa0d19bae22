"""`fdi-tune`: the closed-loop steps between the structural analysis and the firmware, each on simulated drives
(one module per subcommand): calibrate the gates, sweep the fault sizes, add tests for practical
detectability, compute the generated residuals on a CAN log, calibrate the hand-written kinematic table."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from fdi_analysis.cli.common import add_version, run_subcommand
from fdi_host.tuning.cli import calibrate, kin, residuals, screen, uncertainty

SUBCOMMANDS = (screen, calibrate, residuals, uncertainty, kin)

EPILOG = """examples:
  fdi-tune screen analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml \\
      --sizes host_tools/scenarios/fault_sizes.toml --out analysis/models/romo_screening.json.gz
  fdi-tune calibrate analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml
  fdi-tune fault-sizes analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml \\
      --sizes host_tools/scenarios/fault_sizes.toml
  fdi-tune residuals analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml \\
      --log out/drive.blf --plot out/residuals.png --compare-ecu
  fdi-tune uncertainty analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml \\
      --sizes host_tools/scenarios/fault_sizes.toml --out out/uncertainty
  fdi-tune kin-calibration --out fw/vehicles/romo/generated/fdi_kin_calibration.h
MODEL and --thresholds: a file, or the name of one shipped with the package (romo_grouped, romo_thresholds, ...)
"""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fdi-tune",
        description="Closed-loop tuning of the diagnosis on simulated drives: gates, fault sizes, added tests, "
        "residuals on a log, residual spread over the uncertainty envelope.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_version(parser)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for mod in SUBCOMMANDS:
        mod.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    return run_subcommand("fdi-tune", build_parser(), argv)


if __name__ == "__main__":
    sys.exit(main())
