"""`fdi-analyze`: the command line of the offline analysis. One module per subcommand (cli_*.py)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from fdi_analysis import cli_convert, cli_export, cli_mso, cli_report, cli_select
from fdi_analysis.export.fault_sizes import FaultSizesError
from fdi_analysis.export.table import ExportError
from fdi_analysis.model import ModelError
from fdi_analysis.residuals.reasons import NotRealizableError
from fdi_analysis.residuals.selected import AugmentError
from fdi_analysis.structure import StructureError

SUBCOMMANDS = (cli_report, cli_mso, cli_select, cli_export, cli_convert)

EPILOG = """examples:
  fdi-analyze report analysis/models/romo_quasistatic.toml -o out/romo
  fdi-analyze mso analysis/models/romo_grouped.toml
  fdi-analyze select analysis/models/romo_grouped.toml -o out/grouped
  fdi-analyze export-c analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml \
      --fault-sizes host_tools/scenarios/fault_sizes.toml --out fw/generated
  fdi-analyze convert analysis/models/romo_grouped.toml --to-fdt out/romo_grouped_fdt.json
(the closed-loop steps on simulated drives, calibrate, fault-sizes, augment and residuals, are fdi-tune's)
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
    except (ModelError, StructureError, ExportError, FaultSizesError, AugmentError, NotRealizableError) as exc:
        print(f"fdi-analyze: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("fdi-analyze: interrupted", file=sys.stderr)
        return 130
    return code


if __name__ == "__main__":
    sys.exit(main())
