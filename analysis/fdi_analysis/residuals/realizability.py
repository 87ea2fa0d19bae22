"""Fast realizability check of many MSO sets (candidate filtering before the test selection).

One pass of `causality.closure` per MSO set (structural, the sympy solutions are cached per model), so
all 16,635 candidates of the grouped ROMO model are checked in seconds. `causality.synthesize` later tries
every residual equation of the selected sets and builds the expressions.
"""

from __future__ import annotations

from collections.abc import Sequence

from fdi_analysis.fault_matrix import Candidate
from fdi_analysis.model import Model
from fdi_analysis.mso.results import bits
from fdi_analysis.residuals.causality import closure
from fdi_analysis.residuals.solvability import Solver


def why_not_realizable(model: Model, solver: Solver, eq_ids: Sequence[str]) -> str | None:
    """None when the MSO set has a sequential residual generator, else the reason."""
    p = closure(model, solver, eq_ids, None)
    return p if isinstance(p, str) else None


def realizable_candidates(model: Model, candidates: Sequence[Candidate],
                          solver: Solver | None = None) -> tuple[list[Candidate], dict[str, int]]:
    """The realizable candidates (labels kept) and a count of the rejection reasons (by kind)."""
    solver = solver or Solver(model)
    names = [e.id for e in model.equations]
    keep: list[Candidate] = []
    reasons: dict[str, int] = {}
    for c in candidates:
        why = why_not_realizable(model, solver, [names[i] for i in bits(c.equations)])
        if why is None:
            keep.append(c)
        else:
            kind = why.split(" is ", 1)[1].split(" with")[0] if " is reachable only by integrating" in why else \
                why.split(";")[0]
            reasons[kind] = reasons.get(kind, 0) + 1
    return keep, reasons
