"""The firmware's capacities from one source (fdi_analysis.export.capacity): the committed C header is its
rendering, CMake's cache options take its defaults, and the export refuses a table or a generator set that exceeds
the capacities it is given (the C defaults unless told otherwise), naming both numbers."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from fdi_analysis.export import generators as emit_generators
from fdi_analysis.export import table as emit_table
from fdi_analysis.export.c_names import VehicleNames
from fdi_analysis.export.capacity import CAPACITIES, DEFAULT, HEADER, Capacity, CapacityError, render_header
from fdi_analysis.export.thresholds import Thresholds
from fdi_analysis.fault_matrix import Candidate
from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.causality import synthesize

KIN1 = ["K1", "D1", "S1", "S3", "S4", "S5"]  # the kinematic MSO1 of romo_quasistatic (test_export_c.py)


def test_committed_header_is_up_to_date(repo: Path) -> None:
    path = repo / HEADER
    assert path.is_file(), f"{HEADER} is missing: run python -m fdi_analysis.export.capacity"
    assert path.read_text(encoding="utf-8") == render_header(), \
        f"{HEADER} is stale: run python -m fdi_analysis.export.capacity"


def test_no_capacity_is_defined_elsewhere_in_the_c_headers(repo: Path) -> None:
    """Each capacity has one definition, the generated header's: no other header of the library defines a default."""
    headers = [*(repo / "fw/include").glob("*.h"), *(repo / "fw/ecu/include").glob("*.h")]
    for c in CAPACITIES:
        defining = [h.name for h in headers if f"#define {c.macro} " in h.read_text(encoding="utf-8")]
        assert not defining, f"{c.macro} defined in {defining} besides {HEADER}"


def test_capacities_are_checked_and_named() -> None:
    assert Capacity() == DEFAULT and DEFAULT.max_tests == 16 and DEFAULT.max_sens == 192
    assert DEFAULT.est_max_params == emit_generators.MAX_ESTIMATED
    with pytest.raises(CapacityError, match=r"FDI_DIAG_MAX_TESTS=33: the firmware accepts 1\.\.32"):
        Capacity(max_tests=33)
    assert DEFAULT.exceeded("max_tests", 16, "tests selected") is None
    assert DEFAULT.exceeded("max_tests", 17, "tests selected") == (
        "17 tests selected; the firmware is built for at most 16 (FDI_DIAG_MAX_TESTS; raise it with "
        "-DFDI_DIAG_MAX_TESTS=n, then export with the same capacity)")


def test_export_refuses_a_table_beyond_the_capacity(repo: Path) -> None:
    """17 tests against the default 16 are refused before anything is rendered; with the capacity of a firmware
    built with -DFDI_DIAG_MAX_TESTS=24 the same table exports."""
    model = load_model(repo / "analysis/models/romo_quasistatic.toml")
    st = model.structure()
    mask = sum(1 << st.equations.index(e) for e in KIN1)
    faults = sum(1 << st.faults.index(f) for f in ("f1", "f3", "f4", "f5"))
    tests = [Candidate(mask, faults, 5, f"MSO{k}") for k in range(17)]
    th = Thresholds.load(repo / "analysis/models/romo_thresholds.toml")
    names = VehicleNames.of_table("fdi_kin17_table")
    with pytest.raises(emit_table.ExportError, match=r"^17 tests selected; the firmware is built for at most 16 "
                                                     r"\(FDI_DIAG_MAX_TESTS; raise it with -DFDI_DIAG_MAX_TESTS=n"):
        emit_table.table_file(model, tests, th, names, "/* cmd */", uncalibrated=True)
    f = emit_table.table_file(model, tests, th, names, "/* cmd */", uncalibrated=True,
                              capacity=Capacity(max_tests=24))
    assert len(f.tests) == 17


def test_export_refuses_generators_beyond_the_capacity(repo: Path) -> None:
    model = load_model(repo / "analysis/models/romo_quasistatic.toml")
    g = synthesize(model, KIN1, "MSO1")
    names = VehicleNames.of_table("fdi_kin1_table")
    faults, signals = [f.name for f in model.faults], [k.name for k in model.knowns]
    n_bank = len(emit_generators.bank_nodes([g], signals))
    assert n_bank > 1
    emit_generators.generators_file([g], names, faults, "/* cmd */", signals)  # fits the defaults
    with pytest.raises(emit_generators.EmitError,
                       match=rf"^{n_bank} filters in the bank; the firmware is built for at most 1 "
                             r"\(FDI_DIAG_MAX_FILTERS; raise it with -DFDI_DIAG_MAX_FILTERS=n"):
        emit_generators.generators_file([g], names, faults, "/* cmd */", signals, capacity=Capacity(max_filters=1))
    with pytest.raises(emit_generators.EmitError, match=r"^17 generators \(one test each\); the firmware is built "
                                                        r"for at most 16 \(FDI_DIAG_MAX_TESTS"):
        emit_generators.generators_file([g] * 17, names, faults, "/* cmd */", signals)


@pytest.mark.skipif(shutil.which("cmake") is None, reason="no cmake")
def test_cmake_options_take_the_defaults(repo: Path, tmp_path: Path) -> None:
    """fw/CMakeLists.txt reads the generated header: one cache option per capacity, with its default."""
    subprocess.run(["cmake", "-S", str(repo), "-B", str(tmp_path), "-DFDI_BUILD_TESTS=OFF", "-DFDI_BUILD_BENCH=OFF"],
                   check=True, capture_output=True)
    cache = (tmp_path / "CMakeCache.txt").read_text(encoding="utf-8")
    for c in CAPACITIES:
        assert f"\n{c.macro}:STRING={c.default}\n" in cache, c.macro


def test_the_command_writes_the_header(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from fdi_analysis.export.capacity import main

    out = tmp_path / "sub" / "fdi_capacity.h"
    assert main(["--out", str(out)]) == 0
    assert out.read_text(encoding="utf-8") == render_header() and str(out) in capsys.readouterr().out
