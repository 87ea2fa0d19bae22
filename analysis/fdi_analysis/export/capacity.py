"""The capacities of the C library a build may override, from one source: this module.

`CAPACITIES` lists each with its default and range. The C header ``fw/include/generated/fdi_capacity.h`` is
rendered from it (``python -m fdi_analysis.export.capacity``; tests/analysis/test_capacity.py fails when the
committed copy is stale), CMake reads the defaults of its cache options from that header (fw/CMakeLists.txt), and
the export (`export.table`, `export.generators`) refuses a table or a generator set that exceeds them, naming both
numbers. A firmware built with larger capacities (``cmake -DFDI_DIAG_MAX_TESTS=24``) exports with
``Capacity(max_tests=24)``.

    from fdi_analysis.export.capacity import Capacity
    table_file(..., capacity=Capacity(max_tests=24))

"""

from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path
from string import Template

from fdi_analysis.errors import FdiError
from fdi_analysis.export.c_text import banner, write_header_main

COMMAND = "python -m fdi_analysis.export.capacity"
HEADER = Path("fw/include/generated/fdi_capacity.h")  # relative to the repository's root


@dataclass(frozen=True)
class Limit:
    """One overridable capacity: its macro, default, range and what it counts (with why its range is so)."""

    macro: str
    default: int
    lo: int
    hi: int
    what: str


CAPACITIES: tuple[Limit, ...] = (
    Limit("FDI_DIAG_MAX_TESTS", 16, 1, 32, "tests of a table the diagnoser holds (test bitmasks are uint32_t)"),
    Limit("FDI_DIAG_MAX_SENS", 192, 1, 255, "fault sensitivities of all tests together (offsets are uint8_t)"),
    Limit("FDI_DIAG_MAX_FILTERS", 48, 1, 255,
          "filter states: the set's bank + the hand-written generators' instance filters"),
    Limit("FDI_EST_MAX_PARAMS", 3, 1, 4, "quantities one test estimates on line (fdi_est.h)"),
    Limit("FDI_GEN_MAX_FILTERS", 16, 1, 255, "instance filters of one hand-written generator (fdi_gen.h)"),
    Limit("FDI_ECU_MAX_MSGS", 8, 1, 255, "input messages of a bus (fdi_ecu.h)"),
    Limit("FDI_ECU_HISTORY", 6, 2, 255, "accepted frames kept per message for the time alignment (fdi_ecu.h)"),
)
_DEFAULT = {c.macro: c.default for c in CAPACITIES}
MACROS = {"max_tests": "FDI_DIAG_MAX_TESTS", "max_sens": "FDI_DIAG_MAX_SENS", "max_filters": "FDI_DIAG_MAX_FILTERS",
          "est_max_params": "FDI_EST_MAX_PARAMS"}  # Capacity field -> its macro


def limit(macro: str) -> Limit:
    """The declaration of capacity `macro`."""
    return next(c for c in CAPACITIES if c.macro == macro)


class CapacityError(FdiError, ValueError):
    """A capacity outside the range the C headers accept."""


@dataclass(frozen=True)
class Capacity:
    """The capacities a firmware is built with (the defaults of `CAPACITIES` unless given): what the export
    checks a table and its generators against."""

    max_tests: int = _DEFAULT["FDI_DIAG_MAX_TESTS"]
    max_sens: int = _DEFAULT["FDI_DIAG_MAX_SENS"]
    max_filters: int = _DEFAULT["FDI_DIAG_MAX_FILTERS"]
    est_max_params: int = _DEFAULT["FDI_EST_MAX_PARAMS"]

    def __post_init__(self) -> None:
        for f in fields(self):
            lim = limit(MACROS[f.name])
            value = getattr(self, f.name)
            if not lim.lo <= value <= lim.hi:
                raise CapacityError(f"{lim.macro}={value}: the firmware accepts {lim.lo}..{lim.hi}")

    def exceeded(self, field: str, count: int, what: str) -> str | None:
        """None when `count` fits capacity `field`, else the one-line reason naming both numbers and the macro."""
        cap, macro = getattr(self, field), MACROS[field]
        if count <= cap:
            return None
        return (f"{count} {what}; the firmware is built for at most {cap} ({macro}; raise it with "
                f"-D{macro}=n, then export with the same capacity)")

    @staticmethod
    def parse(items: list[str]) -> Capacity:
        """A capacity from ``MACRO=n`` items (``fdi-analyze export-c --capacity FDI_DIAG_MAX_TESTS=24``), the
        defaults for the others; `CapacityError` naming the item for an unknown macro or a value not a number."""
        field_of = {m: f for f, m in MACROS.items()}
        values: dict[str, int] = {}
        for item in items:
            macro, eq, value = item.partition("=")
            if not eq or macro not in field_of:
                raise CapacityError(f"--capacity {item!r}: expected MACRO=n with MACRO one of {', '.join(field_of)}")
            try:
                values[field_of[macro]] = int(value)
            except ValueError as exc:
                raise CapacityError(f"--capacity {item!r}: {value!r} is not a whole number") from exc
        return Capacity(**values)

    def options(self) -> str:
        """The ``--capacity`` options that give this capacity (empty for the defaults)."""
        return "".join(f" --capacity {MACROS[f.name]}={getattr(self, f.name)}" for f in fields(self)
                       if getattr(self, f.name) != getattr(DEFAULT, f.name))


DEFAULT = Capacity()


HEADER_FMT = Template("""\
${banner}
/*
 * fdi_capacity.h - the capacities of the fdi library a build may override with -D<NAME>=n, their defaults and
 * ranges (one source: fdi_analysis.export.capacity, which the export checks tables against). The CMake build
 * makes each a cache option of the same name and passes it to consumers of fdi::fdi as an interface compile
 * definition; fdi_diag_init() refuses a caller compiled with other values (FDI_BAD_LAYOUT, fdi_diag.h).
 * Cost: none. Memory: none.
 */
#ifndef FDI_CAPACITY_H
#define FDI_CAPACITY_H

${entries}
#endif /* FDI_CAPACITY_H */
""")

ENTRY_FMT = Template("""\
#ifndef ${macro}
#define ${macro} ${default}U /* ${what} */
#endif
#if (${macro} < ${lo}) || (${macro} > ${hi})
#error "${macro} must be in ${lo}..${hi}"
#endif
""")


def render_header() -> str:
    """The text of fw/include/generated/fdi_capacity.h."""
    return HEADER_FMT.substitute(banner=banner(COMMAND), entries="\n".join(
        ENTRY_FMT.substitute(macro=c.macro, default=c.default, lo=c.lo, hi=c.hi, what=c.what) for c in CAPACITIES))


def main(argv: list[str] | None = None) -> int:
    return write_header_main(COMMAND, "the library's capacities", HEADER, render_header, argv)


if __name__ == "__main__":
    raise SystemExit(main())
