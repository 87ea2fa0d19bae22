"""Random structures with a fixed seed, shaped like diagnosis models (for cross-checks against FDT)."""

from __future__ import annotations

import numpy as np

from fdi_analysis.structure import Structure


def random_structure(seed: int, ne: int, redundancy: int, nf: int, density: float = 0.08) -> Structure:
    """ne equations over ne - redundancy unknowns; each row gets 1-4 unknowns, some rows carry a fault."""
    rng = np.random.default_rng(seed)
    nx = ne - redundancy
    X = np.zeros((ne, nx), dtype=np.int8)
    for e in range(ne):
        k = int(rng.integers(1, 5))
        X[e, rng.choice(nx, size=min(k, nx), replace=False)] = 1
        X[e, rng.random(nx) < density / 4] = 1
    for v in range(nx):  # every unknown used
        if not X[:, v].any():
            X[int(rng.integers(ne)), v] = 1
    F = np.zeros((ne, nf), dtype=np.int8)
    for f in range(nf):
        F[int(rng.integers(ne)), f] = 1
    Z = np.zeros((ne, 0), dtype=np.int8)
    return Structure(
        equations=tuple(f"e{i + 1}" for i in range(ne)),
        unknowns=tuple(f"x{i + 1}" for i in range(nx)),
        knowns=(),
        faults=tuple(f"f{i + 1}" for i in range(nf)),
        X=X,
        F=F,
        Z=Z,
        name=f"random-{seed}",
    )


def sparse_random_structure(
    seed: int,
    ne: int,
    phi: int,
    *,
    nf: int = 12,
    maxdeg: int = 3,
    mindeg: int = 1,
    one_fault_per_equation: bool = False,
) -> Structure:
    """ne equations over ne - phi unknowns, each equation holding mindeg..maxdeg unknowns (MSO benchmarks).

    Faults: either each on a random equation with fault 0 also on a second one (a fault in two equations),
    or, with `one_fault_per_equation`, on distinct equations (what FDT's MTES assumes).
    """
    rng = np.random.default_rng(seed)
    nx = ne - phi
    X = np.zeros((ne, nx), dtype=np.int8)
    for e in range(ne):
        X[e, rng.choice(nx, size=int(rng.integers(mindeg, maxdeg + 1)), replace=False)] = 1
    for x in range(nx):
        if not X[:, x].any():
            X[rng.integers(ne), x] = 1
    F = np.zeros((ne, nf), dtype=np.int8)
    if one_fault_per_equation:
        for f, e in enumerate(rng.choice(ne, size=nf, replace=False)):
            F[e, f] = 1
    else:
        for f in range(nf):
            F[rng.integers(ne), f] = 1
        if nf > 2:
            F[rng.integers(ne), 0] = 1
    return Structure.from_fdt_dict({"X": X.tolist(), "F": F.tolist(), "name": f"random-{seed}"})
