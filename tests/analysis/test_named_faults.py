"""Names are names (issue 46): a model whose faults and signals are not f<number> (named_tanks.toml here: fuel_flow,
leak_tank1, leak_tank2, leak_tank10, clog_12, ..., sensor_a; pump_cmd, level_a, ...) goes through report, isolability,
select, practical (with a budget), the plots, the tuning's orderings and export-c with every name intact and in the
model's declared order; export-c refuses its uncalibrated table (no [generated] variances) unless asked for one
(--uncalibrated), and then marks it in both files."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import pytest

import fdi_analysis as fa
from fdi_analysis.cli import main as fdi_analyze
from fdi_analysis.export import table as emit_table
from fdi_analysis.export.thresholds import Thresholds
from fdi_analysis.model_loader import load_model
from fdi_analysis.names import in_order
from fdi_analysis.plots import plot_fault_matrix, plot_isolability, plot_selected_faults
from fdi_analysis.selection.practical import CandidateScreen, FaultScreen, Screening
from fdi_analysis.summary import summarize
from fdi_host.tuning.sweep import PairLimit, ScenarioLimit, render_section, write_section

HERE = Path(__file__).parent
MODEL = HERE / "named_tanks.toml"
THRESHOLDS = HERE / "named_tanks_thresholds.toml"
FAULTS = ("fuel_flow", "leak_tank1", "leak_tank2", "leak_tank10", "clog_12", "clog_23", "clog_3", "sensor_a",
          "sensor_b", "sensor_c")
NAME = "fdi_named_tanks_table"
CHOPPED = re.compile(r"\b(uel_flow|eak_tank\d+|ensor_[abc])\b")  # a name with its first letter stripped


def _names_intact(text: str) -> None:
    assert "fuel_flow" in text and "leak_tank10" in text and "sensor_a" in text
    assert CHOPPED.search(text) is None, CHOPPED.search(text)


def test_the_model_declares_its_names_in_an_order_of_its_own() -> None:
    model = load_model(MODEL)
    assert tuple(f.name for f in model.faults) == FAULTS
    assert [k.name for k in model.knowns] == ["pump_cmd", "level_a", "level_b", "level_c"]
    assert in_order(set(FAULTS), FAULTS) == list(FAULTS)
    assert in_order({"sensor_a", "leak_tank10", "leak_tank2", "fuel_flow"}, FAULTS) == [
        "fuel_flow", "leak_tank2", "leak_tank10", "sensor_a"]


def test_report_and_isolability_keep_the_names(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "report"
    assert fdi_analyze(["report", str(MODEL), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "not isolable from each other: fuel_flow, leak_tank1" in text
    assert "not isolable from each other: leak_tank10, clog_3" in text
    _names_intact((out / "report.md").read_text(encoding="utf-8"))
    _names_intact((out / "report.json").read_text(encoding="utf-8"))
    assert (out / "isolability.png").stat().st_size > 0 and (out / "dm.png").stat().st_size > 0
    iso = fa.DiagnosisModel.load(MODEL).isolability()
    assert iso.faults == FAULTS
    assert ("fuel_flow", "leak_tank1") in iso.non_isolable_pairs()
    labels = [t.get_text() for t in plot_isolability(summarize(load_model(MODEL))).axes[0].get_xticklabels()]
    assert labels == list(FAULTS)


def test_select_and_its_plots_keep_the_names(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "select"
    assert fdi_analyze(["select", str(MODEL), "--realizable", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert re.search(r"MSO1 +5 unknowns  faults fuel_flow leak_tank1 clog_12 sensor_a sensor_b", text), text
    md = (out / "selection.md").read_text(encoding="utf-8")
    _names_intact(md)
    assert "| fuel_flow, leak_tank1, clog_12, sensor_a, sensor_b |" in md  # in the model's order, whole
    data = json.loads((out / "selection.json").read_text(encoding="utf-8"))
    assert data["selections"]["optimal B"]["msos"][0]["faults"] == ["fuel_flow", "leak_tank1", "clog_12", "sensor_a",
                                                                   "sensor_b"]
    for png in ("fault_matrix.png", "selected_faults.png"):
        assert (out / png).stat().st_size > 0
    import numpy as np

    fm = np.eye(len(FAULTS) + 1, dtype=bool)
    for fig in (plot_fault_matrix(fm, fm, FAULTS, "named"),
                plot_selected_faults(np.ones((2, len(FAULTS)), dtype=bool), FAULTS, ["1: MSO1", "2: MSO2"], "named")):
        labels = [t.get_text() for t in fig.axes[0].get_xticklabels()]
        assert [x for x in labels if x != "0"] == list(FAULTS)


def _screening(tmp_path: Path) -> Path:
    """Three screened tests of the named model (labels that sort differently as text and as numbers)."""
    share, fnr = {"a": 0.9}, {"a": 20.0}

    def screen(label: str, faults: tuple[str, ...], cost: int) -> CandidateScreen:
        # the signature in reverse: the report must not keep the order it was given in
        return CandidateScreen(label, "e1 e2", faults[::-1], 1.0, 0.0, cost,
                               {f: FaultScreen(share, fnr) for f in faults})

    cands = (screen("MSO2", FAULTS[:4], 10), screen("MSO12", FAULTS[2:], 40), screen("MSO3", FAULTS[7:], 5))
    path = tmp_path / "screening.json"
    Screening("named_tanks", "test", 5.0, 1.5, 0.8, {f: 1.0 for f in FAULTS}, ("a",), cands, 0.27, ()).dump(path)
    return path


def test_practical_and_its_budget_keep_the_names_in_the_model_order(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "practical"
    assert fdi_analyze(["practical", str(MODEL), "--screening", str(_screening(tmp_path)), "-o", str(out),
                        "--budget", "1000"]) == 0
    text = capsys.readouterr().out
    assert text.index("  MSO2 ") < text.index("  MSO12 ")  # natural order of the labels, not MSO12 < MSO2
    assert "faults fuel_flow leak_tank1 leak_tank2 leak_tank10\n" in text
    md = (out / "practical.md").read_text(encoding="utf-8")
    _names_intact(md)
    assert "| MSO2 | 10 | fuel_flow, leak_tank1, leak_tank2, leak_tank10 |" in md
    doc = json.loads((out / "practical.json").read_text(encoding="utf-8"))
    assert doc["tests"][0]["faults"] == list(FAULTS[:4])
    assert (out / "practical_isolability.png").stat().st_size > 0


def test_the_fault_size_tables_follow_the_model_order() -> None:
    """fdi-tune fault-sizes writes [per_test.<fault>] in the model's order (any name; no int(f[1:]))."""
    pairs = [PairLimit(f, "MSO1", 0.3, 0.5, 32.8) for f in ("sensor_a", "leak_tank10", "leak_tank2", "fuel_flow")]
    elsewhere = [ScenarioLimit(f, "MSO1", "b", 2.0, 3.0) for f in ("sensor_b", "clog_3")]
    text = render_section(pairs, "prov", ["MSO1"], "a", elsewhere, ["b"], FAULTS)
    assert re.findall(r"^\[per_test\.(\w+)\]", text, flags=re.M) == ["fuel_flow", "leak_tank2", "leak_tank10",
                                                                    "sensor_a"]
    assert re.findall(r"^\[per_test_scenario\.(\w+)\]", text, flags=re.M) == ["clog_3", "sensor_b"]
    doc = tomllib.loads(write_section("[limits]\n", text))
    assert doc["per_test"]["leak_tank10"]["MSO1"] == 0.5
    # without the model's order: the natural one (leak_tank2 before leak_tank10)
    plain = render_section(pairs, "prov", ["MSO1"])
    assert re.findall(r"^\[per_test\.(\w+)\]", plain, flags=re.M) == ["fuel_flow", "leak_tank2", "leak_tank10",
                                                                     "sensor_a"]


