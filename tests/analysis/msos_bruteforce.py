"""A deliberately naive MSO enumerator for small test inputs (independent of the native engine)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from fdi_analysis.dm import overdetermined_part, redundancy
from fdi_analysis.structure import Structure


def all_msos(st: Structure, eqs: npt.ArrayLike | None = None) -> set[frozenset[int]]:
    """Every MSO subset of `eqs` (default: all equations): removal search with a seen-set."""
    idx = np.arange(st.ne) if eqs is None else np.asarray(eqs, dtype=np.intp)
    seen: set[frozenset[int]] = set()
    found: set[frozenset[int]] = set()
    stack = [frozenset(int(e) for e in overdetermined_part(st.X, idx))]
    while stack:
        m = stack.pop()
        if m in seen or not m:
            continue
        seen.add(m)
        if redundancy(st.X, sorted(m)) == 1:
            found.add(m)
            continue
        for e in m:
            stack.append(frozenset(int(x) for x in overdetermined_part(st.X, sorted(m - {e}))))
    return found
