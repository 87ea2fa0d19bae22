"""Tests added to the structural selection for practical detectability (`fdi-tune augment`): the search
order and coverage with stubbed calibration and sweeps, the [augment] table of the thresholds file, the
selection read back with it, and the committed files: every fault of the exported tests' signatures has a
test that detects it within its limit."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from fdi_analysis.export.thresholds import AUGMENT_MARKER, MARKER, Thresholds, with_augment, with_generated
from fdi_analysis.fault_matrix import Candidate
from fdi_analysis.model import Model
from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.selected import augmented_tests, realizable, selected_generators, structural_selection
from fdi_host.tuning.augment import AugmentError, augment, undetected_faults
from fdi_host.tuning.drives import observer_reference
from fdi_host.tuning.sweep import PairLimit

MODEL = "analysis/models/romo_grouped.toml"
THRESHOLDS = "analysis/models/romo_thresholds.toml"
SIZES = "host_tools/scenarios/fault_sizes.toml"


@pytest.fixture(scope="module")
def romo(repo: Path) -> tuple[Model, list[Candidate], list[Candidate]]:
    model = load_model(repo / MODEL)
    keep = realizable(model, workers=1)
    return model, keep, structural_selection(model, keep)


def _pair(fault: str, g: Generator, at: float | None) -> PairLimit:
    return PairLimit(fault, g.name, at, None if at is None else 1.5 * at, 500.0)


def test_search_takes_the_first_candidate_that_detects_and_lets_it_cover_others(
        romo: tuple[Model, list[Candidate], list[Candidate]]) -> None:
    model, keep, selection = romo
    tried: list[tuple[str, str]] = []
    k = list(model.structure().faults).index("f11")
    chosen = {c.equations for c in selection}
    f11_holders = [c.label for c in keep if (c.faults >> k) & 1 and c.equations not in chosen]

    def sweep(g: Generator, sigma: float, fault: str) -> PairLimit:
        tried.append((g.name, fault))
        assert sigma == 1.0
        if fault == "f11":  # the cheapest candidate is blind to f11, the second one sees it
            return _pair(fault, g, None if g.name == f11_holders[0] else 50.0)
        if fault == "f15":
            return _pair(fault, g, 70.0)
        return _pair(fault, g, None)  # f25: never

    added, left = augment(model, keep, selection, ["f11", "f15", "f25"], lambda g: 1.0, sweep,
                          observer_reference(), tries=3)
    assert [a.generator.name for a in added] == [f11_holders[1]]
    assert set(added[0].covers) == {"f11", "f15"}  # f15 is in its signature and detected: not searched again
    assert added[0].covers["f11"].stated == 75.0 and "detects f11 from 50 (stated 75)" in added[0].comment()
    assert left == ["f25"]
    f25 = [n for n, f in tried if f == "f25"]
    assert len(f25) == 3 and len(set(f25)) == 3  # at most `tries` candidates, none of the selection's
    assert not {c.label for c in selection} & {n for n, _ in tried}


def test_undetected_faults_need_every_pair_swept() -> None:
    g = Generator("T1", ("E1",), "E1", (), 0, 0, (), (), (), ("f1", "f2"))  # type: ignore[arg-type]
    h = Generator("T2", ("E2",), "E2", (), 0, 0, (), (), (), ("f2", "f3"))  # type: ignore[arg-type]
    per_test: dict[str, dict[str, float | str]] = {
        "f1": {"T1": 3.0}, "f2": {"T1": "not detectable", "T2": "not detectable"}, "f3": {"T2": 2.0}}
    assert undetected_faults(per_test, [g, h]) == ["f2"]
    del per_test["f3"]["T2"]
    with pytest.raises(AugmentError, match="no entry for f3 in T2: run `fdi-tune fault-sizes` first"):
        undetected_faults(per_test, [g, h])


def test_augment_table_survives_calibration_and_is_read_back(tmp_path: Path) -> None:
    hand = "gate = 5.0\n\n[design]\ndt = 0.01\ncutoff_hz = 1.0\nzeta = 0.7071\nobs_gain = 2.0\n\n[variance]\nX = 1.0\n"
    text = with_generated(hand, [("A B", 2.0, "T: sigma 1.41")], "calibrated")
    aug = with_augment(text, [("C D E", "T2 detects f9")], "augmented\nsecond line")
    assert aug.index(AUGMENT_MARKER) < aug.index(MARKER) and aug.startswith(hand)
    assert with_augment(aug, [("C D E", "T2 detects f9")], "augmented\nsecond line") == aug  # idempotent
    again = with_generated(aug, [("A B", 3.0, "T: sigma 1.73")], "calibrated again")  # calibrate keeps [augment]
    path = tmp_path / "t.toml"
    path.write_text(again, encoding="utf-8")
    th = Thresholds.load(path)
    assert th.augment == ("C D E",) and th.generated == {"A B": 3.0}
    assert with_augment(hand, [], "none").rstrip().endswith("tests = [\n]")  # no [generated] yet: nothing appended


def test_augment_names_a_set_that_is_not_a_candidate(romo: tuple[Model, list[Candidate], list[Candidate]]) -> None:
    model, keep, selection = romo
    with pytest.raises(ValueError, match="'S1 S2' is not a realizable candidate MSO set of romo_grouped"):
        augmented_tests(model, keep, selection, ["S1 S2"])
    names = [e.id for e in model.equations]
    first = " ".join(names[i] for i in range(len(names)) if (selection[0].equations >> i) & 1)
    with pytest.raises(ValueError, match="already a test of the selection"):
        augmented_tests(model, keep, selection, [first])


def test_committed_tests_detect_every_fault_in_practice(repo: Path) -> None:
    """With the committed [augment] tests, every fault of the exported signatures has a test with a stated size
    within the fault's limit (the structural selection alone leaves the wheel 2 and 3 torque faults blind)."""
    th = Thresholds.load(repo / THRESHOLDS)
    assert th.augment, "the committed thresholds file has no [augment] tests"
    model = load_model(repo / MODEL)
    _, gens = selected_generators(model, th.observer_reference(), workers=1, augment=th.augment)
    assert [" ".join(g.equations) for g in gens[-len(th.augment):]] == list(th.augment)
    doc = tomllib.loads((repo / SIZES).read_text(encoding="utf-8"))
    assert undetected_faults(doc["per_test"], gens) == []
    assert undetected_faults(doc["per_test"], gens[:-len(th.augment)]) != []
    for g in gens:
        assert " ".join(g.equations) in th.generated, f"{g.name} has no calibrated sigma"


