"""The selection among realizable MSO sets and its generators (what `fdi-analyze export-c` emits)."""

from __future__ import annotations

from fdi_analysis.candidates import mso_candidates
from fdi_analysis.fault_matrix import Candidate
from fdi_analysis.model import Model
from fdi_analysis.mso.results import bits
from fdi_analysis.residuals.causality import synthesize
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.realizability import realizable_candidates
from fdi_analysis.residuals.solvability import Solver
from fdi_analysis.selection import optimal


def selected_generators(model: Model, workers: int = 2,
                        progress: bool = False) -> tuple[list[Candidate], list[Generator]]:
    """Optimal method-B selection among the realizable candidates (one smallest MSO per signature, the
    non-realizable ones dropped), and the synthesised generator of each selected test."""
    st = model.structure()
    _, cands = mso_candidates(st, workers=workers, progress=progress)
    solver = Solver(model)
    keep, _ = realizable_candidates(model, cands, solver)
    sel = optimal(keep, st.nf, "B")
    names = [e.id for e in model.equations]
    gens = [synthesize(model, [names[i] for i in bits(t.equations)], t.label, solver) for t in sel.tests]
    return list(sel.tests), gens
