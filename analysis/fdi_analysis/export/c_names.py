"""The C names of a vehicle's generated code: one place that derives them from the table name.

A vehicle target (fw/vehicles/<vehicle>/) holds its generated files under the names below; the table
``fdi_<vehicle>_table`` gives the vehicle (``romo`` for ``fdi_romo_table``, ``three_tank`` for
``fdi_three_tank_table``), and every other name follows from it. The CAN codec (`can_codec`) uses the same
names for the signals it decodes into the frame.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from fdi_analysis.errors import FdiError

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


class CNameError(FdiError, ValueError):
    """A name of generated C (a table, a vehicle's plugin symbols) that is not a C identifier."""


def is_c_identifier(name: str) -> bool:
    return bool(_IDENT.fullmatch(name))


@dataclass(frozen=True)
class VehicleNames:
    vehicle: str  # e.g. "romo"
    table_name: str = ""  # the table's C name when it is not fdi_<vehicle>_table

    @staticmethod
    def of_table(table: str) -> VehicleNames:
        if not _IDENT.fullmatch(table):
            raise CNameError(f"table name {table!r} is not a C identifier")
        v = table.removeprefix("fdi_").removesuffix("_table") or table
        return VehicleNames(v, "" if table == f"fdi_{v}_table" else table)

    @property
    def prefix(self) -> str:
        """Macro prefix of the vehicle's signals: ROMO for ROMO_SIG_VX_M."""
        return self.vehicle.upper()

    @property
    def table(self) -> str:
        return self.table_name or f"fdi_{self.vehicle}_table"

    @property
    def signals(self) -> str:
        """Base name of the signals files (fdi_romo_signals.h/.c)."""
        return f"fdi_{self.vehicle}_signals"

    @property
    def signal_names(self) -> str:
        return f"fdi_{self.vehicle}_signal_names"

    @property
    def generators(self) -> str:
        """Base name of the generator files and of their descriptor array (fdi_romo_generators[])."""
        return f"fdi_{self.vehicle}_generators"

    @property
    def gen_set(self) -> str:
        """The generator set of the vehicle's generated generators (fdi_romo_gen_set)."""
        return f"fdi_{self.vehicle}_gen_set"

    @property
    def plugin(self) -> str:
        """Base name of the plugin glue (fdi_romo_plugin.c) and the plugin's target (fdi_vehicle_romo)."""
        return f"fdi_{self.vehicle}_plugin"

    @property
    def sig_count(self) -> str:
        return f"{self.prefix}_SIG_COUNT"

    @property
    def n_generators(self) -> str:
        return f"FDI_{self.prefix}_N_GENERATORS"

    def sig_index(self, signal: str) -> str:
        """Index macro of a measured signal: ROMO_SIG_VX_M."""
        return f"{self.prefix}_SIG_{signal.upper()}"

    def sig_mask(self, signal: str) -> str:
        """Mask macro of a measured signal: ROMO_SIGM_VX_M."""
        return f"{self.prefix}_SIGM_{signal.upper()}"

    def mask_expr(self, signals: list[str] | tuple[str, ...]) -> str:
        return " | ".join(self.sig_mask(s) for s in signals) or "0U"
