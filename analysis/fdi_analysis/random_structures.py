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
