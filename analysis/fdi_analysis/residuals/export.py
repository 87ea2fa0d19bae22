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

SELECTION_TIME_LIMIT_S = 900.0


def selected_generators(model: Model, workers: int = 2,
                        progress: bool = False) -> tuple[list[Candidate], list[Generator]]:
    """Optimal method-B selection among the realizable candidates (one smallest MSO per signature, the
    non-realizable ones dropped), and the synthesised generator of each selected test."""
    st = model.structure()
    _, cands = mso_candidates(st, workers=workers, progress=progress)
    solver = Solver(model)
    keep, _ = realizable_candidates(model, cands, solver)
    # a time limit far beyond the proof time (~10 s, ~60 s on a loaded 2-core machine): the committed files
    # must not depend on the machine's load (an unproven search could return another selection)
    sel = optimal(keep, st.nf, "B", time_limit_s=SELECTION_TIME_LIMIT_S)
    if not sel.proven:
        raise RuntimeError(f"the optimal selection was not proven within {SELECTION_TIME_LIMIT_S:g} s")
    names = [e.id for e in model.equations]
    gens = [synthesize(model, [names[i] for i in bits(t.equations)], t.label, solver) for t in sel.tests]
    return list(sel.tests), gens
