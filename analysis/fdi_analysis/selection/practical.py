"""Selection by practical isolability: the cheapest set of realizable tests that practically separates every
pair of structurally isolable faults and practically detects every fault, in every manoeuvre.

Input: per candidate test its structural signature F_t (the faults of its MSO set), its cost, and the
(fault, manoeuvre) pairs it practically detects, D_t (its fault-to-noise ratio clears the gate with margin at
the stated share of the manoeuvre's operating points: `fdi_host.tuning.screening`). A set of tests T must
satisfy, for every manoeuvre s,

    separation  for every pair {j, k} the realizable candidates isolate structurally (method B: their
                signatures over all candidates differ), some t in T has (j, s) in D_t and k not in F_t, or
                (k, s) in D_t and j not in F_t: one test sees one fault of the pair and is blind to the other;
    detection   for every fault j, some t in T has (j, s) in D_t,

and costs least (sum of the tests' costs). Requirements that no candidate can meet are not constraints: they
are reported with the reason (`Unmet`). The problem is a weighted set cover, solved exactly: as weighted
MaxSAT by RC2 over CaDiCaL (python-sat, the solver of the structural SAT selection), stratified by weight
levels with core exhaustion and minimisation (plain RC2 did not finish in 12 minutes on the ROMO screening's
632 distinct rows and 580 candidates; stratified, 0.1 s), or without python-sat as a 0-1 linear program with
HiGHS (scipy.optimize.milp, 8 s there); both prove optimality, and the tests check that they agree.
"""

from __future__ import annotations

import gzip
import itertools
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from enum import Enum
from pathlib import Path
from typing import Any

import numpy as np

from fdi_analysis.errors import ComputationError, FdiError, fields_of

MARGIN = 1.5  # a test practically detects a fault where its FNR clears the gate by this factor, at least, ...
SHARE = 0.8  # ... at this share of a manoeuvre's operating points
# ... and by as much as it takes to cross the gate within DETECT_S of a step: 1 / (the share of its final value
# its response has reached then, `residuals.evaluate.step_response`). DETECT_S: the detection goal (300 ms)
# less the alarm confirmation (set_count, 3 steps of 10 ms).
DETECT_S = 0.27


class ScreeningError(FdiError, ValueError):
    """A screening file that this code cannot use (malformed, or made by a screening with another criterion)."""


@dataclass(frozen=True)
class FaultScreen:
    """One fault of a candidate's signature: per scenario the share of operating points where the test
    practically detects it, and the median FNR over the evaluable ones."""

    share: dict[str, float]
    median_fnr: dict[str, float]


@dataclass(frozen=True)
class CandidateScreen:
    label: str
    equations: str  # the MSO set, space separated
    faults: tuple[str, ...]  # structural signature
    sigma: float
    min_speed: float  # operating domain (0: always evaluable)
    cost: int  # operations per step of the residual (common subexpressions counted once) + filters
    per_fault: dict[str, FaultScreen] = field(default_factory=dict)
    rejected: str = ""  # why it has no generator after all ("" when screened)
    evaluable: dict[str, float] = field(default_factory=dict)  # scenario -> share of its points in the domain
    margin: float = MARGIN  # the factor its FNR must clear the gate by (MARGIN, or more for a slow generator)

    def detects(self, fault: str, scenario: str, share: float = SHARE) -> bool:
        fs = self.per_fault.get(fault)
        return fs is not None and fs.share.get(scenario, 0.0) >= share


