"""Selection within a cost budget: the tests that meet the most requirements of the practical selection
(`selection.practical`: detect every fault, separate every structurally isolable pair, in every manoeuvre) while
their summed cost (operations per step) stays within a budget; and the sweep of budgets that shows what a smaller
ECU gives up.

The practical selection meets every requirement that some candidate meets, at least cost. Under a budget it may
not: this is a weighted maximum coverage with a knapsack constraint, solved exactly as a 0-1 linear program with
HiGHS (scipy.optimize.milp):

    maximise  sum_k w_k y_k - eps * sum_t c_t x_t
    s.t.      y_k <= sum_{t covers row k} x_t     (a distinct row of candidates meeting w_k requirements)
              sum_t c_t x_t <= budget,   x, y in {0, 1}

with eps = 1 / (sum_t c_t + 1), so that no saving of cost ever outweighs one requirement: among the selections
meeting the most requirements, the cheapest. Detections come first: a detection weighs more than all separations
together (an undetected fault is not diagnosed at all, an unseparated pair is diagnosed as a pair), so the
selection detects as many (fault, manoeuvre) pairs as the budget allows and, among those selections, separates
the most pairs. The result says how many of each kind it meets.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from fdi_analysis.errors import ComputationError
from fdi_analysis.names import natural_key
from fdi_analysis.selection.practical import PracticalCandidate, Requirement, requirements


@dataclass(frozen=True)
class BudgetSelection:
    """The best selection within `budget`: its tests and their summed cost, how many of the `meetable`
    requirements (those some candidate meets) it meets, detections and separations apart, and the meetable ones it
    gives up."""

    budget: int
    tests: tuple[PracticalCandidate, ...]
    cost: int
    detections: int
    separations: int
    meetable_detections: int
    meetable_separations: int
    given_up: tuple[Requirement, ...] = ()

    @property
    def met(self) -> int:
        return self.detections + self.separations

    @property
    def meetable(self) -> int:
        return self.meetable_detections + self.meetable_separations


def select_within_budget(candidates: Sequence[PracticalCandidate], faults: Sequence[str],
                         scenarios: Sequence[str], budget: int) -> BudgetSelection:
    """The cheapest of the selections that detect the most, then separate the most, at a summed cost <= budget
    (module doc)."""
    return budget_sweep(candidates, faults, scenarios, [budget])[0]


def budget_sweep(candidates: Sequence[PracticalCandidate], faults: Sequence[str], scenarios: Sequence[str],
                 budgets: Sequence[int], progress: Callable[[BudgetSelection], None] | None = None
                 ) -> list[BudgetSelection]:
    """`select_within_budget` for each budget (the requirements built once); `progress` sees each result."""
    reqs, _, _ = requirements(candidates, faults, scenarios)
    costs = [max(1, t.cost) for t in candidates]
    out: list[BudgetSelection] = []
    for b in budgets:
        if b < 0:
            raise ValueError(f"budget {b}: must be >= 0")
        chosen = _solve(reqs, costs, b)
        out.append(_scored(b, [candidates[i] for i in chosen], [costs[i] for i in chosen], reqs, set(chosen)))
        if progress is not None:
            progress(out[-1])
    return out


def _scored(budget: int, tests: list[PracticalCandidate], costs: list[int], reqs: Sequence[Requirement],
            chosen: set[int]) -> BudgetSelection:
    met = [r for r in reqs if chosen.intersection(r.cover)]
    n_det = sum(1 for r in reqs if not r.fault_b)
    det = sum(1 for r in met if not r.fault_b)
    order = sorted(range(len(tests)), key=lambda i: natural_key(tests[i].label))
    return BudgetSelection(budget, tuple(tests[i] for i in order), sum(costs), det, len(met) - det, n_det,
                           len(reqs) - n_det, tuple(r for r in reqs if not chosen.intersection(r.cover)))


def _solve(reqs: Sequence[Requirement], costs: Sequence[int], budget: int) -> list[int]:
    from scipy.optimize import Bounds, LinearConstraint, milp
    from scipy.sparse import coo_matrix

    heavy = 1 + sum(1 for r in reqs if r.fault_b)  # a detection outweighs every separation together
    weight: Counter[tuple[int, ...]] = Counter()
    for r in reqs:
        weight[tuple(sorted(r.cover))] += 1 if r.fault_b else heavy
    rows = sorted(weight)
    n, m = len(costs), len(rows)
    if n == 0 or m == 0:
        return []
    # constraint rows 0..m-1: y_k - sum_{t in row k} x_t <= 0; row m: sum_t c_t x_t <= budget
    ri: list[int] = []
    ci: list[int] = []
    val: list[float] = []
    for k, row in enumerate(rows):
        ri += [k] * (len(row) + 1)
        ci += [*row, n + k]
        val += [-1.0] * len(row) + [1.0]
    ri += [m] * n
    ci += list(range(n))
    val += [float(c) for c in costs]
    a = coo_matrix((val, (ri, ci)), shape=(m + 1, n + m)).tocsr()
    ub = np.zeros(m + 1)
    ub[m] = float(budget)
    eps = 1.0 / (float(sum(costs)) + 1.0)
    obj = np.concatenate([eps * np.asarray(costs, dtype=float), -np.asarray([weight[r] for r in rows], dtype=float)])
    res = milp(obj, constraints=LinearConstraint(a, lb=np.full(m + 1, -np.inf), ub=ub),
               integrality=np.ones(n + m), bounds=Bounds(0.0, 1.0), options={"mip_rel_gap": 0.0})
    if not res.success:
        raise ComputationError(f"selection within budget {budget}: HiGHS found no solution ({res.message})")
    return [i for i in range(n) if res.x[i] > 0.5]
