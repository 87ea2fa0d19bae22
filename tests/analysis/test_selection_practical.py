"""Selection by practical isolability (fdi_analysis.selection.practical): the requirements it builds, the
unmet ones and their reasons, optimality against brute force, and the two exact solvers agreeing."""

from __future__ import annotations

import itertools
import random

import pytest

from fdi_analysis.selection.practical import (
    CandidateScreen,
    FaultScreen,
    PracticalCandidate,
    Screening,
    UnmetKind,
    isolable_pairs,
    practical_matrix,
    select_practical,
    separates,
    structural_matrix,
)

FAULTS = ["f1", "f2", "f3", "f4"]
SCEN = ["a", "b"]


def cand(label: str, faults: str, cost: int, detects: str) -> PracticalCandidate:
    """detects: 'f1@a f2@b ...'."""
    return PracticalCandidate(label, frozenset(faults.split()), cost,
                              frozenset(tuple(x.split("@")) for x in detects.split()))  # type: ignore[misc]


def meets(tests: list[PracticalCandidate], faults: list[str], scen: list[str],
          pairs: list[tuple[str, str]], unmet: set[tuple[str, str, str]]) -> bool:
    for s in scen:
        for f in faults:
            if (s, f, "") not in unmet and not any((f, s) in t.detects for t in tests):
                return False
        for a, b in pairs:
            if (s, a, b) not in unmet and not any(separates(t, a, b, s) for t in tests):
                return False
    return True


def test_separation_needs_detection_of_one_and_blindness_to_the_other() -> None:
    t = cand("T", "f1 f2", 1, "f1@a")
    assert separates(t, "f1", "f3", "a") and separates(t, "f3", "f1", "a")
    assert not separates(t, "f1", "f2", "a")  # sees both structurally
    assert not separates(t, "f1", "f3", "b")  # does not detect f1 in b
    assert not separates(t, "f2", "f3", "a")  # f2 in the signature but not detected


def test_unmet_requirements_carry_their_reason() -> None:
    cands = [cand("A", "f1 f2", 3, "f1@a f1@b f2@a"), cand("B", "f2 f3", 2, "f2@a f2@b f3@a"),
             cand("C", "f1 f2 f3", 1, "f1@a f2@a f3@a f1@b"), cand("D", "f4", 1, "f4@a f4@b")]
    sel = select_practical(cands, FAULTS, SCEN, "highs")
    unmet = {(u.scenario, u.fault_a, u.fault_b): u for u in sel.unmet}
    f3 = unmet[("b", "f3", "")]
    assert f3.kind is UnmetKind.WEAK and f3.tests == 2 and "2 realizable tests for f3" in f3.reason
    assert all(u.scenario == "b" for u in sel.unmet)  # every requirement of a is met
    assert meets(list(sel.tests), FAULTS, SCEN, list(sel.pairs), set(unmet))
    # f1/f2/f3 share no test that sees one without the other in a way that separates f1/f3 except A and B
    assert {t.label for t in sel.tests} >= {"D"}


def test_optimal_against_brute_force_and_both_solvers_agree() -> None:
    rng = random.Random(5)
    for trial in range(30):
        faults = [f"f{i}" for i in range(1, 6)]
        cands = []
        for k in range(9):
            sig = [f for f in faults if rng.random() < 0.45] or [rng.choice(faults)]
            det = " ".join(f"{f}@{s}" for f in sig for s in SCEN if rng.random() < 0.7)
            cands.append(cand(f"T{k}", " ".join(sig), rng.randint(1, 9), det))
        highs = select_practical(cands, faults, SCEN, "highs")
        rc2 = select_practical(cands, faults, SCEN, "rc2")
        assert highs.cost == rc2.cost, trial
        unmet = {(u.scenario, u.fault_a, u.fault_b) for u in highs.unmet}
        pairs = isolable_pairs(cands, faults)
        best = min((sum(max(1, t.cost) for t in sub) for r in range(len(cands) + 1)
                    for sub in itertools.combinations(cands, r)
                    if meets(list(sub), faults, SCEN, pairs, unmet)), default=None)
        assert best == highs.cost, trial
        assert meets(list(highs.tests), faults, SCEN, pairs, unmet)


