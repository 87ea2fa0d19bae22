"""`fdi-analyze export-can MODEL --dbc DBC`: a vehicle's CAN codec for the ECU core, generated from its DBC."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from fdi_analysis.export import can_codec
from fdi_analysis.export.c_names import VehicleNames
from fdi_analysis.model_loader import load_model

EXAMPLE = ("example: fdi-analyze export-can analysis/models/romo_grouped.toml --dbc dbc/romo.dbc "
           "--out fw/vehicles/romo/generated/can")
DEFAULT_NAME = "fdi_romo_table"


def register(sub: Any) -> None:
    p = sub.add_parser(
        "export-can",
        help="write the vehicle's CAN codec for the ECU core from its DBC (cantools C code + fdi_<vehicle>_bus)",
        description="From DBC and the diagnosis node NODE: <vehicle>_can.h/.c (cantools generate_c_source: pack, "
        "unpack, range checks), and fdi_<vehicle>_bus.h/.c, the bus of the ECU core (fw/ecu/include/fdi_ecu.h): "
        "per input message of NODE its ID, length, cycle time, E2E data ID, the frame signals it carries "
        "(the DBC's signal attributes ModelSignal and ModelFactor name MODEL's measured signals) and a decode "
        "function; the packing of NODE's diagnosis message. The frame indices are those of "
        "fdi_<vehicle>_signals.h, written by export-c with the same --name.",
        epilog=EXAMPLE,
    )
    p.add_argument("model", type=Path, help="model file (.toml) or FDT structure (.json): its measured signals")
    p.add_argument("--dbc", type=Path, required=True, help="the vehicle's DBC")
    p.add_argument("--out", type=Path, required=True, help="output folder (fw/vehicles/<vehicle>/generated/can)")
    p.add_argument("--name", default=DEFAULT_NAME,
                   help=f"C name of the vehicle's table, as export-c's --name (default {DEFAULT_NAME}: vehicle romo)")
    p.add_argument("--node", default="FDI", help="the DBC node of the diagnosis unit (default FDI)")
    p.add_argument("--database-name", default=None,
                   help="C prefix of the cantools code (default <vehicle>_can)")
    p.set_defaults(func=run)


def command_line(model: Path, dbc: Path, out: Path, name: str, node: str, db_name: str | None) -> str:
    return (f"fdi-analyze export-can {model.as_posix()} --dbc {dbc.as_posix()} --out {out.as_posix()}"
            + (f" --name {name}" if name != DEFAULT_NAME else "") + (f" --node {node}" if node != "FDI" else "")
            + (f" --database-name {db_name}" if db_name else ""))


def generate(model: Path, dbc: Path, out: Path, name: str = DEFAULT_NAME, node: str = "FDI",
             db_name: str | None = None) -> dict[str, str]:
    """Every file of the codec by name (what `run` writes into `out`)."""
    knowns = [k.name for k in load_model(model).knowns]
    return can_codec.generate(dbc, node, VehicleNames.of_table(name), knowns,
                              command_line(model, dbc, out, name, node, db_name), db_name)


def run(args: argparse.Namespace) -> int:
    files = generate(args.model, args.dbc, args.out, args.name, args.node, args.database_name)
    args.out.mkdir(parents=True, exist_ok=True)
    for fname, text in files.items():
        (args.out / fname).write_text(text, encoding="utf-8")
        print(f"wrote {args.out / fname}")
    return 0
