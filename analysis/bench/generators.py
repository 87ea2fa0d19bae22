"""Random structures for the MSO benchmark, from generators the engine was never tuned on.

The engine was developed against `fdi_analysis.random_structures.sparse_random_structure` (each equation
picks 1-3 unknowns uniformly from the whole model). The benchmark measures on other shapes:

* `banded`: a chain of components, as in physical models; equation e holds 1-`deg` unknowns from a window
  around its position, so coupling is local (long MSO sets along the chain);
* `bernoulli`: every entry of X is set with probability p (denser or sparser than the tuning models),
  every equation holds at least one unknown;
* `clustered`: subsystems of 8-20 equations, dense inside, few links between them (the shape of vehicle
  models: wheel corners around a body).

All take (seed, equations, nominal redundancy = equations - unknowns) and return a Structure in FDT's
MatrixStruc form, with `nf` faults each on one equation (what FDT's MTES assumes).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from fdi_analysis.structure import Structure

Matrix = npt.NDArray[np.int8]


def _finish(X: Matrix, rng: np.random.Generator, nf: int, name: str) -> Structure:
    ne, nx = X.shape
    for x in range(nx):  # every unknown in some equation
        if not X[:, x].any():
            X[int(rng.integers(ne)), x] = 1
    F = np.zeros((ne, nf), dtype=np.int8)
    for f, e in enumerate(rng.choice(ne, size=min(nf, ne), replace=False)):
        F[e, f] = 1
    return Structure.from_fdt_dict({"X": X.tolist(), "F": F.tolist(), "name": name})


def banded(seed: int, ne: int, phi: int, *, deg: int = 3, width: int = 4, nf: int = 10) -> Structure:
    rng = np.random.default_rng(seed)
    nx = ne - phi
    X = np.zeros((ne, nx), dtype=np.int8)
    for e in range(ne):
        centre = int(e * nx / ne)
        lo, hi = max(0, centre - width), min(nx, centre + width + 1)
        k = int(rng.integers(1, deg + 1))
        X[e, rng.choice(np.arange(lo, hi), size=min(k, hi - lo), replace=False)] = 1
    return _finish(X, rng, nf, f"banded-{seed}")


def bernoulli(seed: int, ne: int, phi: int, *, p: float = 0.04, nf: int = 10) -> Structure:
    rng = np.random.default_rng(seed)
    nx = ne - phi
    X = (rng.random((ne, nx)) < p).astype(np.int8)
    for e in range(ne):
        if not X[e].any():
            X[e, int(rng.integers(nx))] = 1
    return _finish(X, rng, nf, f"bernoulli-{seed}")


def clustered(seed: int, ne: int, phi: int, *, links: float = 0.1, nf: int = 10) -> Structure:
    rng = np.random.default_rng(seed)
    nx = ne - phi
    X = np.zeros((ne, nx), dtype=np.int8)
    e0 = x0 = 0
    while e0 < ne:
        size = int(min(rng.integers(8, 21), ne - e0))
        nxc = max(1, round(size * nx / ne)) if e0 + size < ne else max(1, nx - x0)
        nxc = min(nxc, nx - x0) if nx - x0 > 0 else 1
        cols = np.arange(x0, x0 + nxc) if x0 + nxc <= nx else rng.choice(nx, size=nxc, replace=False)
        for e in range(e0, e0 + size):
            k = int(rng.integers(1, 4))
            X[e, rng.choice(cols, size=min(k, len(cols)), replace=False)] = 1
            if rng.random() < links:  # a link to another subsystem
                X[e, int(rng.integers(nx))] = 1
        e0 += size
        x0 = min(nx, x0 + nxc)
    return _finish(X, rng, nf, f"clustered-{seed}")
