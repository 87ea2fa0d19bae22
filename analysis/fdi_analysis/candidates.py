"""Candidate tests for selection: one MSO set per distinct fault signature (the smallest), numbered.

The MSO search aggregates every MSO set into its fault-signature table without storing the sets; the
cheapest MSO of each signature represents it (tests with one fault set clear the same fault-matrix
elements). Candidates are numbered MSO1, MSO2, ... in order of cost (unknowns), then size, then equations.
"""

from __future__ import annotations

from fdi_analysis.fault_matrix import Candidate
from fdi_analysis.mso import MsoSummary, find_msos
from fdi_analysis.structure import Structure
from fdi_analysis.summary import require_redundancy


def candidates_from_summary(summary: MsoSummary) -> list[Candidate]:
    raw = [Candidate(equations=e.smallest, faults=e.faults, cost=e.smallest_unknowns) for e in summary.signatures]
    raw.sort(key=lambda t: (t.cost, t.equations.bit_count(), t.equations))
    return [Candidate(t.equations, t.faults, t.cost, label=f"MSO{k + 1}") for k, t in enumerate(raw)]


def mso_candidates(st: Structure, workers: int = 2, progress: bool = True) -> tuple[MsoSummary, list[Candidate]]:
    require_redundancy(st)
    summary = find_msos(st, workers=workers, progress=progress)
    if not summary.complete:
        raise KeyboardInterrupt
    return summary, candidates_from_summary(summary)
