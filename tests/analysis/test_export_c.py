"""The exported C diagnosis table: deterministic, up to date in fw/generated, accepted by fdi_table_check."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from fdi_analysis.export.table import render, write
from fdi_analysis.export.thresholds import Thresholds
from fdi_analysis.fault_matrix import Candidate
from fdi_analysis.model_loader import load_model

MODEL = Path("analysis/models/romo_grouped.toml")
THRESHOLDS = Path("analysis/models/romo_thresholds.toml")
SIZES = Path("host_tools/scenarios/fault_sizes.toml")
OUT = Path("fw/generated")
NAME = "fdi_romo_table"

CHECK_MAIN = """
#include <stdio.h>
#include "fdi_romo_table.h"
int main(void) {
    fdi_status_t st = fdi_table_check(&fdi_romo_table);
    printf("%d %u %u\\n", (int)st, (unsigned)fdi_romo_table.n_tests, (unsigned)fdi_romo_table.n_faults);
    return (int)st;
}
"""


GENERATORS = "fdi_romo_generators"


@pytest.fixture(scope="module")
def generated_files(repo: Path, tmp_path_factory: pytest.TempPathFactory,
                    other_fp_path: Callable[[list[str]], subprocess.CompletedProcess[str]]) -> dict[str, str]:
    """The table and generators as `scripts/generate.sh` writes them, computed in another process on another
    floating-point path (another OpenBLAS kernel and thread count, no numpy SIMD): they must equal the
    committed files byte for byte on any machine."""
    out = tmp_path_factory.mktemp("export")
    res = other_fp_path([sys.executable, "-m", "fdi_analysis.cli", "export-c", str(MODEL), "--thresholds",
                         str(THRESHOLDS), "--fault-sizes", str(SIZES), "--out", str(out), "--no-progress"])
    assert res.returncode == 0, res.stderr
    texts = {p.name: p.read_text(encoding="utf-8") for p in sorted(out.iterdir())}
    # the banner names the command as generate.sh runs it (--out fw/generated)
    return {name: text.replace(f"--out {out.as_posix()}", f"--out {OUT.as_posix()}") for name, text in texts.items()}


@pytest.fixture(scope="module")
def generated(generated_files: dict[str, str]) -> tuple[str, str]:
    return generated_files[f"{NAME}.h"], generated_files[f"{NAME}.c"]


def test_committed_table_is_up_to_date(repo: Path, generated_files: dict[str, str]) -> None:
    assert set(generated_files) == {f"{NAME}.h", f"{NAME}.c", f"{GENERATORS}.h", f"{GENERATORS}.c"}
    for fname, text in generated_files.items():
        path = repo / OUT / fname
        assert path.is_file(), f"fw/generated/{fname} is missing: run scripts/generate.sh"
        assert path.read_text() == text, f"fw/generated/{fname} is stale: run scripts/generate.sh"


def compile_and_check(repo: Path, folder: Path) -> str:
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler")
    main = folder / "main.c"
    main.write_text(CHECK_MAIN)
    exe = folder / "check"
    flags = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wdouble-promotion", "-Werror"]
    gens = folder / f"{GENERATORS}.c"
    if not gens.is_file():
        gens = repo / OUT / f"{GENERATORS}.c"  # the table alone links against the committed generators
    includes = [f"-I{repo / 'fw/include'}", f"-I{repo / 'fw/src'}", f"-I{folder}", f"-I{gens.parent}",
                f"-I{repo / OUT}"]  # the kinematic table's calibration header (fdi_kin_calibration.h)
    subprocess.run([cc, *flags, *includes, str(main),
                    str(folder / f"{NAME}.c"), str(gens), *sorted(str(p) for p in (repo / "fw/src").glob("*.c")),
                    "-lm", "-o", str(exe)], check=True)
    res = subprocess.run([str(exe)], capture_output=True, text=True)
    assert res.returncode == 0, f"fdi_table_check rejected the table: {res.stdout}"
    return res.stdout


def test_generated_table_compiles_and_passes_the_firmware_check(
    repo: Path, generated: tuple[str, str], generated_files: dict[str, str], tmp_path: Path
) -> None:
    for fname, text in generated_files.items():
        (tmp_path / fname).write_text(text)
    status, n_tests, n_faults = compile_and_check(repo, tmp_path).split()
    assert status == "0" and int(n_faults) == 25 and 1 <= int(n_tests) <= 32
    # every selected test runs its generated generator, slots in test order (fw/generated/fdi_romo_generators.c)
    kinds = re.findall(r"^    \{\d+U, (FDI_GEN_\w+),", generated[1], flags=re.M)
    assert kinds == [f"FDI_GEN_GENERATED_{k + 1}" for k in range(int(n_tests))]
    gens_c = generated_files[f"{GENERATORS}.c"]
    assert len(re.findall(r"^static fdi_status_t gen_\d+\(", gens_c, flags=re.M)) == int(n_tests)


def test_render_is_deterministic_and_rejects_bad_selections(repo: Path, tmp_path: Path) -> None:
    model = load_model(repo / "analysis/models/romo_quasistatic.toml")
    st = model.structure()
    eqs = ["K1", "D1", "S1", "S3", "S4", "S5"]
    mask = sum(1 << st.equations.index(e) for e in eqs)
    faults = sum(1 << st.faults.index(f) for f in ("f1", "f3", "f4", "f5"))
    tests = [Candidate(mask, faults, 5, "MSO1")]
    th = Thresholds.load(repo / THRESHOLDS)
    a = render(model, tests, th, NAME, "cmd")
    assert a == render(model, tests, th, NAME, "cmd")
    assert "FDI_GEN_KIN_X_DERIV" in a[1] and "FDI_SIGM_VY_M" in a[1]
    write(tmp_path, NAME, *a)
    assert compile_and_check(repo, tmp_path).split()[0] == "0"
    with pytest.raises(ValueError, match=r"1\.\.32"):
        render(model, [], th, NAME, "cmd")
