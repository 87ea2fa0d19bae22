"""Hypothesis strategies for small random diagnosis structures (shared by the property tests)."""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

from fdi_analysis.structure import Structure


@st.composite
def structures(draw: st.DrawFn, max_eqs: int = 10, max_faults: int = 5, min_redundancy: int = 0) -> Structure:
    """ne equations over nx <= ne - min_redundancy unknowns, 1-3 unknowns per equation, every unknown used,
    each fault on 1-2 random equations. Small enough for the brute-force references."""
    ne = draw(st.integers(min_value=2, max_value=max_eqs))
    nx = draw(st.integers(min_value=1, max_value=max(1, ne - min_redundancy)))
    X = np.zeros((ne, nx), dtype=np.int8)
    for e in range(ne):
        cols = draw(st.lists(st.integers(0, nx - 1), min_size=1, max_size=min(3, nx), unique=True))
        X[e, cols] = 1
    for v in range(nx):
        if not X[:, v].any():
            X[draw(st.integers(0, ne - 1)), v] = 1
    nf = draw(st.integers(min_value=1, max_value=max_faults))
    F = np.zeros((ne, nf), dtype=np.int8)
    for f in range(nf):
        rows = draw(st.lists(st.integers(0, ne - 1), min_size=1, max_size=2, unique=True))
        F[rows, f] = 1
    return Structure.from_fdt_dict({"X": X.tolist(), "F": F.tolist(), "name": "hypothesis"})
