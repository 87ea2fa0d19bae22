"""`fdi-analyze`: the command line of the offline analysis. One module per subcommand (cli_*.py)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from fdi_analysis import cli_convert, cli_export, cli_mso, cli_practical, cli_report, cli_select
from fdi_analysis.cli_common import add_version, run, use_file_backend
from fdi_analysis.export.fault_sizes import FaultSizesError
from fdi_analysis.export.table import ExportError
from fdi_analysis.model import ModelError
from fdi_analysis.residuals.reasons import NotRealizableError
from fdi_analysis.residuals.selected import SelectionError
from fdi_analysis.resources import model_file, shipped_models
from fdi_analysis.structure import StructureError

SUBCOMMANDS = (cli_report, cli_mso, cli_select, cli_practical, cli_export, cli_convert)

EPILOG = """examples:
  fdi-analyze report analysis/models/romo_quasistatic.toml -o out/romo
  fdi-analyze mso analysis/models/romo_grouped.toml
  fdi-analyze select analysis/models/romo_grouped.toml -o out/grouped
  fdi-analyze export-c analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml \
      --fault-sizes host_tools/scenarios/fault_sizes.toml --out fw/generated
  fdi-analyze convert analysis/models/romo_grouped.toml --to-fdt out/romo_grouped_fdt.json
(the closed-loop steps on simulated drives, screen, calibrate, fault-sizes and residuals, are fdi-tune's)
MODEL is a file, or the name of a model shipped with the package: {models}
"""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fdi-analyze",
        description="Structural fault diagnosis analysis of a model file (TOML) or an FDT structure (JSON).",
        epilog=EPILOG.format(models=", ".join(shipped_models())),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_version(parser)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for mod in SUBCOMMANDS:
        mod.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if isinstance(getattr(args, "model", None), Path):
        args.model = model_file(args.model)  # a bare name: the shipped model
    use_file_backend()
    return run("fdi-analyze", lambda: int(args.func(args)),
               (ModelError, StructureError, ExportError, FaultSizesError, SelectionError, NotRealizableError))


if __name__ == "__main__":
    sys.exit(main())
