"""Selection within a cost budget (fdi_analysis.selection.budget): optimal against brute force, the complete
selection's coverage once the budget allows its cost, the sweep, and the command line's options."""

from __future__ import annotations

import itertools
import random
from pathlib import Path

import pytest

from fdi_analysis.cli import main as fdi_analyze
from fdi_analysis.selection.budget import budget_sweep, select_within_budget
from fdi_analysis.selection.practical import (
    CandidateScreen,
    FaultScreen,
    PracticalCandidate,
    Screening,
    requirements,
    select_practical,
    separates,
)

SCEN = ["a", "b"]


def cand(label: str, faults: str, cost: int, detects: str) -> PracticalCandidate:
    """detects: 'f1@a f2@b ...'."""
    return PracticalCandidate(label, frozenset(faults.split()), cost,
                              frozenset(tuple(x.split("@")) for x in detects.split()))  # type: ignore[misc]


def random_candidates(rng: random.Random, faults: list[str], n: int) -> list[PracticalCandidate]:
    out = []
    for k in range(n):
        sig = [f for f in faults if rng.random() < 0.45] or [rng.choice(faults)]
        det = " ".join(f"{f}@{s}" for f in sig for s in SCEN if rng.random() < 0.7)
        out.append(cand(f"T{k}", " ".join(sig), rng.randint(1, 9), det))
    return out


def test_optimal_against_brute_force() -> None:
    """Within the budget the most detections, then the most separations, then the least cost (every subset
    tried)."""
    rng = random.Random(11)
    faults = [f"f{i}" for i in range(1, 6)]
    for trial in range(25):
        cands = random_candidates(rng, faults, 8)
        reqs, _, _ = requirements(cands, faults, SCEN)
        budget = rng.randint(0, 25)
        best: tuple[int, int, int] | None = None  # (-detections, -separations, cost)
        for r in range(len(cands) + 1):
            for sub in itertools.combinations(range(len(cands)), r):
                cost = sum(cands[i].cost for i in sub)
                if cost <= budget:
                    met = [q for q in reqs if set(sub).intersection(q.cover)]
                    det = sum(1 for q in met if not q.fault_b)
                    key = (-det, det - len(met), cost)
                    best = min(best or key, key)
        got = select_within_budget(cands, faults, SCEN, budget)
        assert best is not None
        assert (-got.detections, -got.separations, got.cost) == best, trial
        assert got.cost <= budget
        # the counts are those of the definitions, not of the solver's own variables
        assert (got.detections, got.separations) == (
            sum(1 for q in reqs if not q.fault_b and any((q.fault_a, q.scenario) in t.detects for t in got.tests)),
            sum(1 for q in reqs if q.fault_b and any(separates(t, q.fault_a, q.fault_b, q.scenario)
                                                     for t in got.tests)))


def test_a_budget_of_the_complete_cost_meets_every_meetable_requirement() -> None:
    rng = random.Random(3)
    faults = [f"f{i}" for i in range(1, 7)]
    for _ in range(10):
        cands = random_candidates(rng, faults, 10)
        complete = select_practical(cands, faults, SCEN, "highs")
        within = select_within_budget(cands, faults, SCEN, complete.cost)
        assert within.met == within.meetable
        assert within.cost == complete.cost  # and no cheaper selection meets them all
        none = select_within_budget(cands, faults, SCEN, 0)
        assert none.tests == () and len(none.given_up) == none.meetable and none.met == 0
        assert within.given_up == ()


def test_sweep_is_monotone_and_matches_single_selections() -> None:
    rng = random.Random(8)
    faults = [f"f{i}" for i in range(1, 6)]
    cands = random_candidates(rng, faults, 9)
    seen: list[int] = []
    sweep = budget_sweep(cands, faults, SCEN, [0, 4, 8, 12, 40], progress=lambda b: seen.append(b.budget))
    assert seen == [0, 4, 8, 12, 40]
    keys = [(b.detections, b.separations) for b in sweep]
    assert keys == sorted(keys)  # more budget never detects fewer, nor separates fewer at as many detections
    assert sweep[3].met == select_within_budget(cands, faults, SCEN, 12).met
    with pytest.raises(ValueError, match="must be >= 0"):
        select_within_budget(cands, faults, SCEN, -1)


def _screening(tmp_path: Path) -> Path:
    """A screening file for the three-tank model's faults: three tests, only MSO2 (the dearest) sees fC12, fC23, fC3."""
    model_faults = ("fP", "fL1", "fL2", "fL3", "fC12", "fC23", "fC3", "fS1", "fS2", "fS3")
    share = {"a": 0.9}
    fnr = {"a": 20.0}

    def screen(label: str, faults: tuple[str, ...], cost: int) -> CandidateScreen:
        return CandidateScreen(label, "e1 e2", faults, 1.0, 0.0, cost, {f: FaultScreen(share, fnr) for f in faults})

    cands = (screen("MSO1", model_faults[:4], 10), screen("MSO2", model_faults[2:], 40),
             screen("MSO3", model_faults[7:], 5))
    path = tmp_path / "screening.json"
    Screening("three_tank", "test", 5.0, 1.5, 0.8, {f: 1.0 for f in model_faults}, ("a",), cands, 0.27, ()).dump(path)
    return path


def test_cli_budget_and_sweep(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    path = _screening(tmp_path)
    out = tmp_path / "rep"
    assert fdi_analyze(["practical", "three_tank", "--screening", str(path), "-o", str(out), "--budget", "15",
                        "--budget-sweep", "3"]) == 0
    text = capsys.readouterr().out
    assert "within the budget of 15: 2 tests, cost 15" in text
    # MSO2 alone sees fC12, fC23 and fC3 (not detected without it), and alone separates fP and fL1 from fL2, fL3
    assert "requirements of the complete selection given up within the budget:" in text
    assert "  a: detect fC12, fC23, fC3; separate fP/fL2, fP/fL3, fL1/fL2, fL1/fL3" in text
    assert "budget     55:" in text  # the sweep's last budget is the complete selection's cost
    assert (out / "budget_sweep.png").stat().st_size > 0
    assert "| budget | cost |" in (out / "budget_sweep.md").read_text(encoding="utf-8")
    assert fdi_analyze(["practical", "three_tank", "--screening", str(path), "--budget-sweep", "2"]) == 1
    assert "give -o" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        fdi_analyze(["practical", "three_tank", "--screening", str(path), "--budget", "-3"])
    assert exc.value.code == 2
