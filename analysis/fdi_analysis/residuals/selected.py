"""The selection among realizable MSO sets and its generators (what `fdi-analyze export-c` emits): the
optimal structural selection, then the tests added for practical detectability (`fdi-tune augment`). The
observer generators' gain design takes its `ObserverReference` from the caller (the thresholds file's
[observer] table, or a reference drive in the closed-loop tools)."""

from __future__ import annotations

from collections.abc import Sequence

from fdi_analysis.candidates import mso_candidates
from fdi_analysis.fault_matrix import Candidate
from fdi_analysis.model import Model
from fdi_analysis.mso.results import bits
from fdi_analysis.residuals.causality import synthesize
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.observer import ObserverReference
from fdi_analysis.residuals.realizability import realizable_candidates
from fdi_analysis.residuals.solvability import Solver
from fdi_analysis.selection import optimal

SELECTION_TIME_LIMIT_S = 900.0


class AugmentError(ValueError):
    """An [augment] test of the thresholds file that the model does not offer (any more)."""


def selected_generators(model: Model, reference: ObserverReference | None, workers: int = 2,
                        progress: bool = False,
                        augment: Sequence[str] = ()) -> tuple[list[Candidate], list[Generator]]:
    """Optimal method-B selection among the realizable candidates (one smallest MSO per signature, the
    non-realizable ones dropped), followed by the `augment` tests (equation sets of realizable candidates,
    the thresholds file's [augment] table), and the synthesised generator of each test."""
    solver = Solver(model)
    keep = realizable(model, workers, progress, solver)
    tests = structural_selection(model, keep)
    tests += augmented_tests(model, keep, tests, augment)
    return tests, generators(model, tests, reference, solver)


def generators(model: Model, tests: Sequence[Candidate], reference: ObserverReference | None,
               solver: Solver | None = None) -> list[Generator]:
    """The synthesised residual generator of each test (named by its label)."""
    solver = solver or Solver(model)
    names = [e.id for e in model.equations]
    return [synthesize(model, [names[i] for i in bits(t.equations)], t.label, solver, reference) for t in tests]


def realizable(model: Model, workers: int = 2, progress: bool = False,
               solver: Solver | None = None) -> list[Candidate]:
    """The realizable candidates of the model (labels MSO<k> in candidate order)."""
    _, cands = mso_candidates(model.structure(), workers=workers, progress=progress)
    keep, _ = realizable_candidates(model, cands, solver or Solver(model))
    return keep


def structural_selection(model: Model, keep: Sequence[Candidate]) -> list[Candidate]:
    """The optimal method-B selection among the realizable candidates `keep`."""
    # a time limit far beyond the proof time (~10 s, ~60 s on a loaded 2-core machine): the committed files
    # must not depend on the machine's load (an unproven search could return another selection)
    sel = optimal(list(keep), model.structure().nf, "B", time_limit_s=SELECTION_TIME_LIMIT_S)
    if not sel.proven:
        raise RuntimeError(f"the optimal selection was not proven within {SELECTION_TIME_LIMIT_S:g} s")
    return list(sel.tests)


def augmented_tests(model: Model, keep: Sequence[Candidate], selection: Sequence[Candidate],
                    augment: Sequence[str]) -> list[Candidate]:
    """The realizable candidates (of `keep`) named by their equation sets in `augment`, in that order."""
    names = [e.id for e in model.equations]
    by_eqs = {" ".join(names[i] for i in bits(c.equations)): c for c in keep}
    chosen = {c.equations for c in selection}
    out: list[Candidate] = []
    for eqs in augment:
        c = by_eqs.get(" ".join(eqs.split()))
        if c is None:
            raise AugmentError(f"[augment] test '{eqs}' is not a realizable candidate MSO set of {model.name} "
                             "(the model changed?): run `fdi-tune augment` again")
        if c.equations in chosen:
            raise AugmentError(f"[augment] test '{eqs}' ({c.label}) is already a test of the selection")
        chosen.add(c.equations)
        out.append(c)
    return out
