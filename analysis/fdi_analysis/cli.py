"""`fdi-analyze`: the command line of the offline analysis. One module per subcommand (cli_*.py)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from fdi_analysis import cli_convert, cli_report
from fdi_analysis.model import ModelError
from fdi_analysis.structure import StructureError

SUBCOMMANDS = (cli_report, cli_convert)

EPILOG = """examples:
  fdi-analyze report analysis/models/romo_quasistatic.toml -o out/romo
  fdi-analyze convert analysis/models/romo_grouped.toml --to-fdt out/romo_grouped_fdt.json
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
    except (ModelError, StructureError) as exc:
        print(f"fdi-analyze: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("fdi-analyze: interrupted", file=sys.stderr)
        return 130
    return code


if __name__ == "__main__":
    sys.exit(main())
