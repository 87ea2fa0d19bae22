"""The notebook side of the analysis API (issue 47): short reprs, labelled HTML tables, pandas DataFrames with the
names as labels, one-way isolability (API and `fdi-analyze report`), `ax=` on every plot, and a clear error without
pandas. Names are arbitrary identifiers: the small model names its faults neither ``f<number>`` nor HTML-safe."""

from __future__ import annotations

import html
import inspect
import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest

import fdi_analysis as fa
from fdi_analysis.cli import main
from fdi_analysis.tables import NO_FAULT, require_pandas

ROMO_MODELS = ("romo_quasistatic", "romo_grouped", "romo_full_vertical")
SHORT = 300  # characters: a repr is a line or a few
# e1..m3 over x1..x3; fault "q&r" in e2 and m1: isolable one way only from the other two
SMALL = {
    "X": [[1, 1, 0], [0, 1, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
    "F": [[1, 0, 0], [0, 1, 0], [0, 1, 0], [0, 0, 0], [0, 0, 1]],
    "faults": ["leak_in", "q&r", "Pump2"],
    "name": "small<model>",
}


@pytest.fixture(scope="module")
def grouped() -> fa.DiagnosisModel:
    return fa.DiagnosisModel.load("romo_grouped")


@pytest.fixture(scope="module")
def selection(grouped: fa.DiagnosisModel) -> fa.TestSelection:
    return grouped.select("B", time_limit_s=60, workers=1)


def test_reprs_are_short_on_every_romo_model(grouped: fa.DiagnosisModel, selection: fa.TestSelection) -> None:
    for name in ROMO_MODELS:
        m = fa.DiagnosisModel.load(name)
        for obj in (m, m.dm(), m.isolability(), m.summary()):
            text = repr(obj)
            assert len(text) < SHORT and "\n" not in text and name in repr(m), (name, text[:400])
    summary = grouped.mso_summary(workers=1)
    for obj in (selection, *selection.tests, summary):
        assert len(repr(obj)) < SHORT, repr(obj)[:400]
    assert "1,801,605 MSO sets" in repr(summary)
    assert repr(grouped.isolability()).startswith("IsolabilityAnalysis(25 faults, 25 detectable, 21 classes")


def test_one_way_pairs_follow_from_the_mso_signatures(grouped: fa.DiagnosisModel) -> None:
    """Derived independently of the isolability matrix: fault a cannot be isolated from fault b when every MSO set
    that reacts to a also reacts to b (no test can see a and not b)."""
    iso = grouped.isolability()
    faults = grouped.faults
    summary = grouped.mso_summary(workers=1)
    sigs = [e.faults for e in summary.signatures]
    seen = {(a, b): any(s >> a & 1 and not s >> b & 1 for s in sigs)
            for a in range(len(faults)) for b in range(len(faults)) if a != b}
    assert all(any(s >> a & 1 for s in sigs) for a in range(len(faults)))  # every fault detectable
    one_way = [(faults[a], faults[b]) for (a, b), sees in seen.items() if not sees and seen[b, a]]
    both = {tuple(sorted((faults[a], faults[b]))) for (a, b), sees in seen.items() if not sees and not seen[b, a]}
    assert sorted(iso.one_way_pairs()) == sorted(one_way)
    assert {tuple(sorted(p)) for p in iso.non_isolable_pairs()} == both
    # the example: f10 cannot be isolated from f6, f6 can be isolated from f10
    assert ("f10", "f6") in iso.one_way_pairs() and ("f6", "f10") not in iso.one_way_pairs()
    k10, k6 = faults.index("f10"), faults.index("f6")
    assert not iso.isolable[k10, k6] and iso.isolable[k6, k10]
    assert not set(iso.one_way_pairs()) & {p for q in iso.non_isolable_pairs() for p in (q, q[::-1])}


def test_one_way_pairs_of_a_small_model_with_any_names() -> None:
    iso = fa.DiagnosisModel.from_matrices(**SMALL).isolability()
    assert iso.one_way_pairs() == [("leak_in", "q&r"), ("Pump2", "q&r")]
    assert iso.non_isolable_pairs() == []
    assert "2 pairs isolable one way only" in repr(iso)


def test_report_lists_the_one_way_pairs(models_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["report", str(models_dir / "romo_grouped.toml"), "-o", str(tmp_path), "--no-plots"]) == 0
    out = capsys.readouterr().out
    expected = fa.DiagnosisModel.load("romo_grouped").isolability().one_way_pairs()
    line = next(x for x in out.splitlines() if x.startswith("isolable one way only"))
    assert f"{len(expected)} pairs" in line and "f10 -> f6" in line
    data = json.loads((tmp_path / "report.json").read_text(encoding="utf-8"))
    assert [tuple(p) for p in data["faults"]["one_way_pairs"]] == expected
    md = (tmp_path / "report.md").read_text(encoding="utf-8")
    assert "isolable one way only" in md and "f10 -> f6" in md
    assert main(["report", str(models_dir / "romo_quasistatic.toml"), "-o", str(tmp_path / "q"), "--no-plots"]) == 0
    assert json.loads((tmp_path / "q" / "report.json").read_text(encoding="utf-8"))["faults"]["one_way_pairs"] == []


def test_html_tables_carry_the_names() -> None:
    m = fa.DiagnosisModel.from_matrices(**SMALL)
    iso = m.isolability()
    sel = m.select("B")
    names = [html.escape(f) for f in SMALL["faults"]]
    assert "q&amp;r" in names
    for obj in (m, iso, sel):
        text = obj._repr_html_()
        assert text.startswith("<table") and text.count("<table") == text.count("</table>")
        assert all(re.search(f"<th[^>]*>{re.escape(n)}</th>", text) for n in names), type(obj).__name__  # labels
        assert "q&r" not in text and "small<model>" not in text  # escaped
    iso_html = iso._repr_html_()
    assert all(f'<th style="text-align: left">{n}</th>' in iso_html and f"<th>{n}</th>" in iso_html
               for n in names)  # row and column labels
    assert "leak_in -&gt; q&amp;r" in iso_html  # the one-way pairs in the caption
    assert all(f'<th style="text-align: left">{t.label}</th>' in sel._repr_html_() for t in sel.tests)
    dm = m.dm()._repr_html_()
    assert "M+ (overdetermined)" in dm and "e1" in dm
    mso_html = m.mso_summary(workers=1)._repr_html_()
    assert "3 MSO sets" in mso_html and "<th>equations</th>" in mso_html


def test_dataframes_are_labelled(grouped: fa.DiagnosisModel, selection: fa.TestSelection) -> None:
    iso = grouped.isolability()
    df = iso.to_dataframe()
    assert list(df.index) == list(df.columns) == list(grouped.faults)
    assert df.index.name == "fault" and df.columns.name == "isolable from"
    assert np.array_equal(df.to_numpy(), iso.isolable)
    assert not df.loc["f10", "f6"] and df.loc["f6", "f10"]
    fm = grouped.fault_matrix_frame(selection.tests, "B")
    assert list(fm.index) == list(fm.columns) == [NO_FAULT, *grouped.faults]
    assert (fm.index.name, fm.columns.name) == ("occurred", "diagnosed as")
    assert np.array_equal(fm.to_numpy(), grouped.fault_matrix(selection.tests, "B"))
    assert fm.loc[NO_FAULT, NO_FAULT] and fm.loc["f10", "f14"] and not fm.loc["f10", NO_FAULT]
    assert selection.fault_matrix_frame().equals(fm)
    sig = selection.to_dataframe()
    assert list(sig.index) == [t.label for t in selection.tests] and list(sig.columns) == list(grouped.faults)
    assert np.array_equal(sig.to_numpy(), selection.signature_matrix())
    assert grouped.signature_frame(selection.tests).equals(sig)
    for t in selection.tests:
        assert [f for f in grouped.faults if sig.loc[t.label, f]] == list(t.faults)
    table = grouped.mso_summary(workers=1).to_dataframe()
    assert table["MSO sets"].sum() == 1_801_605 and len(table) == 16_635
    first = table.iloc[0]
    assert [f for f in grouped.faults if first[f]] == table.index[0].split(", ")


def test_every_plot_takes_ax(grouped: fa.DiagnosisModel, selection: fa.TestSelection) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    objects = {fa.DiagnosisModel: grouped, fa.IsolabilityAnalysis: grouped.isolability(), fa.TestSelection: selection}
    args = {"plot_fault_matrix": (selection.tests,)}
    called = []
    for cls, obj in objects.items():
        for name, fn in inspect.getmembers(cls, inspect.isfunction):
            if not name.startswith("plot"):
                continue
            assert "ax" in inspect.signature(fn).parameters, f"{cls.__name__}.{name} has no ax="
            fig, ax = plt.subplots()
            assert getattr(obj, name)(*args.get(name, ()), ax=ax) is fig, f"{cls.__name__}.{name}"
            assert ax.collections or ax.images, f"{cls.__name__}.{name} drew nothing into ax"
            assert fig.axes == [ax], f"{cls.__name__}.{name} added axes"
            called.append(f"{cls.__name__}.{name}")
            plt.close(fig)
    assert {"DiagnosisModel.plot_dm", "DiagnosisModel.plot_isolability", "DiagnosisModel.plot_fault_matrix",
            "IsolabilityAnalysis.plot", "TestSelection.plot"} <= set(called)


def test_tables_without_pandas_say_how_to_get_it(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas now raises ImportError
    iso = fa.DiagnosisModel.from_matrices(**SMALL).isolability()
    with pytest.raises(ImportError, match=r"romo-fdi\[notebook\]"):
        iso.to_dataframe()
    with pytest.raises(ImportError, match="pandas"):
        require_pandas()
    assert iso._repr_html_().startswith("<table")  # the HTML needs no pandas
