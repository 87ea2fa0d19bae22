"""`fdi-analyze`: the command line of the offline analysis. One module per subcommand (report, mso, robustness,
select, practical, export, export_can, convert); `common` is what every command line of the project shares (the
`fdi_host` programs import it too).

The subcommands are imported when `main` builds the parser, not with this package: importing
`fdi_analysis.cli.common` runs this file first, and a host program's start must not load the analysis (sympy,
the residual synthesis, the C export: about a second).
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from fdi_analysis.cli.common import add_version, run_subcommand
from fdi_analysis.resources import shipped_models, shipped_thresholds

EPILOG = """examples:
  fdi-analyze report analysis/models/romo_quasistatic.toml -o out/romo
  fdi-analyze mso analysis/models/romo_grouped.toml
  fdi-analyze robustness analysis/models/romo_grouped.toml --mso -o out/robustness
  fdi-analyze select analysis/models/romo_grouped.toml -o out/grouped
  fdi-analyze export-c analysis/models/romo_grouped.toml --thresholds analysis/models/romo_thresholds.toml \\
      --fault-sizes host_tools/scenarios/fault_sizes.toml --out fw/vehicles/romo/generated
  fdi-analyze export-can analysis/models/romo_grouped.toml --dbc dbc/romo.dbc --out fw/vehicles/romo/generated/can
  fdi-analyze report romo_grouped -o out/grouped          (a model shipped with the package, by name)
  fdi-analyze convert analysis/models/romo_grouped.toml --to-fdt out/romo_grouped_fdt.json
(the closed-loop steps on simulated drives, screen, calibrate, fault-sizes and residuals, are fdi-tune's)
MODEL is a file, or the name of a model shipped with the package: {models}
THRESHOLDS (--thresholds) likewise: a file, or the name of a shipped one: {thresholds}
"""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fdi-analyze",
        description="Structural fault diagnosis analysis of a model file (TOML) or an FDT structure (JSON).",
        epilog=EPILOG.format(models=", ".join(shipped_models()), thresholds=", ".join(shipped_thresholds())),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_version(parser)
    from fdi_analysis.cli import convert, export, export_can, mso, practical, report, robustness, select

    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for mod in (report, mso, robustness, select, practical, export, export_can, convert):
        mod.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    return run_subcommand("fdi-analyze", build_parser(), argv)