@dataclass(frozen=True)
class Screening:
    """The screening file (`fdi-tune screen`): how every realizable candidate was measured, and the results."""

    model: str
    provenance: str
    gate: float
    margin: float
    share: float
    sizes: dict[str, float]
    scenarios: tuple[str, ...]
    candidates: tuple[CandidateScreen, ...]
    detect_s: float = DETECT_S  # the slow-generator margin's detection time (see DETECT_S)
    seeds: tuple[int, ...] = ()  # noise seeds of the sigma drives besides each scenario's own

    def dump(self, path: Path) -> None:
        """Write as JSON, gzip-compressed (no time stamp) when the name ends in .gz."""
        doc = asdict(self)
        doc["candidates"] = [asdict(c) | {"sigma": c.sigma if math.isfinite(c.sigma) else None}
                             for c in self.candidates]
        text = json.dumps(doc, separators=(",", ":"), sort_keys=True, allow_nan=False) + "\n"
        path.parent.mkdir(parents=True, exist_ok=True)
        if path.suffix == ".gz":
            path.write_bytes(gzip.compress(text.encode("utf-8"), mtime=0))
        else:
            path.write_text(text, encoding="utf-8")

    @staticmethod
    def load(path: Path) -> Screening:
        """The screening at `path` (JSON, gzipped when it ends in .gz); a `ScreeningError` naming the file for one
        that cannot be read or decoded, or lacks a field."""
        try:
            raw = path.read_bytes()
            doc = json.loads(gzip.decompress(raw) if path.suffix == ".gz" else raw)
        except (OSError, EOFError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise ScreeningError(f"{path}: not a screening (JSON{', gzipped' if path.suffix == '.gz' else ''}): "
                                 f"{exc}") from exc
        if not isinstance(doc, dict):
            raise ScreeningError(f"{path}: not a screening (a JSON object expected)")
        with fields_of(path, ScreeningError):
            return Screening._of(doc, path)

    @staticmethod
    def _of(doc: dict[str, Any], path: Path) -> Screening:
        missing = [k for k in ("detect_s", "seeds") if k not in doc]
        if missing:
            raise ScreeningError(f"{path}: no {' and no '.join(missing)}: made by an older `fdi-tune screen` whose "
                                 "criterion differs from this code's; rerun it (FDI_SCREEN=1 scripts/generate.sh)")
        cands = tuple(
            CandidateScreen(c["label"], c["equations"], tuple(c["faults"]),
                            float(c["sigma"]) if c["sigma"] is not None else math.nan, float(c["min_speed"]),
                            int(c["cost"]), {f: FaultScreen(dict(v["share"]), dict(v["median_fnr"]))
                                             for f, v in c["per_fault"].items()}, c["rejected"],
                            {k: float(v) for k, v in c.get("evaluable", {}).items()}, float(c.get("margin", MARGIN)))
            for c in doc["candidates"])
        return Screening(doc["model"], doc["provenance"], float(doc["gate"]), float(doc["margin"]),
                         float(doc["share"]), {k: float(v) for k, v in doc["sizes"].items()},
                         tuple(doc["scenarios"]), cands, float(doc["detect_s"]), tuple(int(x) for x in doc["seeds"]))

    def practical_candidates(self) -> list[PracticalCandidate]:
        """The screened candidates (those with a generator) as the selection sees them."""
        return [PracticalCandidate(c.label, frozenset(c.faults), c.cost,
                                   frozenset((f, s) for f in c.faults for s in self.scenarios
                                             if c.detects(f, s, self.share)),
                                   {(f, s): fs.share.get(s, 0.0) for f, fs in c.per_fault.items()
                                    for s in self.scenarios},
                                   c.evaluable,
                                   {(f, s): fs.median_fnr.get(s, 0.0) for f, fs in c.per_fault.items()
                                    for s in self.scenarios},
                                   self.gate * c.margin)
                for c in self.candidates if not c.rejected]


@dataclass(frozen=True)
class PracticalCandidate:
    label: str
    faults: frozenset[str]  # structural signature
    cost: int
    detects: frozenset[tuple[str, str]]  # (fault, scenario) practically detected
    share: Mapping[tuple[str, str], float] = field(default_factory=dict)  # (fault, scenario) -> detecting share
    evaluable: Mapping[str, float] = field(default_factory=dict)  # scenario -> share in the operating domain
    median_fnr: Mapping[tuple[str, str], float] = field(default_factory=dict)  # (fault, scenario) -> median FNR
    needed_fnr: float = 0.0  # the FNR it must reach to detect (gate x its margin); 0: unknown


class UnmetKind(Enum):
    """Why no realizable test meets a requirement."""

    NOT_IN_SIGNATURE = "no realizable test has the fault in its signature"
    OUT_OF_DOMAIN = "every realizable test that could meet it is outside its operating domain throughout"
    WEAK = "realizable tests could meet it, none reaches the fault-to-noise ratio at the stated share"


@dataclass(frozen=True)
class Unmet:
    """A requirement no realizable candidate meets: a pair to separate (fault_b set) or a fault to detect.
    `tests`: the realizable tests that could meet it structurally (see the fault, and for a pair not the other
    one); `best_test`, `best_share`: the one of them that comes closest (share of the manoeuvre's operating
    points where it detects); `strongest_test`, `strongest_fnr`, `needed_fnr`: the one whose median fault-to-noise
    ratio at the required size comes nearest to what it needs (its gate x margin; the size it would take, were the
    response linear in the size, is needed / median times the required one)."""

    scenario: str
    fault_a: str
    fault_b: str  # "" for a detection requirement
    kind: UnmetKind
    tests: int
    best_test: str = ""
    best_share: float = 0.0
    strongest_test: str = ""
    strongest_fnr: float = 0.0
    needed_fnr: float = 0.0

    @property
    def reason(self) -> str:
        what = f"{self.fault_a}/{self.fault_b}" if self.fault_b else self.fault_a
        if self.kind is UnmetKind.NOT_IN_SIGNATURE:
            return f"no realizable test has {self.fault_a} in its signature"
        if self.kind is UnmetKind.OUT_OF_DOMAIN:
            return (f"all {self.tests} realizable tests for {what} are outside their operating domain at every "
                    f"operating point of {self.scenario}")
        strongest = (f"; the strongest median fault-to-noise ratio, {self.strongest_test}'s, is "
                     f"{self.strongest_fnr:.2g} of the {self.needed_fnr:.2g} it needs" if self.needed_fnr > 0.0 else "")
        return (f"{self.tests} realizable tests for {what}; the closest, {self.best_test}, detects at "
                f"{self.best_share:.0%} of the operating points of {self.scenario}{strongest}")


@dataclass(frozen=True)
class PracticalSelection:
    tests: tuple[PracticalCandidate, ...]
    cost: int
    solver: str  # "rc2" or "highs"
    unmet: tuple[Unmet, ...]
    pairs: tuple[tuple[str, str], ...]  # the structurally isolable pairs required to be separated
    scenarios: tuple[str, ...]


def separates(t: PracticalCandidate, a: str, b: str, scenario: str) -> bool:
    return ((a, scenario) in t.detects and b not in t.faults) or ((b, scenario) in t.detects and a not in t.faults)


def isolable_pairs(candidates: Sequence[PracticalCandidate], faults: Sequence[str]) -> list[tuple[str, str]]:
    """Pairs of faults whose signatures over all candidates differ (method B structural isolability)."""
    sig = {f: frozenset(i for i, t in enumerate(candidates) if f in t.faults) for f in faults}
    return [(a, b) for a, b in itertools.combinations(faults, 2) if sig[a] != sig[b]]


def _unmet(cands: Sequence[PracticalCandidate], a: str, b: str, s: str) -> Unmet:
    """Why no candidate meets the requirement (a, b) in scenario s (b = "": detect a)."""
    if b:
        options = [(t, t.share.get((a, s), 0.0)) for t in cands if a in t.faults and b not in t.faults]
        options += [(t, t.share.get((b, s), 0.0)) for t in cands if b in t.faults and a not in t.faults]
    else:
        options = [(t, t.share.get((a, s), 0.0)) for t in cands if a in t.faults]
    if not options:
        return Unmet(s, a, b, UnmetKind.NOT_IN_SIGNATURE, 0)
    best, share = max(options, key=lambda o: (o[1], -o[0].cost))
    if all(t.evaluable.get(s, 1.0) == 0.0 for t, _ in options):
        return Unmet(s, a, b, UnmetKind.OUT_OF_DOMAIN, len(options), best.label, share)
    # the fault each option would have to detect: a unless the test sees a (then b)
    ratios = [(t, t.median_fnr.get((a if a in t.faults else b, s), 0.0), t.needed_fnr) for t, _ in options
              if t.needed_fnr > 0.0]
    if not ratios:
        return Unmet(s, a, b, UnmetKind.WEAK, len(options), best.label, share)
    strong, fnr, need = max(ratios, key=lambda o: (o[1] / o[2], -o[0].cost))
    return Unmet(s, a, b, UnmetKind.WEAK, len(options), best.label, share, strong.label, fnr, need)


@dataclass(frozen=True)
class Requirement:
    """One requirement of the module doc that some candidate meets: in `scenario`, detect `fault_a` (fault_b "")
    or separate the pair; `cover`: the indices of the candidates that meet it."""

    scenario: str
    fault_a: str
    fault_b: str
    cover: tuple[int, ...]


def requirements(candidates: Sequence[PracticalCandidate], faults: Sequence[str], scenarios: Sequence[str]
                 ) -> tuple[list[Requirement], list[Unmet], list[tuple[str, str]]]:
    """The requirements some candidate meets, those none meets (with the reason), and the structurally isolable
    pairs they are built from; per manoeuvre, the detections first, then the pairs."""
    pairs = isolable_pairs(candidates, faults)
    reqs: list[Requirement] = []
    unmet: list[Unmet] = []
    for s in scenarios:
        for a, b in [(f, "") for f in faults] + pairs:
            cover = tuple(i for i, t in enumerate(candidates)
                          if (separates(t, a, b, s) if b else (a, s) in t.detects))
            if cover:
                reqs.append(Requirement(s, a, b, cover))
            else:
                unmet.append(_unmet(candidates, a, b, s))
    return reqs, unmet, pairs


def select_practical(candidates: Sequence[PracticalCandidate], faults: Sequence[str],
                     scenarios: Sequence[str], solver: str = "auto") -> PracticalSelection:
    """The cheapest selection meeting every requirement some candidate meets (see the module doc)."""
    reqs, unmet, pairs = requirements(candidates, faults, scenarios)
    rows = [r.cover for r in reqs]
    if solver not in ("auto", "rc2", "highs"):
        raise ValueError(f"solver {solver!r}: use auto, rc2 or highs")
    costs = [max(1, t.cost) for t in candidates]
    use = solver
    if use == "auto":
        try:
            import pysat  # noqa: F401

            use = "rc2"
        except ImportError:
            use = "highs"
    chosen = _solve_rc2(rows, costs) if use == "rc2" else _solve_highs(rows, costs)
    tests = tuple(candidates[i] for i in sorted(chosen))
    return PracticalSelection(tests, sum(costs[i] for i in chosen), use, tuple(unmet), tuple(pairs),
                              tuple(scenarios))


def _dedupe(rows: Sequence[Sequence[int]]) -> list[tuple[int, ...]]:
    return sorted({tuple(sorted(r)) for r in rows})


def _solve_rc2(rows: Sequence[Sequence[int]], costs: Sequence[int]) -> list[int]:
    from pysat.examples.rc2 import RC2Stratified
    from pysat.formula import WCNF

    w = WCNF()
    for r in _dedupe(rows):
        w.append([i + 1 for i in r])
    for i, c in enumerate(costs):
        w.append([-(i + 1)], weight=c)
    with RC2Stratified(w, solver="cd19", adapt=True, exhaust=True, minz=True) as rc2:
        model = rc2.compute()
    if model is None:
        raise RuntimeError("practical selection: the requirements that candidates meet are contradictory")
    return [v - 1 for v in model if 0 < v <= len(costs)]


def _solve_highs(rows: Sequence[Sequence[int]], costs: Sequence[int]) -> list[int]:
    from scipy.optimize import Bounds, LinearConstraint, milp

    uniq = _dedupe(rows)
    n = len(costs)
    a = np.zeros((len(uniq), n))
    for k, r in enumerate(uniq):
        a[k, list(r)] = 1.0
    res = milp(np.asarray(costs, dtype=float), constraints=LinearConstraint(a, lb=1.0, ub=np.inf),
               integrality=np.ones(n), bounds=Bounds(0.0, 1.0), options={"mip_rel_gap": 0.0})
    if not res.success:
        raise ComputationError(f"practical selection: HiGHS found no solution ({res.message})")
    return [i for i in range(n) if res.x[i] > 0.5]


def practical_matrix(tests: Sequence[PracticalCandidate], faults: Sequence[str],
                     scenarios: Sequence[str]) -> dict[tuple[str, str], int]:
    """For each ordered pair (a, b), a != b: in how many manoeuvres the tests practically separate them."""
    out: dict[tuple[str, str], int] = {}
    for a, b in itertools.permutations(faults, 2):
        out[(a, b)] = sum(any(separates(t, a, b, s) for t in tests) for s in scenarios)
    return out


def structural_matrix(tests: Sequence[PracticalCandidate], faults: Sequence[str]) -> dict[tuple[str, str], bool]:
    """Method B: (a, b) isolable by the tests' signatures."""
    sig: Mapping[str, frozenset[int]] = {f: frozenset(i for i, t in enumerate(tests) if f in t.faults)
                                         for f in faults}
    return {(a, b): sig[a] != sig[b] for a, b in itertools.permutations(faults, 2)}
