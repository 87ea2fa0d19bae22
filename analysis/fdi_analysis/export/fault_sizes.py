"""The fault-size file (`FaultSizes`, one reader for every tool): the required size of each fault
([requirement], the engineering requirement the quality suite, the screening and the practical selection
work with), the physical limits ([limits]) and the sizes at which each test reacts ([per_test.<fault>], the
fault-size sweep's smallest detectable sizes, extra information).

Which quiet tests may exonerate which fault: the reaction sizes of the residual analysis.

A test that is structurally sensitive to a fault but reacts to it only at sizes far above the size of the fault at
hand stays quiet while that fault is present; if its quietness exonerated the fault, the isolation would clear the
true fault and could name a wrong class. The table therefore carries, per (fault j, test i), the size of fault j at
which test i reacts (the `[per_test.<fault>]` tables of host_tools/scenarios/fault_sizes.toml, written by `fdi-
analyze fault-sizes`; 0 where the test does not react within the fault's physical limits in the sweep's steady
cornering, also when it reacts in another manoeuvre, [per_test_scenario.<fault>]: such a test stays quiet in a
typical drive and must not clear the fault). The firmware (fw/include/fdi_iso.h) lets a quiet test clear fault j
only when the tests in alarm imply, were the fault j, a size of at least EXONERATION_MARGIN times the quiet test's
reaction size.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from fdi_analysis.errors import FdiError


class FaultSizesError(FdiError, ValueError):
    """The fault sizes file is malformed."""


@dataclass(frozen=True)
class FaultSizes:
    requirement: Mapping[str, float]  # fault -> required size (the size to detect and isolate)
    per_test: Mapping[str, Mapping[str, float | str]]  # fault -> test label -> size, or why there is none
    source: str
    # fault -> test label -> (scenario, size): pairs stated in another manoeuvre ([per_test_scenario.<fault>]);
    # not reaction sizes (the test stays quiet in the sweep's manoeuvre)
    elsewhere: Mapping[str, Mapping[str, tuple[str, float]]] = field(default_factory=dict)
    limits: Mapping[str, float] = field(default_factory=dict)  # fault -> physical limit ([limits])

    @staticmethod
    def load(path: Path) -> FaultSizes:
        try:
            doc = tomllib.loads(path.read_text(encoding="utf-8"))
        except (OSError, tomllib.TOMLDecodeError) as exc:
            raise FaultSizesError(f"{path}: {exc}") from exc
        sizes = doc.get("requirement")
        if not isinstance(sizes, dict):
            raise FaultSizesError(f"{path}: expected a [requirement] table (fault id = required size)")
        bad = [f for f, v in sizes.items()
               if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) or not v > 0]
        if bad:
            raise FaultSizesError(f"{path}: [requirement] size of {bad[0]} must be a positive number, got "
                                  f"{sizes[bad[0]]!r}")
        per_test = doc.get("per_test", {})
        for f, row in per_test.items():
            for test, v in row.items():
                if not isinstance(v, str) and not (isinstance(v, int | float) and v > 0):
                    raise FaultSizesError(f"{path}: [per_test.{f}] {test} must be a positive number or a reason")
        elsewhere: dict[str, dict[str, tuple[str, float]]] = {}
        for f, row in doc.get("per_test_scenario", {}).items():
            for test, v in row.items():
                ok = (isinstance(v, dict) and isinstance(v.get("scenario"), str)
                      and isinstance(v.get("size"), int | float) and v["size"] > 0)
                if not ok:
                    raise FaultSizesError(f"{path}: [per_test_scenario.{f}] {test} must be "
                                          "{ scenario = <name>, size = <positive number> }")
                elsewhere.setdefault(f, {})[test] = (v["scenario"], float(v["size"]))
        limits = {f: float(v) for f, v in doc.get("limits", {}).items() if isinstance(v, int | float)}
        return FaultSizes({f: float(v) for f, v in sizes.items()}, per_test, str(path), elsewhere, limits)

    def check_faults(self, faults: Sequence[str]) -> None:
        """FaultSizesError when the file names a fault that is not in `faults` or lacks a required one."""
        unknown = [f for f in self.requirement if f not in faults]
        if unknown:
            raise FaultSizesError(f"{self.source}: unknown fault {unknown[0]!r} in [requirement] (faults are "
                                  f"{faults[0]}..{faults[-1]})")
        missing = [f for f in faults if f not in self.requirement]
        if missing:
            raise FaultSizesError(f"{self.source}: [requirement] lacks {', '.join(missing)}")

    def reaction_size(self, fault: str, test: str) -> float:
        """The size of `fault` at which `test` reacts; 0 when it does not (or was not measured)."""
        v = self.per_test.get(fault, {}).get(test)
        return float(v) if isinstance(v, int | float) else 0.0


# The stated sizes are grid values above the first alarm of one scenario (cornering): a factor 2 covers the
# grid step and a less exciting manoeuvre before a quiet test is taken as evidence.
EXONERATION_MARGIN = 2.0
# The on-line rule (fdi_diag.h): a settled quiet test clears a fault when its sensitivity times the size the alarms
# imply reaches this many times its gate. It covers the linearisation where the quiet test sees the fault through a
# nonlinearity the alarmed tests do not (the derivative overpredicts a saturating fault's effect by up to 1.6x,
# tests/analysis/test_sensitivity.py; where both see it through the same slip law the errors cancel); the implied
# size is a lower bound already (its noise allowance). On a drive, `fdi-quality --trace CASE --linearity` measures
# how far a test's response departs from s F (in the slalom, a steering offset's tyre tests: 0.5 to 2.1 times), and
# `fdi-quality --linearity` surveys it over every case (README); the margin does not cover every departure, so it is
# validated per table by the quality suite, not derived.
SENSITIVITY_MARGIN = 1.5
# A test reacts to a fault of a stated size when it raises a raw alarm within this time of a step (the sweep's
# window): the response time of a quiet test under the reaction-size rule.
REACTION_WINDOW_S = 3.0


def test_size_rows(faults: Sequence[str], labels: Sequence[str], signatures: Sequence[int],
                   sizes: FaultSizes | None) -> tuple[list[list[float]], float]:
    """(rows, margin): per fault j and test i (labels[i]) the reaction size, 0 off the signature. Without
    sizes: 1 on the signature and margin 1, the classic rule (every quiet test of the signature exonerates)."""
    if sizes is None:
        return [[1.0 if sig >> i & 1 else 0.0 for i in range(len(labels))] for sig in signatures], 1.0
    return ([[sizes.reaction_size(f, lab) if sig >> i & 1 else 0.0 for i, lab in enumerate(labels)]
             for f, sig in zip(faults, signatures, strict=True)], EXONERATION_MARGIN)