def _export(tmp_path: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "fdi_analysis.cli", "export-c", str(MODEL), "--thresholds",
                           str(THRESHOLDS), "--out", str(tmp_path), "--name", NAME, "--no-progress", *extra],
                          capture_output=True, text=True, timeout=600, check=False)


def test_export_c_refuses_an_uncalibrated_table(tmp_path: Path) -> None:
    res = _export(tmp_path)
    assert res.returncode == 1 and not list(tmp_path.iterdir())
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert lines[0] == (f"fdi-analyze: error: {THRESHOLDS} has no calibrated variance ([generated]) for MSO1, MSO2, "
                        "MSO3, MSO6, MSO9: run fdi-tune calibrate, or export placeholders (1.0) with --uncalibrated")
    # the Python side alike: refused unless asked
    model, th = load_model(MODEL), Thresholds.load(THRESHOLDS)
    from fdi_analysis.fault_matrix import Candidate

    st = model.structure()
    mso1 = ["T1", "V12", "P", "S1", "S2", "D1"]
    test = Candidate(sum(1 << st.equations.index(e) for e in mso1), 0b110010011, 5, "MSO1")
    with pytest.raises(emit_table.ExportError, match="no calibrated variance"):
        emit_table.render(model, [test], th, NAME, "cmd")
    h, c = emit_table.render(model, [test], th, NAME, "cmd", uncalibrated=True)
    assert "UNCALIBRATED" in h and "UNCALIBRATED" in c
    # a test without an on-board generator needs no variance
    assert "UNCALIBRATED" not in emit_table.render(model, [test], th, NAME, "cmd", generated=[False])[0]


