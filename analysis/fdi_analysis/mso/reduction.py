"""Step 4 of the paper: replace intermediate variables by known signals.

An intermediate variable is an unknown that a chain ("tree") of fault-free equations computes from known
variables: repeatedly, a fault-free equation whose unknowns are all computed except one computes that one
(mixed causality: a differential constraint dx = d/dt x computes dx from x and x from dx). The reduced
structure drops those equations and variables; where a variable appeared in a remaining equation, a new
known `<name>~` takes its place.

Why only low-priority MSO sets disappear. Let T be the tree equations and V the variables they compute
(|T| = |V|, each tree equation computes its own variable, fault-free).
* Every MSO set S' of the reduced structure gives an MSO set S' + (tree equations of the variables it uses)
  of the full structure with the same faults (the added part is just-determined and fault-free), so no
  fault signature is invented.
* Fault i is isolable from fault j in the full structure iff some equation of i is in (M - E_j)+. The tree
  variables are computable in M - E_j as well (the tree is fault-free), so eliminating T and V leaves the
  overdetermined part unchanged apart from T itself: the single-fault isolability (and detectability) is
  the same. An MSO set of the full structure that is lost therefore has a fault set that other MSO sets
  cover as a union; it adds nothing to isolation. The tests check both statements (isolability equal,
  every lost signature a union of kept ones) on ROMO and on random structures.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..structure import DIFF_DERIVATIVE, DIFF_INTEGRATED, INCIDENCE, Structure


@dataclass(frozen=True)
class Reduction:
    """Reduced structure and how it was obtained.

    ``intermediate`` lists (variable, equation that computes it) in computation order; ``kept[k]`` is the
    index in the original structure of equation k of the reduced one; ``new_knowns[v]`` names the known that
    replaces variable v.
    """

    structure: Structure
    intermediate: tuple[tuple[str, str], ...]
    kept: tuple[int, ...]
    new_knowns: dict[str, str]


def intermediate_variables(structure: Structure) -> list[tuple[int, int]]:
    """(variable, equation) pairs, in an order in which each equation computes its variable from known
    signals and earlier variables; only fault-free equations are used."""
    inc = structure.incidence
    faulty = [bool(v) for v in np.any(structure.F != 0, axis=1)]
    rows = [set(np.flatnonzero(inc[e]).tolist()) for e in range(structure.ne)]
    computed: set[int] = set()
    used: set[int] = set()
    order: list[tuple[int, int]] = []
    changed = True
    while changed:
        changed = False
        for e in range(structure.ne):
            if faulty[e] or e in used:
                continue
            rest = rows[e] - computed
            if len(rest) == 1:
                (x,) = rest
                computed.add(x)
                used.add(e)
                order.append((x, e))
                changed = True
    return order


def reduce_intermediate(structure: Structure) -> Reduction:
    order = intermediate_variables(structure)
    if not order:
        return Reduction(structure, (), tuple(range(structure.ne)), {})
    vars_out = sorted(x for x, _ in order)
    eqs_out = {e for _, e in order}
    kept = [e for e in range(structure.ne) if e not in eqs_out]
    keep_x = [x for x in range(structure.nx) if x not in set(vars_out)]
    taken = set(structure.knowns) | set(structure.unknowns)
    new_names: dict[str, str] = {}
    for x in vars_out:
        name = structure.unknowns[x] + "~"
        while name in taken:
            name += "~"
        taken.add(name)
        new_names[structure.unknowns[x]] = name
    X = structure.X[np.ix_(kept, keep_x)].copy()
    # a differential constraint that lost one side is an ordinary equation of the other side
    for r in range(X.shape[0]):
        row = X[r]
        if (np.count_nonzero(row == DIFF_DERIVATIVE) + np.count_nonzero(row == DIFF_INTEGRATED)) == 1:
            row[(row == DIFF_DERIVATIVE) | (row == DIFF_INTEGRATED)] = INCIDENCE
    Znew = (structure.X[np.ix_(kept, vars_out)] != 0).astype(np.int8)
    Z = np.hstack([structure.Z[kept], Znew]) if structure.nz or Znew.size else structure.Z[kept]
    reduced = Structure(
        equations=tuple(structure.equations[e] for e in kept),
        unknowns=tuple(structure.unknowns[x] for x in keep_x),
        knowns=structure.knowns + tuple(new_names[structure.unknowns[x]] for x in vars_out),
        faults=structure.faults,
        X=X,
        F=structure.F[kept].copy(),
        Z=Z.astype(np.int8),
        name=(structure.name + " (intermediate variables reduced)").strip(),
        equation_kinds=tuple(structure.equation_kinds[e] for e in kept) if structure.equation_kinds else (),
    )
    return Reduction(
        structure=reduced,
        intermediate=tuple((structure.unknowns[x], structure.equations[e]) for x, e in order),
        kept=tuple(kept),
        new_knowns=new_names,
    )
