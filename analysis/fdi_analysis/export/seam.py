"""The Python/C seam of the host ECU, named: what the ctypes bindings (fdi_host.ecu.bindings) may ask the shared
library's query functions (host_tools/fdi_host/ecu/fdi_py_seam.c), one list per function, from one source: this module.

Each list becomes a C enumeration in ``host_tools/fdi_host/ecu/fdi_py_seam.h`` (``python -m
fdi_analysis.export.seam``; tests/host/test_seam.py fails when the committed copy is stale or when fdi_py_seam.c leaves
a query unanswered) and a Python `enum.IntEnum` (`SizeOf`, `TableInt`, ...) the bindings pass, so neither side
writes a bare number. A question's number is its place in its class: append, never reorder.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from pathlib import Path
from string import Template

from fdi_analysis.export.c_text import banner, comment_text, write_header_main

COMMAND = "python -m fdi_analysis.export.seam"
HEADER = Path("host_tools/fdi_host/ecu/fdi_py_seam.h")  # relative to the repository's root


class Query(enum.IntEnum):
    """A question of one query function; its number is its place in the class (append, never reorder), its
    description `what` the C comment."""

    what: str

    def __new__(cls, value: int, what: str = "") -> Query:
        obj = int.__new__(cls, value)
        obj._value_ = value
        obj.what = what
        return obj


class SizeOf(Query):
    """The questions of fdi_py_sizeof() (fdi_py_sizeof_t)."""

    ECU = 0, "sizeof(fdi_ecu_t)"
    ECU_CONFIG = 1, "sizeof(fdi_ecu_config_t)"
    ECU_COUNTERS = 2, "sizeof(fdi_ecu_counters_t)"
    ECU_RESULT = 3, "sizeof(fdi_ecu_result_t)"
    ECU_TX = 4, "sizeof(fdi_ecu_tx_t)"
    ECU_RESULT_DIAG = 5, "offsetof(fdi_ecu_result_t, diag)"
    DIAG_RESULT_ISO = 6, "offsetof(fdi_diag_result_t, iso)"
    MAX_TESTS = 7, "FDI_DIAG_MAX_TESTS"
    DIAG = 8, "sizeof(fdi_diag_t)"
    MAX_MSGS = 9, "FDI_ECU_MAX_MSGS"
    MAX_SENS = 10, "FDI_DIAG_MAX_SENS"
    DIAG_RESULT_SENS_OFFSET = 11, "offsetof(fdi_diag_result_t, sens_offset)"
    DIAG_RESULT = 12, "sizeof(fdi_diag_result_t)"
    DIAG_CONFIG = 13, "sizeof(fdi_diag_config_t)"
    GEN_N_PARAMS = 14, "FDI_GEN_N_PARAMS"
    FRAME_MAX_SIGNALS = 15, "FDI_FRAME_MAX_SIGNALS"
    ECU_HISTORY = 16, "FDI_ECU_HISTORY"
    DIAG_EVIDENCE = 17, "sizeof(fdi_diag_evidence_t)"
    TABLE_MAX_FAULTS = 18, "FDI_TABLE_MAX_FAULTS"
    EST_MAX_PARAMS = 19, "FDI_EST_MAX_PARAMS"


class TableInt(Query):
    """The questions of fdi_py_table_int() (fdi_py_table_int_t)."""

    N_FAULTS = 0, "n_faults"
    N_TESTS = 1, "n_tests"
    MSO_ID = 2, "mso_id of test i"
    HAS_GENERATOR = 3, "1 if test i has a generator, else 0"
    FAULT_MASK = 4, "fault_mask of test i"
    INPUT_MASK = 5, "input_mask of test i"
    ISO_CLASS = 6, "iso_class of fault i"
    FAULT_SIGNATURE = 7, "fault_signature of fault i"
    DT_US = 8, "the design step dt in microseconds"
    N_SIGNALS = 9, "n_signals"
    SENS_MASK = 10, "sens_mask of test i's generator (0 without)"
    N_EST = 11, "quantities test i's generator estimates (0 without)"


class TableReal(Query):
    """The questions of fdi_py_table_real() (fdi_py_table_real_t)."""

    SENSITIVITY_MARGIN = 0, "sensitivity_margin"
    GATE = 1, "gate of test i"
    VARIANCE = 2, "variance of test i"


class TableStr(Query):
    """The questions of fdi_py_table_str() (fdi_py_table_str_t)."""

    FAULT_NAME = 0, "name of fault i"
    INTERPRETATION = 1, "interpretation of test i"
    SIGNAL_NAME = 2, "name of signal i"
    GENERATOR_NAME = 3, "generator name of test i (\"\" without)"


class BusInt(Query):
    """The questions of fdi_py_bus_int() (fdi_py_bus_int_t)."""

    N_MSGS = 0, "n_msgs"
    CAN_ID = 1, "can_id of message i"
    DIAG_ID = 2, "CAN ID of the diagnosis frame"
    CYCLE_MS = 3, "cycle_ms of message i"
    SIGNALS = 4, "frame-signal mask of message i"
    DLC = 5, "dlc of message i"
    DATA_ID = 6, "E2E data ID of message i"
    DIAG_DATA_ID = 7, "E2E data ID of the diagnosis frame"


@dataclass(frozen=True)
class Family:
    """One query function of fdi_py_seam.c (`function`): its questions (`queries`), as C enum type and prefix."""

    function: str
    enum_type: str
    prefix: str
    queries: type[Query]


FAMILIES: tuple[Family, ...] = (
    Family("fdi_py_sizeof", "fdi_py_sizeof_t", "FDI_PY_SIZEOF_", SizeOf),
    Family("fdi_py_table_int", "fdi_py_table_int_t", "FDI_PY_TABLE_INT_", TableInt),
    Family("fdi_py_table_real", "fdi_py_table_real_t", "FDI_PY_TABLE_REAL_", TableReal),
    Family("fdi_py_table_str", "fdi_py_table_str_t", "FDI_PY_TABLE_STR_", TableStr),
    Family("fdi_py_bus_int", "fdi_py_bus_int_t", "FDI_PY_BUS_INT_", BusInt),
)


HEADER_FMT = Template("""\
${banner}
/*
 * fdi_py_seam.h - the questions the ctypes bindings (fdi_host/ecu/bindings.py) ask the query functions of
 * fdi_py_seam.c, one enumeration per function, named on both sides from one source (fdi_analysis.export.seam).
 * A question's number is its place in its list; the functions answer an unknown one with 0 / -1 / NULL.
 */
#ifndef FDI_PY_SEAM_H
#define FDI_PY_SEAM_H

${enums}
#endif /* FDI_PY_SEAM_H */
""")

ENUM_FMT = Template("""\
/* ${function}(): ${n} questions */
typedef enum
{
${entries}
} ${enum_type};
""")

ENTRY_FMT = Template("    ${prefix}${name} = ${value}${comma} /* ${what} */")


def render_header() -> str:
    """The text of host_tools/fdi_host/ecu/fdi_py_seam.h."""
    enums = []
    for fam in FAMILIES:
        last = len(fam.queries) - 1
        entries = "\n".join(ENTRY_FMT.substitute(prefix=fam.prefix, name=q.name, value=int(q),
                                                 comma="," if int(q) < last else "", what=comment_text(q.what))
                            for q in fam.queries)
        enums.append(ENUM_FMT.substitute(function=fam.function, n=len(fam.queries), entries=entries,
                                         enum_type=fam.enum_type))
    return HEADER_FMT.substitute(banner=banner(COMMAND), enums="\n".join(enums))


def main(argv: list[str] | None = None) -> int:
    return write_header_main(COMMAND, "the host ECU's Python/C seam", HEADER, render_header, argv)


if __name__ == "__main__":
    raise SystemExit(main())