def test_export_c_uncalibrated_marks_the_table_and_keeps_the_names(repo: Path, tmp_path: Path) -> None:
    res = _export(tmp_path, "--uncalibrated")
    assert res.returncode == 0, res.stderr
    header = (tmp_path / f"{NAME}.h").read_text(encoding="utf-8")
    source = (tmp_path / f"{NAME}.c").read_text(encoding="utf-8")
    mark = "/* UNCALIBRATED: variances are placeholders (1.0); do not use on a vehicle."
    for text in (header, source):
        assert text.splitlines()[0].endswith("--uncalibrated`. Do not edit: regenerate instead. */")  # the banner
        assert mark in text and "for MSO1, MSO2, MSO3, MSO6, MSO9." in text
    assert header.index(mark) < header.index("#ifndef")  # before anything else a reader meets
    assert source.count(".variance = 1.0f") == 5
    names = re.findall(r'^    "(\w+) ', source, flags=re.M)[:len(FAULTS)]
    assert tuple(names) == FAULTS  # the fault names in the table, whole, in the model's order
    assert re.findall(r"/\* (\w+) \*/$", source, flags=re.M)[:len(FAULTS)] == list(FAULTS)  # signature rows
    signals = (tmp_path / "fdi_named_tanks_signals.h").read_text(encoding="utf-8")
    assert "NAMED_TANKS_SIG_PUMP_CMD" in signals and "NAMED_TANKS_SIG_LEVEL_A" in signals
    # the generated C builds and the firmware's check accepts the table
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler")
    main = tmp_path / "main.c"
    main.write_text(f'#include <stdio.h>\n#include "{NAME}.h"\nint main(void) {{\n'
                    f"    fdi_status_t st = fdi_table_check(&{NAME});\n"
                    f'    printf("%d %u\\n", (int)st, (unsigned){NAME}.n_faults);\n    return (int)st;\n}}\n')
    exe = tmp_path / "check"
    subprocess.run([cc, "-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{repo / 'fw/include'}",
                    f"-I{tmp_path}", str(main), *(str(p) for p in sorted(tmp_path.glob("fdi_named_tanks_*.c"))),
                    *sorted(str(p) for p in (repo / "fw/src").glob("*.c")), "-lm", "-o", str(exe)], check=True)
    run = subprocess.run([str(exe)], capture_output=True, text=True, check=False)
    assert run.returncode == 0 and run.stdout.split() == ["0", str(len(FAULTS))], run.stdout


def test_the_host_names_faults_by_the_table() -> None:
    """The ECU bindings and the quality suite name a fault mask by the table's fault names (bit j = fault j), never
    f<j+1>."""
    from fdi_host.ecu.bindings import EcuResult, TableInfo
    from fdi_host.quality.suite import evaluate_case
    from fdi_host.sim.faults import FaultSpec

    info = TableInfo(name="named_tanks", n_faults=len(FAULTS), fault_names=tuple(f"{f} a description" for f in FAULTS),
                     test_names=("MSO1: T1; V12",), mso_ids=(1,), test_fault_masks=(0x193,), test_input_masks=(0x7,),
                     has_generator=(True,), iso_class=(0x3, 0x3, *(1 << j for j in range(2, len(FAULTS)))), dt=0.01)
    assert info.faults == FAULTS
    assert info.fault_labels(0b1000000101) == ["fuel_flow", "leak_tank2", "sensor_c"]
    step = EcuResult(step=1, t_us=10_000, status=3, validity=0xF, alarm_mask=1, evaluable_mask=1, accused_mask=1,
                     candidates=0b100, class_mask=0b100, n_classes=1, detected=True, isolated=True, iso_class=3,
                     test_status=("alarm",), residuals=(1.0,), ratios=(2.0,), test_names=info.test_names)
    assert step.candidate_labels(info) == ["leak_tank2"]
    final = evaluate_case([step], FaultSpec("f3", 0.0, 1.0), 0.0, 0b100, info.faults)[5]
    assert final == ("leak_tank2",)


