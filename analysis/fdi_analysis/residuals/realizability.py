"""Fast realizability check of many MSO sets (candidate filtering before the test selection).

One pass of `causality.closure` per MSO set (structural, the sympy solutions are cached per model), plus,
where it would integrate one state open loop, one pass with that state estimated by an observer
(`causality.observer_closure`), so all 16,635 candidates of the grouped ROMO model are checked in
seconds. `causality.synthesize` later tries
every residual equation of the selected sets and builds the expressions.
"""

from __future__ import annotations

from collections.abc import Sequence

from fdi_analysis.fault_matrix import Candidate
from fdi_analysis.model import Model
from fdi_analysis.mso.results import bits
from fdi_analysis.residuals.causality import closure, observer_closure, open_loop_state
from fdi_analysis.residuals.reasons import Reason, Rejection
from fdi_analysis.residuals.solvability import Solver


def why_not_realizable(model: Model, solver: Solver, eq_ids: Sequence[str],
                       observer: bool = True) -> Rejection | None:
    """None when the MSO set has a sequential residual generator (with `observer`: possibly with one state
    estimated by an observer where the plain sequence would integrate it open loop), else the reason."""
    p = closure(model, solver, eq_ids, None)
    if isinstance(p, Rejection) and observer and open_loop_state(p) is not None:
        p = observer_closure(model, solver, eq_ids, None, p)
    return p if isinstance(p, Rejection) else None


def realizable_candidates(model: Model, candidates: Sequence[Candidate], solver: Solver | None = None,
                          observer: bool = True,
                          with_observer: list[Candidate] | None = None) -> tuple[list[Candidate], dict[Reason, int]]:
    """The realizable candidates (labels kept) and a count of the rejection reasons by kind; `observer`
    False keeps only the sequential generators without an observer state. `with_observer`, when given,
    receives the realizable candidates that need the observer state."""
    solver = solver or Solver(model)
    names = [e.id for e in model.equations]
    keep: list[Candidate] = []
    reasons: dict[Reason, int] = {}
    for c in candidates:
        ids = [names[i] for i in bits(c.equations)]
        why = why_not_realizable(model, solver, ids, observer)
        if why is None:
            keep.append(c)
            if with_observer is not None and observer and isinstance(closure(model, solver, ids, None), Rejection):
                with_observer.append(c)
        else:
            reasons[why.kind] = reasons.get(why.kind, 0) + 1
    return keep, reasons
