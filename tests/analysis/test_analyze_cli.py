"""`fdi-analyze`: help, the report subcommand's files, conversion, and errors on bad models."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fdi_analysis.cli import main


def test_help_has_examples(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["--help"])
    assert info.value.code == 0
    assert "example" in capsys.readouterr().out


def test_report_writes_json_markdown_and_plots(
    models_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["report", str(models_dir / "romo_quasistatic.toml"), "-o", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "structural redundancy 9" in out
    data = json.loads((tmp_path / "report.json").read_text())
    assert data["counts"]["normal_equations"] == 63 and data["structural_redundancy"] == 9
    assert ["f10", "f14"] in data["faults"]["non_isolable_pairs"]
    md = (tmp_path / "report.md").read_text()
    assert "| 82 | 63 | 19 |" in md and "![DM decomposition](dm.png)" in md
    for png in ("dm.png", "isolability.png"):
        assert (tmp_path / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_convert_round_trips_through_report(models_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "g.json"
    assert main(["convert", str(models_dir / "romo_grouped.toml"), "--to-fdt", str(out)]) == 0
    assert main(["report", str(out), "-o", str(tmp_path / "r"), "--no-plots"]) == 0
    data = json.loads((tmp_path / "r" / "report.json").read_text())
    assert data["counts"]["equations"] == 41 and data["structural_redundancy"] == 9


def test_bad_model_is_a_clear_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('[[unknown]]\nname = "x"\n[[equation]]\nid = "e1"\nexpr = "x = y"\n')
    assert main(["report", str(bad)]) == 1
    err = capsys.readouterr().err
    assert "bad.toml: equation 'e1': undeclared symbol 'y'" in err


def small_structure_file(tmp_path: Path) -> Path:
    from fdi_analysis.random_structures import random_structure

    st = random_structure(3, ne=18, redundancy=3, nf=6)
    path = tmp_path / "small.json"
    st.to_fdt_json(path)
    return path


def test_mso_subcommand_counts_what_brute_force_finds(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from msos_bruteforce import all_msos

    from fdi_analysis.structure import Structure

    path = small_structure_file(tmp_path)
    assert main(["mso", str(path), "-o", str(tmp_path / "m"), "--workers", "1", "--no-progress"]) == 0
    data = json.loads((tmp_path / "m" / "mso.json").read_text())
    msos = all_msos(Structure.from_fdt_json(path))
    assert data["complete"] and data["count"] == len(msos) > 0
    assert sum(data["by_unknowns"].values()) == len(msos)
    assert f"{len(msos):,} MSO sets (complete)" in capsys.readouterr().out


def test_select_subcommand_writes_selections_and_figures(tmp_path: Path) -> None:
    path = small_structure_file(tmp_path)
    out = tmp_path / "s"
    assert main(["select", str(path), "-o", str(out), "--workers", "1", "--no-progress"]) == 0
    data = json.loads((out / "selection.json").read_text())
    sel = data["selections"]
    for method in "AB":
        assert sel[f"optimal {method}"]["tests"] <= sel[f"greedy {method}"]["tests"]
        assert sel[f"optimal {method}"]["optimality"] == "count and cost proven"
    for png in ("fault_matrix.png", "selected_faults.png"):
        assert (out / png).read_bytes()[:4] == b"\x89PNG"


def test_select_realizable_keeps_only_tests_with_a_generator(models_dir: Path, tmp_path: Path,
                                                             capsys: pytest.CaptureFixture[str]) -> None:
    from fdi_analysis.model_loader import load_model
    from fdi_analysis.residuals.realizability import why_not_realizable
    from fdi_analysis.residuals.solvability import Solver

    out = tmp_path / "r"
    args = ["select", str(models_dir / "romo_grouped.toml"), "--realizable", "--no-progress", "-o", str(out),
            "--time-limit", "20"]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "realizable: " in text and "need open-loop integration" in text
    model = load_model(models_dir / "romo_grouped.toml")
    solver = Solver(model)
    data = json.loads((out / "selection.json").read_text())
    for sel in data["selections"].values():
        for row in sel["msos"]:
            assert why_not_realizable(model, solver, row["equations"]) is None
