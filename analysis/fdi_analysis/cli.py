"""`fdi-analyze`: the command line of the offline analysis. One module per subcommand (cli_*.py)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from fdi_analysis import (
    cli_augment,
    cli_calibrate,
    cli_convert,
    cli_export,
    cli_mso,
    cli_report,
    cli_residuals,
    cli_select,
)
from fdi_analysis.exoneration import FaultSizesError
from fdi_analysis.export_c import ExportError
from fdi_analysis.model import ModelError
from fdi_analysis.structure import StructureError

SUBCOMMANDS = (cli_report, cli_mso, cli_select, cli_export, cli_convert, cli_calibrate, cli_augment, cli_residuals)

EPILOG = """examples:
  fdi-analyze report analysis/models/romo_quasistatic.toml -o out/romo
  fdi-analyze mso analysis/models/romo_grouped.toml
  fdi-analyze select analysis/models/romo_grouped.toml -o out/grouped
  fdi-analyze export-c analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml \
      --fault-sizes host_tools/scenarios/fault_sizes.toml --out fw/generated
  fdi-analyze augment analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml \
      --sizes host_tools/scenarios/fault_sizes.toml
  fdi-analyze convert analysis/models/romo_grouped.toml --to-fdt out/romo_grouped_fdt.json
  fdi-analyze residuals analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml \
      --log out/drive.blf --plot out/residuals.png --compare-ecu
"""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fdi-analyze",
        description="Structural fault diagnosis analysis of a model file (TOML) or an FDT structure (JSON).",
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
    except (ModelError, StructureError, ExportError, FaultSizesError) as exc:
        print(f"fdi-analyze: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("fdi-analyze: interrupted", file=sys.stderr)
        return 130
    return code


if __name__ == "__main__":
    sys.exit(main())
