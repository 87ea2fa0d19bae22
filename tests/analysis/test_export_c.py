"""The exported C diagnosis table: deterministic, up to date in fw/generated, accepted by fdi_table_check."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from fdi_analysis.cli_export import generate
from fdi_analysis.export_c import KNOWN_GENERATORS, Thresholds, render, write
from fdi_analysis.fault_matrix import Candidate
from fdi_analysis.model_loader import load_model

MODEL = Path("analysis/models/romo_grouped.toml")
THRESHOLDS = Path("analysis/models/romo_thresholds.toml")
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


@pytest.fixture(scope="module")
def generated(repo: Path) -> tuple[str, str]:
    import os

    cwd = os.getcwd()
    os.chdir(repo)
    try:
        return generate(MODEL, THRESHOLDS, OUT, NAME, workers=2, progress=False)
    finally:
        os.chdir(cwd)


def test_committed_table_is_up_to_date(repo: Path, generated: tuple[str, str]) -> None:
    header, source = generated
    h, c = repo / OUT / f"{NAME}.h", repo / OUT / f"{NAME}.c"
    assert h.is_file() and c.is_file(), "fw/generated is missing: run scripts/generate.sh"
    assert h.read_text() == header, "fw/generated/fdi_romo_table.h is stale: run scripts/generate.sh"
    assert c.read_text() == source, "fw/generated/fdi_romo_table.c is stale: run scripts/generate.sh"


def compile_and_check(repo: Path, folder: Path) -> str:
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler")
    main = folder / "main.c"
    main.write_text(CHECK_MAIN)
    exe = folder / "check"
    flags = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wdouble-promotion", "-Werror"]
    subprocess.run([cc, *flags, f"-I{repo / 'fw/include'}", f"-I{folder}", str(main), str(folder / f"{NAME}.c"),
                    *sorted(str(p) for p in (repo / "fw/src").glob("*.c")), "-lm", "-o", str(exe)], check=True)
    res = subprocess.run([str(exe)], capture_output=True, text=True)
    assert res.returncode == 0, f"fdi_table_check rejected the table: {res.stdout}"
    return res.stdout


def test_generated_table_compiles_and_passes_the_firmware_check(
    repo: Path, generated: tuple[str, str], tmp_path: Path
) -> None:
    write(tmp_path, NAME, *generated)
    status, n_tests, n_faults = compile_and_check(repo, tmp_path).split()
    assert status == "0" and int(n_faults) == 25 and 1 <= int(n_tests) <= 32
    # every test whose MSO is one of the hand-written kinematic generators is exported with it, the others
    # as FDI_GEN_NONE (generated generators come with the residual generation)
    kinds = re.findall(r"^    \{\d+U, (FDI_GEN_\w+),", generated[1], flags=re.M)
    eq_block = generated[1].split(f"{NAME}_equations")[1].split("};")[0]
    eq_sets = [frozenset(q.split()) for q in re.findall(r'"([^"]*)"', eq_block)]
    assert len(kinds) == len(eq_sets) == int(n_tests)
    for kind, eqs in zip(kinds, eq_sets, strict=True):
        assert kind == KNOWN_GENERATORS.get(eqs, "FDI_GEN_NONE")


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
