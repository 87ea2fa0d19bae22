"""The Python/C seam of the host ECU is named from one source (fdi_analysis.export.seam): the committed C header
is its rendering, fdi_py_seam.c answers every question by its name (no bare number), and the shared library answers
the names the bindings pass as the header numbers them (a question past the end gets the functions' 'unknown')."""

from __future__ import annotations

import re
from pathlib import Path

from fdi_analysis.export.seam import FAMILIES, HEADER, SizeOf, TableInt, render_header
from fdi_host.ecu import bindings

GLUE = Path("host_tools/fdi_host/ecu/fdi_py_seam.c")


def test_committed_header_is_up_to_date(repo: Path) -> None:
    assert (repo / HEADER).read_text(encoding="utf-8") == render_header(), \
        f"{HEADER} is stale: run python -m fdi_analysis.export.seam"


def test_the_glue_answers_every_question_by_name(repo: Path) -> None:
    glue = (repo / GLUE).read_text(encoding="utf-8")
    for fam in FAMILIES:
        definition = re.search(rf"\b{fam.function}\([^)]*\)\n{{", glue)
        assert definition is not None, f"{fam.function} is not defined in {GLUE}"
        body = glue[definition.start():glue.index("\n}\n", definition.start())]
        for q in fam.queries:
            name = fam.prefix + q.name
            assert f"case {name}:" in body or f"(what == (int){name})" in body, f"{fam.function}: {name} unanswered"
        assert not re.search(r"case [0-9]+:|what == [0-9]+", body), f"{fam.function}: a bare number"


def test_the_library_answers_the_names() -> None:
    lib = bindings._lib()
    dll = lib.dll
    assert dll.fdi_py_sizeof(SizeOf.MAX_TESTS) == lib.caps.max_tests > 0
    assert dll.fdi_py_sizeof(SizeOf.DIAG) == lib.diag_size > 0
    assert dll.fdi_py_sizeof(len(SizeOf)) == 0  # past the end: unknown
    t = dll.fdi_plugin_table()
    assert dll.fdi_py_table_int(t, TableInt.N_FAULTS, 0) == bindings.table_info("romo").n_faults
    assert dll.fdi_py_table_int(t, len(TableInt), 0) == -1


def test_the_command_writes_the_header(tmp_path: Path) -> None:
    from fdi_analysis.export.seam import main

    out = tmp_path / "fdi_py_seam.h"
    assert main(["--out", str(out)]) == 0 and out.read_text(encoding="utf-8") == render_header()