def test_isolable_pairs_and_matrices() -> None:
    cands = [cand("A", "f1 f2", 1, "f1@a"), cand("B", "f2", 1, "f2@a f2@b")]
    pairs = isolable_pairs(cands, ["f1", "f2", "f3"])
    assert pairs == [("f1", "f2"), ("f1", "f3"), ("f2", "f3")]
    assert isolable_pairs(cands, ["f3", "f4"]) == []  # f3, f4 in no test: same (empty) signature
    prac = practical_matrix(cands, ["f1", "f2", "f3"], SCEN)
    assert prac[("f1", "f2")] == 2 and prac[("f2", "f1")] == 2  # B sees f2 and not f1, in a and b
    assert prac[("f1", "f3")] == 1  # A detects f1 in a only
    assert structural_matrix(cands, ["f1", "f2", "f3"])[("f1", "f2")]


def test_screening_file_round_trip(tmp_path) -> None:  # type: ignore[no-untyped-def]
    c1 = CandidateScreen("MSO7", "A B C", ("f1", "f2"), 67.9, 2.0, 136,
                         {"f1": FaultScreen({"a": 0.9, "b": 0.1}, {"a": 12.0, "b": 3.0}),
                          "f2": FaultScreen({"a": 0.0, "b": 0.85}, {"a": 0.1, "b": 9.0})})
    c2 = CandidateScreen("MSO9", "A D", (), float("nan"), 0.0, 0, {}, "observer diverges")
    scr = Screening("m", "cmd", 5.0, 1.5, 0.8, {"f1": 1.0, "f2": 2.0}, ("a", "b"), (c1, c2), 0.3, (1001, 1002))
    path = tmp_path / "s.json"
    scr.dump(path)
    back = Screening.load(path)
    assert (back.detect_s, back.seeds) == (0.3, (1001, 1002))
    assert back.candidates[0] == c1 and back.candidates[1].rejected == "observer diverges"
    pc = back.practical_candidates()
    assert len(pc) == 1 and pc[0].detects == frozenset({("f1", "a"), ("f2", "b")})
    with pytest.raises(ValueError):
        select_practical(pc, ["f1", "f2"], ["a", "b"], "nonsense")


def test_unmet_kinds_name_why() -> None:
    """No test with the fault at all; tests that could meet it but are outside their domain throughout the
    manoeuvre; tests in their domain that are too weak (with the closest one and its share)."""
    weak = PracticalCandidate("W", frozenset({"f1", "f2"}), 1, frozenset(), {("f1", "a"): 0.4}, {"a": 1.0, "b": 0.0})
    sel = select_practical([weak], ["f1", "f2", "f3"], ["a", "b"], "highs")
    kinds = {(u.scenario, u.fault_a, u.fault_b): u for u in sel.unmet}
    assert kinds[("a", "f3", "")].kind is UnmetKind.NOT_IN_SIGNATURE
    assert kinds[("b", "f1", "")].kind is UnmetKind.OUT_OF_DOMAIN and "outside their operating domain" in \
        kinds[("b", "f1", "")].reason
    w = kinds[("a", "f1", "")]
    assert w.kind is UnmetKind.WEAK and (w.best_test, w.best_share) == ("W", 0.4) and "40%" in w.reason


def test_unmet_pair_names_the_strongest_ratio_against_the_needed_one() -> None:
    """A pair no test separates: the report names the closest test by share and the one whose median fault-to-noise
    ratio comes nearest to what it needs (ratio to its own need: a test with a larger margin needs more)."""
    a = PracticalCandidate("A", frozenset({"f1"}), 1, frozenset(), {("f1", "s"): 0.1}, {"s": 1.0},
                           {("f1", "s"): 3.0}, 15.0)  # 0.2 of its need
    b = PracticalCandidate("B", frozenset({"f2"}), 1, frozenset(), {("f2", "s"): 0.0}, {"s": 1.0},
                           {("f2", "s"): 2.0}, 5.0)  # 0.4 of its need: the strongest
    both = PracticalCandidate("C", frozenset({"f1", "f2"}), 1, frozenset({("f1", "s"), ("f2", "s")}))
    sel = select_practical([a, b, both], ["f1", "f2"], ["s"], "highs")
    (u,) = [u for u in sel.unmet if u.fault_b]
    assert (u.fault_a, u.fault_b, u.kind) == ("f1", "f2", UnmetKind.WEAK)
    assert (u.best_test, u.best_share) == ("A", 0.1)
    assert (u.strongest_test, u.strongest_fnr, u.needed_fnr) == ("B", 2.0, 5.0)
    assert "B's, is 2 of the 5 it needs" in u.reason
