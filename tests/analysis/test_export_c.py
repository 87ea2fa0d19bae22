"""The exported C of the ROMO vehicle target (table, generators, signals): deterministic, up to date in
fw/vehicles/romo/generated, accepted by fdi_table_check on the generic core; rendered from named templates."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from fdi_analysis.export import generators as emit_generators
from fdi_analysis.export import signals as emit_signals
from fdi_analysis.export import table as emit_table
from fdi_analysis.export.c_names import VehicleNames
from fdi_analysis.export.table import render, write
from fdi_analysis.export.thresholds import Thresholds
from fdi_analysis.fault_matrix import Candidate
from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.causality import synthesize

MODEL = Path("analysis/models/romo_grouped.toml")
THRESHOLDS = Path("analysis/models/romo_thresholds.toml")
SIZES = Path("host_tools/scenarios/fault_sizes.toml")
OUT = Path("fw/vehicles/romo/generated")
NAME = "fdi_romo_table"
SIGNALS = "fdi_romo_signals"

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
    # the banner names the command as generate.sh runs it (--out fw/vehicles/romo/generated)
    return {name: text.replace(f"--out {out.as_posix()}", f"--out {OUT.as_posix()}") for name, text in texts.items()}


@pytest.fixture(scope="module")
def generated(generated_files: dict[str, str]) -> tuple[str, str]:
    return generated_files[f"{NAME}.h"], generated_files[f"{NAME}.c"]


def test_committed_table_is_up_to_date(repo: Path, generated_files: dict[str, str]) -> None:
    assert set(generated_files) == {f"{n}.{x}" for n in (NAME, GENERATORS, SIGNALS) for x in "hc"}
    for fname, text in generated_files.items():
        path = repo / OUT / fname
        assert path.is_file(), f"{OUT / fname} is missing: run scripts/generate.sh"
        assert path.read_text() == text, f"{OUT / fname} is stale: run scripts/generate.sh"


def compile_and_check(repo: Path, folder: Path) -> str:
    """Build the table of `folder` (with its generators and signals, else the committed ones) and the ROMO target's
    hand-written sources on the generic core, and run fdi_table_check."""
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler")
    main = folder / "main.c"
    main.write_text(CHECK_MAIN)
    exe = folder / "check"
    flags = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wdouble-promotion", "-Werror"]
    romo = repo / "fw/vehicles/romo"
    sources = [folder / f"{n}.c" if (folder / f"{n}.c").is_file() else repo / OUT / f"{n}.c"
               for n in (NAME, GENERATORS, SIGNALS)]
    includes = [f"-I{repo / 'fw/include'}", f"-I{folder}", f"-I{repo / OUT}", f"-I{romo / 'include'}"]
    subprocess.run([cc, *flags, *includes, str(main), *map(str, sources),
                    *sorted(str(p) for p in (repo / "fw/src").glob("*.c")),
                    *sorted(str(p) for p in (romo / "src").glob("fdi_romo_kin.c")),
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
    # every selected test runs its generated generator, descriptors in test order (fdi_romo_generators[k])
    kinds = re.findall(r"^    \{\.gen = (&?\w+(?:\[\d+\])?),", generated[1], flags=re.M)
    assert kinds == [f"&fdi_romo_generators[{k}]" for k in range(int(n_tests))]
    gens_c = generated_files[f"{GENERATORS}.c"]
    # one generator set: one step for all slots, one block per slot, one descriptor per slot pointing to the set
    assert len(re.findall(r"^static void romo_gen_step\(", gens_c, flags=re.M)) == 2  # declaration, definition
    assert len(re.findall(r"^    if \(\(run & 0x[0-9A-F]{8}U\) != 0U\) /\* MSO", gens_c, flags=re.M)) == int(n_tests)
    # ... with its rate gains, its estimable quantities (every ROMO test has some) and its range (the tyre-law tests)
    descriptor = (r"&fdi_romo_gen_set, \d+U,\n     FDI_GEN_SENS_MASK\(0x[0-9A-F]{8}U\), (NULL|&romo_rate_gain\[\d+\]), "
                  r"[1-3]U, romo_est_\d+, (NULL|romo_gen_\d+_in_range)\}")
    assert len(re.findall(descriptor, gens_c)) == int(n_tests)
    # the rate gains: the vx and vy offsets in the a_x and a_y kinematics (MSO1, MSO2), each -1
    assert "static const float romo_rate_gain[2] = {-1.0f, -1.0f};" in gens_c
    # shared terms once: each steering angle's sin and cos evaluated once per step (the library's float-only ones,
    # the same bits on every target), no powf, no fmaxf, no double
    for f in ("fdi_gen_sin", "fdi_gen_cos"):
        calls = re.findall(rf"{f}\(b\[\d+\]\.x1\)", gens_c)
        assert len(calls) == len(set(calls)) == 4  # the four steering angles
    assert "sinf(" not in gens_c and "cosf(" not in gens_c
    assert "powf(" not in gens_c and "fmaxf(" not in gens_c and "double" not in gens_c


def test_render_is_deterministic_and_rejects_bad_selections(repo: Path, tmp_path: Path) -> None:
    """The kinematic MSO1 as a one-test table of a vehicle target of its own ("kin1"): table, generators and
    signals rendered twice alike, and accepted by fdi_table_check; no test or too many are refused."""
    model = load_model(repo / "analysis/models/romo_quasistatic.toml")
    st = model.structure()
    eqs = ["K1", "D1", "S1", "S3", "S4", "S5"]
    mask = sum(1 << st.equations.index(e) for e in eqs)
    faults = sum(1 << st.faults.index(f) for f in ("f1", "f3", "f4", "f5"))
    tests = [Candidate(mask, faults, 5, "MSO1")]
    th = Thresholds.load(repo / THRESHOLDS)
    names = VehicleNames.of_table("fdi_kin1_table")
    a = render(model, tests, th, names.table, "cmd")
    assert a == render(model, tests, th, names.table, "cmd")
    assert "&fdi_kin1_generators[0]" in a[1] and "KIN1_SIGM_VY_M" in a[1]
    g = synthesize(model, eqs, "MSO1")
    gens = emit_generators.render(emit_generators.generators_file([g], names, [f.name for f in model.faults],
                                                                  "/* cmd */", [k.name for k in model.knowns]))
    sigs = emit_signals.render(emit_signals.signals_file(model, names, "/* cmd */"))
    write(tmp_path, names.table, *a)
    write(tmp_path, names.generators, *gens)
    write(tmp_path, names.signals, *sigs)
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler")
    main = tmp_path / "main.c"
    main.write_text(CHECK_MAIN.replace("fdi_romo_table", names.table))
    exe = tmp_path / "check"
    subprocess.run([cc, "-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wdouble-promotion", "-Werror",
                    f"-I{repo / 'fw/include'}", f"-I{tmp_path}", str(main),
                    *(str(tmp_path / f"{n}.c") for n in (names.table, names.generators, names.signals)),
                    *sorted(str(p) for p in (repo / "fw/src").glob("*.c")), "-lm", "-o", str(exe)], check=True)
    res = subprocess.run([str(exe)], capture_output=True, text=True)
    assert res.returncode == 0 and res.stdout.split()[0] == "0", res.stdout
    with pytest.raises(ValueError, match=r"1\.\.32"):
        render(model, [], th, NAME, "cmd")


def test_c_text_comes_from_named_templates() -> None:
    """Computed first, rendered last: each emitter keeps its C text in module-level templates and its rendering
    functions stay short (no long f-string function)."""
    import ast
    import inspect

    for mod in (emit_table, emit_generators, emit_signals):
        templates = [n for n, v in vars(mod).items() if n.endswith("_FMT")]
        assert len(templates) >= 3, mod.__name__
        tree = ast.parse(inspect.getsource(mod))
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef):
                assert node.end_lineno is not None and node.end_lineno - node.lineno < 60, \
                    f"{mod.__name__}.{node.name} has {node.end_lineno - node.lineno} lines"


def test_sensitivities_reuse_the_residuals_temporaries() -> None:
    """The sensitivity blocks read the residual's temporaries wherever a subexpression equals one: a flat sum that
    a temporary over an earlier temporary stands for, its negation, a part of a longer sum, a call on it; the
    rewritten expressions keep their value, and an expression that holds none is left as it is."""
    import sympy

    a, b, x, y = sympy.symbols("a b x y")
    t1, t2, t3 = sympy.symbols("t1 t2 t3")
    temps = [emit_generators._Temp(t1, -0.66 * a + b), emit_generators._Temp(t2, t1 + 0.66 * x),
             emit_generators._Temp(t3, sympy.sqrt(t2))]
    flat = b - 0.66 * a + 0.66 * x  # t2 written out: sympy flattened t1 into it
    exprs = [flat * y, -flat, flat + 5 * y, sympy.sqrt(flat) * y, a * y + 2]
    got = emit_generators._reusing(exprs, temps)
    assert got == [t2 * y, -t2, t2 + 5 * y, t3 * y, a * y + 2]
    v2 = (t1 + 0.66 * x).subs(t1, -0.66 * a + b)
    value = {t2: v2, t3: sympy.sqrt(v2)}
    for e, g in zip(exprs, got, strict=True):
        assert sympy.simplify(g.xreplace(value) - e) == 0


def test_the_calibrated_envelope_goes_into_the_table(repo: Path, generated: tuple[str, str], tmp_path: Path) -> None:
    """[envelope] of the thresholds file with the limits `fdi-tune calibrate` wrote: the table carries them (its
    signals, votes, limits) and points to them; an envelope without calibrated limits, or on a signal the model
    does not measure, is refused; a malformed [envelope] names what is wrong."""
    import dataclasses

    from fdi_analysis.export.c_expr import c_float
    from fdi_analysis.export.thresholds import Envelope

    th = Thresholds.load(repo / THRESHOLDS)
    env = th.envelope
    assert env is not None and env.votes >= 2 and set(env.limits) == set(env.signals)
    source = generated[1]
    assert "    &romo_envelope,\n};" in source
    assert f"{len(env.signals)}U, {env.votes}U, romo_envelope_signals, romo_envelope_limits" in source
    assert "{" + ", ".join(c_float(env.limits[s]) for s in env.signals) + "}" in source
    assert "{" + ", ".join(f"ROMO_SIG_{s.upper()}" for s in env.signals) + "}" in source
    model = load_model(repo / MODEL)
    st = model.structure()
    tests = [Candidate(sum(1 << st.equations.index(e) for e in ["K1", "D1", "S1", "S3", "S4", "S5"]),
                       sum(1 << st.faults.index(f) for f in ("f1", "f3", "f4", "f5")), 5, "MSO1")]
    uncalibrated = dataclasses.replace(th, envelope=dataclasses.replace(env, limits={}))
    with pytest.raises(emit_table.ExportError, match="fdi-tune calibrate"):
        render(model, tests, uncalibrated, NAME, "cmd")
    alien = dataclasses.replace(th, envelope=Envelope(("nonsense_m",), 1, 1.25, {"nonsense_m": 1.0}))
    with pytest.raises(emit_table.ExportError, match="nonsense_m not measured signals"):
        render(model, tests, alien, NAME, "cmd")
    none = dataclasses.replace(th, envelope=None)
    assert "    NULL,\n};" in render(model, tests, none, NAME, "cmd")[1]
    for bad, what in (({"signals": [], "votes": 1, "margin": 1.25}, "signals"),
                      ({"signals": ["a", "a"], "votes": 1, "margin": 1.25}, "signals"),
                      ({"signals": ["a", "b"], "votes": 3, "margin": 1.25}, "votes"),
                      ({"signals": ["a"], "votes": 1, "margin": 0.5}, "margin")):
        with pytest.raises(ValueError, match=rf"\[envelope\] {what}"):
            Envelope.of(bad, {})
