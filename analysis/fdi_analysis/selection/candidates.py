"""Candidate tests for the selection, numbered in order of cost (unknowns), then size, then equations.

- MSO candidates (`mso_candidates`): one MSO set per distinct fault signature, the smallest. The MSO search
  aggregates every MSO set into its fault-signature table without storing the sets; the cheapest MSO of each
  signature represents it (tests with one fault set clear the same fault-matrix elements). Numbered MSO1,
  MSO2, ...
- MTES candidates (`mtes_candidates`), for models too large to enumerate: one MTES per distinct fault
  support. The MTES search (`fdi_analysis.mso.mtes`) visits a number of nodes that grows with the number of
  distinct fault supports, not with the number of MSO sets (the full vertical ROMO model has about 1.6e9 MSO
  sets and 215,186 MTES). Each distinct fault support is represented by its cheapest MTES (fewest unknowns,
  then fewest equations); numbered MTES1, MTES2, ... `full_isolability_reached` tells whether these
  candidates isolate every pair that the whole model isolates (structural isolability by DM decompositions,
  no enumeration).
"""

from __future__ import annotations

import numpy as np

from fdi_analysis.fault_matrix import Candidate
from fdi_analysis.mso import MsoSummary, bits, find_msos, isolability, isolability_from_signatures, mtes
from fdi_analysis.mso.results import MtesResult
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


def candidates_from_mtes(st: Structure, result: MtesResult) -> list[Candidate]:
    if not result.mtes:
        return []
    nbytes = (st.ne + 7) // 8
    packed = np.frombuffer(b"".join(t.equations.to_bytes(nbytes, "little") for t in result.mtes), dtype=np.uint8)
    member = np.unpackbits(packed.reshape(len(result.mtes), nbytes), axis=1, bitorder="little")[:, :st.ne]
    n_eqs = member.sum(axis=1)
    n_unknowns = ((member.astype(np.float32) @ st.incidence.astype(np.float32)) > 0).sum(axis=1)
    best: dict[int, tuple[int, int, int]] = {}  # faults -> (unknowns, equations, equation set)
    for t, unk, neq in zip(result.mtes, n_unknowns.tolist(), n_eqs.tolist(), strict=True):
        key = (unk, neq, t.equations)
        cur = best.get(t.faults)
        if cur is None or key < cur:
            best[t.faults] = key
    raw = sorted(best.items(), key=lambda kv: (kv[1], kv[0]))
    return [Candidate(equations=eqs, faults=f, cost=unk, label=f"MTES{k + 1}")
            for k, (f, (unk, _, eqs)) in enumerate(raw)]


def mtes_candidates(st: Structure) -> tuple[MtesResult, list[Candidate]]:
    require_redundancy(st)
    result = mtes(st)
    return result, candidates_from_mtes(st, result)


def full_isolability_reached(st: Structure, cands: list[Candidate]) -> bool:
    """True when the candidates isolate (and detect) exactly what the structure allows."""
    structural = isolability(st)
    reached = isolability_from_signatures(st.nf, frozenset(c.faults for c in cands))
    detected = np.zeros(st.nf, dtype=bool)
    for c in cands:
        detected[bits(c.faults)] = True
    return bool(np.array_equal(reached, structural.isolable) and np.array_equal(detected, structural.detectable))
