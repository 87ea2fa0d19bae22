"""The selection among realizable MSO sets and its generators (what `fdi-analyze export-c` emits): the
practical selection of the thresholds file ([selection], `fdi-analyze practical`) when it has one, else the
optimal structural selection. The observer generators' gain design takes its `ObserverReference` from the
caller (the thresholds file's [observer] table, or a reference drive in the closed-loop tools); their fault
sensitivities (`sensitivity`) are computed with them."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from fdi_analysis.errors import ComputationError, FdiError
from fdi_analysis.fault_matrix import Candidate
from fdi_analysis.model import Model
from fdi_analysis.mso.results import bits
from fdi_analysis.residuals.causality import synthesize
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.observer import ObserverReference
from fdi_analysis.residuals.realizability import realizable_candidates
from fdi_analysis.residuals.sensitivity import with_sensitivities
from fdi_analysis.residuals.solvability import Solver
from fdi_analysis.residuals.uncertainty_sensitivity import UncertaintySolver, uncertainties, with_uncertainty
from fdi_analysis.selection import optimal
from fdi_analysis.selection.candidates import mso_candidates

SELECTION_TIME_LIMIT_S = 900.0


class SelectionError(FdiError, ValueError):
    """A [selection] test of the thresholds file that the model does not offer (any more)."""


def selected_generators(model: Model, reference: ObserverReference | None, workers: int = 2,
                        progress: bool = False, selection: Sequence[str] = (),
                        sensitivities: bool = False, uncertainty: bool = False, max_tyre_accel: float = 0.0
                        ) -> tuple[list[Candidate], list[Generator]]:
    """The tests on board and their synthesised generators: the `selection` (equation sets of realizable
    candidates, the thresholds file's [selection] table) in that order, or without one the optimal method-B
    selection among the realizable candidates (one smallest MSO per signature, the non-realizable ones
    dropped); with `sensitivities` each generator also carries its fault sensitivities, with `uncertainty` its
    sensitivities to the model's uncertain quantities; `max_tyre_accel` > 0 limits the domain of the generators with a
    tyre law (those with a minimum speed) to |(ax_m, ay_m)| <= it (`Generator.max_accel`)."""
    solver = Solver(model)
    keep = realizable(model, workers, progress, solver)
    tests = chosen_tests(model, keep, selection) if selection else structural_selection(model, keep)
    gens = generators(model, tests, reference, solver, sensitivities, uncertainty, progress)
    if max_tyre_accel > 0.0:
        gens = [replace(g, max_accel=max_tyre_accel) if g.min_speed > 0.0 else g for g in gens]
    return tests, gens


def generators(model: Model, tests: Sequence[Candidate], reference: ObserverReference | None,
               solver: Solver | None = None, sensitivities: bool = False, uncertainty: bool = False,
               progress: bool = False) -> list[Generator]:
    """The synthesised residual generator of each test (named by its label), with `uncertainty` carrying
    its uncertainty sensitivities (`residuals.uncertainty_sensitivity`; ~1-20 s per generator)."""
    solver = solver or Solver(model)
    names = [e.id for e in model.equations]
    gens = [synthesize(model, [names[i] for i in bits(t.equations)], t.label, solver, reference) for t in tests]
    if sensitivities:
        keep_faults = Solver(model, keep_faults=True)
        gens = [with_sensitivities(model, g, keep_faults) for g in gens]
    if uncertainty and uncertainties(model):
        us = UncertaintySolver(model)
        out = []
        for k, g in enumerate(gens):
            out.append(with_uncertainty(model, g, us))
            if progress:
                print(f"  uncertainty sensitivities: {k + 1}/{len(gens)} ({g.name}: {len(out[-1].uncertainty)})",
                      flush=True)
        gens = out
    return gens


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
        raise ComputationError(f"the optimal selection was not proven within {SELECTION_TIME_LIMIT_S:g} s")
    return list(sel.tests)


def chosen_tests(model: Model, keep: Sequence[Candidate], selection: Sequence[str]) -> list[Candidate]:
    """The realizable candidates (of `keep`) named by their equation sets in `selection`, in that order."""
    names = [e.id for e in model.equations]
    by_eqs = {" ".join(names[i] for i in bits(c.equations)): c for c in keep}
    chosen: set[int] = set()
    out: list[Candidate] = []
    for eqs in selection:
        c = by_eqs.get(" ".join(eqs.split()))
        if c is None:
            raise SelectionError(f"[selection] test '{eqs}' is not a realizable candidate MSO set of {model.name} "
                                 "(the model changed?): run `fdi-tune screen` and `fdi-analyze practical` again")
        if c.equations in chosen:
            raise SelectionError(f"[selection] test '{eqs}' ({c.label}) is listed twice")
        chosen.add(c.equations)
        out.append(c)
    return out