def _structural_sizes_all_detected(repo: Path, path: Path) -> None:
    """A copy of the fault-size file in which every test detects f11, f12, f15 and f16 (stated 100)."""
    lines, section = [], ""
    for line in (repo / SIZES).read_text(encoding="utf-8").splitlines():
        section = line if line.startswith("[") else section
        if section in ("[per_test.f11]", "[per_test.f12]", "[per_test.f15]", "[per_test.f16]") and '"' in line:
            line = line.split(" = ")[0] + " = 100"
        lines.append(line)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def test_cli_writes_an_empty_table_when_the_selection_detects_everything(
        repo: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from fdi_host.tuning.cli import main

    sizes, thresholds = tmp_path / "sizes.toml", tmp_path / "thresholds.toml"
    _structural_sizes_all_detected(repo, sizes)
    thresholds.write_text((repo / THRESHOLDS).read_text(encoding="utf-8"), encoding="utf-8")
    assert main(["augment", str(repo / MODEL), "--thresholds", str(thresholds), "--sizes", str(sizes)]) == 0
    out = capsys.readouterr()
    assert "not detected in practice by the selection: none" in out.err and "0 tests added" in out.out
    th = Thresholds.load(thresholds)
    assert th.augment == () and th.generated == Thresholds.load(repo / THRESHOLDS).generated


def test_cli_names_a_test_missing_from_the_fault_size_file(
        repo: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from fdi_host.tuning.cli import main

    sizes = tmp_path / "sizes.toml"
    text = (repo / SIZES).read_text(encoding="utf-8")
    sizes.write_text(text.replace("[per_test.f13]\nMSO2140 = 70", "[per_test.f13]"), encoding="utf-8")
    code = main(["augment", str(repo / MODEL), "--thresholds", str(repo / THRESHOLDS), "--sizes", str(sizes)])
    assert code == 2
    assert "no entry for f13 in MSO2140: run `fdi-tune fault-sizes` first" in capsys.readouterr().err
