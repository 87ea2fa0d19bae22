"""The notebook API (`fdi_analysis.api`, re-exported by the package): each method against the module it wraps,
on shipped models, FDT JSON and matrices; plots into given axes without a backend forced at import; the example
script of examples/ runs."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from msos_bruteforce import all_msos

import fdi_analysis as fa
from fdi_analysis import mso
from fdi_analysis.dm import dulmage_mendelsohn
from fdi_analysis.isolability import isolability
from fdi_analysis.model_loader import export_fdt_json, load_model
from fdi_analysis.selection import reaches_same_matrix
from fdi_analysis.selection.candidates import mso_candidates

REPO = Path(__file__).resolve().parents[2]
CHAIN = {
    "X": [[1, 1, 0], [0, 1, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
    "F": [[1, 0, 0], [0, 1, 0], [0, 0, 0], [0, 0, 0], [0, 0, 1]],
    "equations": ["e1", "e2", "m1", "m2", "m3"],
    "faults": ["fa", "fb", "fc"],
}


def _clean_env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    env["PYTHONPATH"] = os.pathsep.join([str(REPO / "analysis"), str(REPO / "host_tools")])
    return env


def test_import_is_light_and_the_api_loads_on_first_use() -> None:
    code = ("import sys, fdi_analysis as fa; before = {m for m in ('numpy', 'sympy', 'matplotlib', 'fdi_analysis.api',"
            " 'importlib.metadata') if m in sys.modules}; fa.DiagnosisModel; print(sorted(before), "
            "'fdi_analysis.api' in sys.modules, fa.__version__)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=_clean_env())
    before, loaded, version = out.stdout.rsplit(" ", 2)
    assert before == "[]" and loaded == "True"
    assert version.strip() == (REPO / "VERSION").read_text(encoding="utf-8").strip()
    with pytest.raises(AttributeError):
        _ = fa.NoSuchName


def test_a_shipped_model_by_name_is_the_file(models_dir: Path) -> None:
    by_name = fa.DiagnosisModel.load("three_tank")
    by_path = fa.DiagnosisModel.load(models_dir / "three_tank.toml")
    assert by_name.model.source == by_path.model.source == (models_dir / "three_tank.toml").resolve()
    assert by_name.equations == by_path.equations and len(by_name.faults) == 10
    with pytest.raises(ValueError, match="no_such_model"):
        fa.DiagnosisModel.load("no_such_model")


def test_dm_mtes_and_isolability_are_those_of_the_modules() -> None:
    m = fa.DiagnosisModel.load("three_tank")
    st = m.structure
    d = m.dm()
    ref = dulmage_mendelsohn(st.X)
    assert d.redundancy == ref.redundancy == 3
    assert d.overdetermined == tuple(st.equations[i] for i in ref.plus_eqs)
    assert {e for eqs, _ in d.just_determined for e in eqs} == {st.equations[i] for i in ref.zero_eqs}
    iso, iso_ref = m.isolability(), isolability(st)
    assert np.array_equal(iso.isolable, iso_ref.isolable)
    assert iso.classes == tuple(tuple(st.faults[i] for i in c) for c in iso_ref.classes)
    assert iso.non_isolable_pairs() == [("fP", "fL1"), ("fL3", "fC3")]
    mt = m.mtes()
    assert {t.mask for t in mt} == {t.equations for t in mso.mtes(st).mtes}
    assert all(set(t.faults) == {st.faults[k] for k in mso.bits(s.faults)}
               for t, s in zip(mt, mso.mtes(st).mtes, strict=True))


def test_msos_stream_every_mso_set_once() -> None:
    m = fa.DiagnosisModel.from_matrices(**CHAIN, name="chain")
    got = list(m.msos())
    brute = all_msos(m.structure)
    assert {frozenset(m.equations.index(e) for e in t.equations) for t in got} == brute and len(got) == len(brute)
    for t in got:
        assert t.cost == len(t.equations) - 1
        assert set(t.faults) == {f for f, row in zip(CHAIN["faults"], np.array(CHAIN["F"]).T, strict=True)
                                 if any(row[m.equations.index(e)] for e in t.equations)}
    tank = fa.DiagnosisModel.load("three_tank")
    assert sum(1 for _ in tank.msos()) == tank.mso_summary(workers=1).count == len(all_msos(tank.structure))


def test_fdt_json_loads_as_the_same_structure(tmp_path: Path, models_dir: Path) -> None:
    src = load_model(models_dir / "three_tank.toml")
    export_fdt_json(src, tmp_path / "tank.json")
    a, b = fa.DiagnosisModel(src), fa.DiagnosisModel.load(tmp_path / "tank.json")
    assert a.equations == b.equations and a.faults == b.faults
    assert np.array_equal(a.isolability().isolable, b.isolability().isolable)
    assert {t.mask for t in a.msos()} == {t.mask for t in b.msos()}
    with pytest.raises(fa.ApiError, match="structure only"):
        b.export_c(tmp_path / "gen", "romo_thresholds")


def test_select_is_the_optimal_selection_of_the_candidates() -> None:
    m = fa.DiagnosisModel.load("three_tank")
    sel = m.select("B")
    _, cands = mso_candidates(m.structure, workers=1, progress=False)
    assert sel.proven and sel.kind == "optimal" and sel.candidates == len(cands)
    assert sel.cost == sum(t.cost for t in sel.tests) == sel.selection.total_cost
    assert reaches_same_matrix(sel.selection, cands, len(m.faults))
    assert np.array_equal(m.fault_matrix(sel.tests, "B"), m.fault_matrix(
        [m._test_set(c.equations, c.faults, c.cost) for c in cands], "B"))
    assert sel.signature_matrix().shape == (len(sel.tests), len(m.faults))
    greedy = m.select("A", optimal=False)
    assert greedy.kind == "greedy" and len(greedy.tests) >= len(m.select("A").tests)
    with pytest.raises(fa.ApiError):
        m.select("C")


def test_plots_draw_into_the_given_axes() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    m = fa.DiagnosisModel.load("three_tank")
    fig, (a1, a2) = plt.subplots(1, 2)
    assert m.isolability().plot(ax=a1) is fig and a1.images
    assert m.select("B").plot(ax=a2) is fig and a2.collections
    own = m.plot_isolability()
    assert own is not fig and own.axes
    assert len(m.plot_dm().axes) == 1  # the faults are columns right of the unknowns
    plt.close("all")


def test_no_plot_module_forces_a_backend_at_import() -> None:
    code = ("import matplotlib, fdi_analysis.plots, fdi_analysis.api, fdi_host.sim.plots, fdi_host.monitor.report, "
            "fdi_host.paper.fig6, fdi_host.replay, fdi_host.cli; print(matplotlib.rcParams._get_backend_or_none())")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=_clean_env())
    assert out.stdout.strip() == "None", out.stdout  # still matplotlib's automatic choice


def test_the_example_runs(tmp_path: Path) -> None:
    out = subprocess.run([sys.executable, str(REPO / "examples" / "api_tour.py"), str(tmp_path / "ex")], cwd=tmp_path,
                         capture_output=True, text=True, timeout=300, env=_clean_env())
    assert out.returncode == 0, out.stderr
    assert "1,801,605 MSO sets" in out.stdout and "optimal selection (method B): 6 tests, 110 unknowns" in out.stdout
    assert (tmp_path / "ex" / "api_tour.png").stat().st_size > 10_000
    assert "chain" in out.stdout and "3 MSO sets" in out.stdout


def test_export_c_writes_what_the_export_generates(tmp_path: Path, models_dir: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """The wrapper around `fdi-analyze export-c`'s generation (tested in test_export_c.py): the model's file, the
    shipped thresholds file by name, every generated file written."""
    from fdi_analysis.cli import export as cli_export

    calls = []

    def fake(model: Path, thresholds: Path, out: Path, name: str, *rest: object, **options: object) -> dict[str, str]:
        calls.append((model, thresholds, out, name, rest, options))
        return {f"{name}.h": "/* h */\n", f"{name}.c": "/* c */\n"}

    monkeypatch.setattr(cli_export, "generate_all", fake)
    res = fa.DiagnosisModel.load("romo_grouped").export_c(tmp_path / "gen", "romo_thresholds", name="t")
    assert calls[0][:4] == ((models_dir / "romo_grouped.toml").resolve(), models_dir / "romo_thresholds.toml",
                            tmp_path / "gen", "t")
    assert calls[0][5] == {"uncalibrated": False}  # refused unless asked: export_c(..., uncalibrated=True)
    assert res.files == (tmp_path / "gen" / "t.h", tmp_path / "gen" / "t.c")
    assert (tmp_path / "gen" / "t.c").read_text(encoding="utf-8") == "/* c */\n"