def test_the_monitor_scores_and_draws_named_faults(tmp_path: Path) -> None:
    """fdi-monitor's scoring, its --classes file (with the faults' names) and its diagnosis plot: any name."""
    from fdi_host.ecu.records import DiagRecord
    from fdi_host.monitor.cli import read_classes
    from fdi_host.monitor.report import plot_diagnosis
    from fdi_host.monitor.score import FaultWindow, score_run

    path = tmp_path / "classes.json"
    path.write_text(json.dumps({"signature": [0b01, 0b10, 0b01, 0], "test_names": ["MSO1", "MSO2"],
                                "faults": ["fuel_flow", "leak_tank2", "sensor_a", "clog_3"]}), encoding="utf-8")
    tc, _ = read_classes(path)
    assert tc.fault_names(0b0101) == "fuel_flow,sensor_a" and tc.fault_names(0) == "-"
    assert not tc.detectable("clog_3") and tc.bit("sensor_a") == 0b100
    recs = [DiagRecord(k * 0.01, 1 if k >= 20 else 0, 0b0100 if k >= 20 else 0) for k in range(100)]
    s = score_run(recs, [FaultWindow("sensor_a", 0.1, 1.0)], tc).faults[0]
    assert s.verdict == "sensor_a" and s.expected_class == "fuel_flow,sensor_a" and s.isolation_correct is True
    png = plot_diagnosis(tmp_path / "diagnosis.png", recs, [FaultWindow("sensor_a", 0.1, 1.0)], tc)
    assert png is not None and png.stat().st_size > 0
    path.write_text(json.dumps({"signature": [1, 2], "faults": ["fuel_flow"]}), encoding="utf-8")
    with pytest.raises(ValueError, match="'faults' must name every fault"):
        read_classes(path)


def test_signals_need_a_c_macro_of_their_own(tmp_path: Path) -> None:
    """Any identifier is a signal's name, but the generated C needs a macro per signal: two names that differ only
    in case (or one that is not ASCII) are refused with their names, not left to the C compiler."""
    from fdi_analysis.export.c_names import VehicleNames
    from fdi_analysis.export.signals import SignalsError, signals_file

    names = VehicleNames.of_table(NAME)
    assert [s.index_macro for s in signals_file(load_model(MODEL), names, "").signals] == [
        "NAMED_TANKS_SIG_PUMP_CMD", "NAMED_TANKS_SIG_LEVEL_A", "NAMED_TANKS_SIG_LEVEL_B", "NAMED_TANKS_SIG_LEVEL_C"]
    clash = tmp_path / "clash.toml"
    clash.write_text(re.sub(r"\blevel_c\b", "LEVEL_B", MODEL.read_text(encoding="utf-8")), encoding="utf-8")
    with pytest.raises(SignalsError, match="signals level_b, LEVEL_B have no C macro of their own"):
        signals_file(load_model(clash), names, "")


def test_export_c_takes_the_firmwares_capacity(tmp_path: Path) -> None:
    """The 5-test table against a firmware built with -DFDI_DIAG_MAX_TESTS=4: refused, naming both numbers and the
    macro; a malformed --capacity is a one-line input error too."""
    res = _export(tmp_path, "--uncalibrated", "--capacity", "FDI_DIAG_MAX_TESTS=4")
    assert res.returncode == 1 and not list(tmp_path.iterdir()), res.stderr
    assert res.stderr.strip() == ("fdi-analyze: error: 5 tests selected; the firmware is built for at most 4 "
                                  "(FDI_DIAG_MAX_TESTS; raise it with -DFDI_DIAG_MAX_TESTS=n, then export with the "
                                  "same capacity)")
    res = _export(tmp_path, "--uncalibrated", "--capacity", "FDI_DIAG_MAX_TEST=4")
    assert res.returncode == 1 and "expected MACRO=n with MACRO one of FDI_DIAG_MAX_TESTS" in res.stderr
    res = _export(tmp_path, "--uncalibrated", "--capacity", "FDI_DIAG_MAX_TESTS=24")
    assert res.returncode == 0, res.stderr
    assert "--capacity FDI_DIAG_MAX_TESTS=24`" in (tmp_path / f"{NAME}.h").read_text(encoding="utf-8")
