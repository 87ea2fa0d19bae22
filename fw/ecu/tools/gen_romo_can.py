"""Generate fw/vehicles/romo/generated/can/ from dbc/romo.dbc (fw/ecu/tools/gen_can.py for the ROMO bus).

    romo_can.{h,c}       cantools C code of the DBC (node FDI)
    fdi_romo_bus.{h,c}   the bus of the ECU core: input messages, their frame signals and decoding, the
                         diagnosis frame

The DBC signals carry the model's measured signals as the DBC's signal attributes state them ("ModelSignal", the
model's name; "ModelFactor", DBC value = model value * factor: the one mapping of the project, read by the host
tools too); the frame's signals are the knowns of
analysis/models/romo_grouped.toml (the model of the generated table, fdi_romo_signals.h).

Usage: python fw/ecu/tools/gen_romo_can.py [--dbc dbc/romo.dbc] [--out fw/vehicles/romo/generated/can]
(`bash scripts/generate.sh` runs it; tests/host/test_generated_can.py checks the committed copy is current).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import cantools
import gen_can

from fdi_analysis.model_loader import load_model

REPO = Path(__file__).resolve().parents[3]
DBC = REPO / "dbc" / "romo.dbc"
MODEL = REPO / "analysis" / "models" / "romo_grouped.toml"
OUT = REPO / "fw" / "vehicles" / "romo" / "generated" / "can"
DB_NAME = "romo_can"
NODE = "FDI"
VEHICLE = "romo"
CMD = "bash scripts/generate.sh"


def roles(dbc: Path = DBC) -> list[gen_can.SignalRole]:
    """The DBC signals that carry a model signal (attribute "ModelSignal"), with model value = DBC value / factor."""
    db = cantools.database.load_file(str(dbc))
    out = []
    for msg in db.messages:
        for sig in msg.signals:
            attrs = sig.dbc.attributes if sig.dbc is not None else {}
            if "ModelSignal" in attrs and attrs["ModelSignal"].value:
                factor = float(attrs["ModelFactor"].value) if "ModelFactor" in attrs else 1.0
                out.append(gen_can.SignalRole(sig.name, str(attrs["ModelSignal"].value), 1.0 / factor))
    return out


def generate(dbc: Path = DBC) -> dict[str, str]:
    """Every file of fw/vehicles/romo/generated/can/ by name."""
    knowns = [k.name for k in load_model(MODEL).knowns]
    return gen_can.generate(dbc, NODE, DB_NAME, VEHICLE, roles(dbc), knowns, CMD)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dbc", type=Path, default=DBC)
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    for name, text in generate(args.dbc).items():
        (args.out / name).write_text(text)
        print(f"wrote {args.out / name}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
