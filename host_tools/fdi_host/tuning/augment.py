"""Tests added to the structural selection for practical detectability.

The optimal selection is structural: every fault of a test's signature is detectable in principle, but a
fault can be so weak against a test's fault-free noise that no size within the fault's physical limit crosses
the gate ("not detectable by this test in practice" in the fault-size sweep). For each fault that no test of
the structural selection detects in practice, the realizable candidate MSO sets whose signature holds it are
tried in candidate order (fewest unknowns first, the order of the MSO labels), at most `tries` of them: each
is synthesised, calibrated on the fault-free drives as `fdi-tune calibrate` does, and swept with the fault
as `fdi-tune fault-sizes` does; the first one with a stated size within the limit is added. An added test
also covers the other undetected faults of its signature that it detects (swept too). Isolability does not
change: the structural selection already reaches the model's maximal isolability; added tests only bring
evidence where the selected ones are blind in practice.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from fdi_analysis.export.fault_sizes import FaultSizesError
from fdi_analysis.fault_matrix import Candidate
from fdi_analysis.model import Model
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.observer import ObserverReference
from fdi_analysis.residuals.reasons import NotRealizableError
from fdi_analysis.residuals.selected import generators
from fdi_analysis.residuals.solvability import Solver
from fdi_host.tuning.sweep import PairLimit

DEFAULT_TRIES = 6


class AugmentError(FaultSizesError):
    """The fault-size file does not describe the selection's tests."""


@dataclass(frozen=True)
class Added:
    """A test added to the selection: its generator, calibrated sigma and the faults it covers."""

    generator: Generator
    sigma: float
    covers: Mapping[str, PairLimit]  # undetected fault -> its detection limit in this test

    def comment(self) -> str:
        what = ", ".join(f"{f} from {p.detected_at:g} (stated {p.stated:g})" for f, p in self.covers.items())
        g = self.generator
        return f"{g.name} (residual {g.residual_equation}, sigma {self.sigma:.3g}): detects {what}"


def undetected_faults(per_test: Mapping[str, Mapping[str, float | str]], gens: Sequence[Generator]) -> list[str]:
    """The faults of the tests' signatures that no test detects in practice (no stated size in `per_test`, the
    [per_test.<fault>] tables of the fault-size file), in fault order."""
    faults = sorted({f for g in gens for f in g.faults}, key=lambda f: int(f[1:]))
    out = []
    for f in faults:
        row = per_test.get(f, {})
        missing = [g.name for g in gens if f in g.faults and g.name not in row]
        if missing:
            raise AugmentError(f"the fault-size file has no entry for {f} in {', '.join(missing)}: "
                               "run `fdi-tune fault-sizes` first")
        if not any(isinstance(row[g.name], int | float) for g in gens if f in g.faults):
            out.append(f)
    return out


def augment(model: Model, candidates: Sequence[Candidate], selection: Sequence[Candidate], undetected: Sequence[str],
            sigma_of: Callable[[Generator], float], sweep: Callable[[Generator, float, str], PairLimit],
            reference: ObserverReference | None, tries: int = DEFAULT_TRIES,
            log: Callable[[str], None] | None = None,
            solver: Solver | None = None) -> tuple[list[Added], list[str]]:
    """(tests added, faults still undetected): see the module docstring. `candidates` are the realizable
    candidates in candidate order; `sigma_of` calibrates a generator, `sweep` finds a fault's detection limit
    in a generator with that sigma; `reference` designs the observer generators' gains."""
    say = log or (lambda _s: None)
    fault_names = list(model.structure().faults)
    used = {c.equations for c in selection}
    solver = solver or Solver(model)
    added: list[Added] = []
    left: list[str] = []
    todo = list(undetected)
    while todo:
        f = todo.pop(0)
        k = fault_names.index(f)
        pool = [c for c in candidates if (c.faults >> k) & 1 and c.equations not in used][:tries]
        found = None
        for c in pool:
            try:
                (g,) = generators(model, [c], reference, solver)
            except NotRealizableError as exc:
                say(f"{f}: {c.label} skipped: {exc}")
                continue
            sigma = sigma_of(g)
            p = sweep(g, sigma, f)
            say(f"{f}: {c.label} (residual {g.residual_equation}, sigma {sigma:.3g}): "
                + (f"stated size {p.stated:g}" if p.stated is not None else "not detectable in practice"))
            if p.stated is not None:
                covers = {f: p}
                for other in [o for o in todo if o in g.faults]:
                    q = sweep(g, sigma, other)
                    say(f"{other}: {c.label}: " + (f"stated size {q.stated:g}" if q.stated is not None
                                                   else "not detectable in practice"))
                    if q.stated is not None:
                        covers[other] = q
                        todo.remove(other)
                found = Added(g, sigma, covers)
                used.add(c.equations)
                break
        if found is None:
            left.append(f)
            say(f"{f}: none of the first {len(pool)} candidates detects it within its limit")
        else:
            added.append(found)
    return added, left
