"""Dulmage-Mendelsohn decomposition of a bipartite equation/unknown structure.

Mixed causality, as in the paper: a differential constraint ``dx = d/dt x`` is an ordinary incidence of
both variables (derivatives may be computed and states may be integrated), so the decomposition works on
``X != 0``.

- M+ (structurally overdetermined part): the equations reachable from an unmatched equation by an
  alternating path of any maximum matching, with their variables. Its structural redundancy
  ``|M+| - |var(M+)|`` is the redundancy of the model.
- M- (underdetermined part): the variables reachable from an unmatched variable, with their equations.
- M0 (just-determined part): the rest, split into the strongly connected blocks of the matching's
  dependency graph, in an order in which they can be solved one after the other.
- The equivalence classes of M+ (Krysander et al. 2008): e and e' are equivalent when removing either
  removes the other from the overdetermined part; these are the "lumps" of the MSO algorithm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components, maximum_bipartite_matching

BoolMatrix = npt.NDArray[np.bool_]


@dataclass(frozen=True)
class DMResult:
    """Row/column index sets of the decomposition (indices into the structure passed in)."""

    plus_eqs: tuple[int, ...]
    plus_vars: tuple[int, ...]
    minus_eqs: tuple[int, ...]
    minus_vars: tuple[int, ...]
    zero_blocks: tuple[tuple[tuple[int, ...], tuple[int, ...]], ...]
    matching: tuple[int, ...]  # matching[e] = matched variable or -1

    @property
    def zero_eqs(self) -> tuple[int, ...]:
        return tuple(sorted(e for eqs, _ in self.zero_blocks for e in eqs))

    @property
    def zero_vars(self) -> tuple[int, ...]:
        return tuple(sorted(v for _, vs in self.zero_blocks for v in vs))

    @property
    def redundancy(self) -> int:
        """Structural redundancy of the overdetermined part: |M+| - |var(M+)|."""
        return len(self.plus_eqs) - len(self.plus_vars)

    @property
    def structural_rank(self) -> int:
        return sum(1 for v in self.matching if v >= 0)


def max_matching(X: BoolMatrix) -> npt.NDArray[np.int64]:
    """A maximum matching: for each row (equation) the matched column or -1 (Hopcroft-Karp)."""
    ne, nx = X.shape
    if ne == 0 or nx == 0:
        return np.full(ne, -1, dtype=np.int64)
    m = maximum_bipartite_matching(csr_matrix(X.astype(np.int8)), perm_type="column")
    return np.asarray(m, dtype=np.int64)


def dulmage_mendelsohn(X: npt.ArrayLike) -> DMResult:
    """Decompose the equation x unknown incidence `X` (any nonzero entry is an incidence)."""
    A = np.asarray(X) != 0
    ne, nx = A.shape
    row_match = max_matching(A)
    col_match = np.full(nx, -1, dtype=np.int64)
    for e, v in enumerate(row_match):
        if v >= 0:
            col_match[v] = e
    rows_of = [[int(i) for i in np.flatnonzero(A[:, v])] for v in range(nx)]
    cols_of = [[int(i) for i in np.flatnonzero(A[e])] for e in range(ne)]

    # M+: alternating BFS from unmatched equations (eq -edge-> var -matching-> eq).
    plus_e = np.zeros(ne, dtype=bool)
    plus_v = np.zeros(nx, dtype=bool)
    stack = [e for e in range(ne) if row_match[e] < 0]
    plus_e[stack] = True
    while stack:
        e = stack.pop()
        for v in cols_of[e]:
            if not plus_v[v]:
                plus_v[v] = True
                m = col_match[v]
                if m >= 0 and not plus_e[m]:
                    plus_e[m] = True
                    stack.append(int(m))

    # M-: alternating BFS from unmatched variables (var -edge-> eq -matching-> var).
    minus_e = np.zeros(ne, dtype=bool)
    minus_v = np.zeros(nx, dtype=bool)
    vstack = [v for v in range(nx) if col_match[v] < 0]
    minus_v[vstack] = True
    while vstack:
        v = vstack.pop()
        for e in rows_of[v]:
            if not minus_e[e]:
                minus_e[e] = True
                mv = int(row_match[e])
                if mv >= 0 and not minus_v[mv]:
                    minus_v[mv] = True
                    vstack.append(mv)

    zero_e = [e for e in range(ne) if not plus_e[e] and not minus_e[e]]
    blocks = _zero_blocks(A, zero_e, row_match, col_match)
    return DMResult(
        plus_eqs=tuple(int(i) for i in np.flatnonzero(plus_e)),
        plus_vars=tuple(int(i) for i in np.flatnonzero(plus_v)),
        minus_eqs=tuple(int(i) for i in np.flatnonzero(minus_e)),
        minus_vars=tuple(int(i) for i in np.flatnonzero(minus_v)),
        zero_blocks=blocks,
        matching=tuple(int(v) for v in row_match),
    )


def _zero_blocks(
    A: BoolMatrix, zero_e: list[int], row_match: npt.NDArray[np.int64], col_match: npt.NDArray[np.int64]
) -> tuple[tuple[tuple[int, ...], tuple[int, ...]], ...]:
    """Strongly connected blocks of M0 in a solvable order (a block only needs earlier blocks)."""
    if not zero_e:
        return ()
    pos = {e: k for k, e in enumerate(zero_e)}
    n = len(zero_e)
    # Edge a -> b when equation a needs the variable that equation b is matched to (b must come first).
    src, dst = [], []
    for a in zero_e:
        for v in np.flatnonzero(A[a]):
            b = int(col_match[v])
            if b != a and b in pos:
                src.append(pos[a])
                dst.append(pos[b])
    g = csr_matrix((np.ones(len(src), dtype=np.int8), (src, dst)), shape=(n, n))
    ncomp, labels = connected_components(g, directed=True, connection="strong")
    # Topological order of the condensation: a block depends on the blocks it points to.
    deps: list[set[int]] = [set() for _ in range(ncomp)]
    for s, d in zip(src, dst, strict=True):
        if labels[s] != labels[d]:
            deps[labels[s]].add(int(labels[d]))
    order: list[int] = []
    done = [False] * ncomp
    for start in range(ncomp):  # iterative DFS post-order (no recursion)
        if done[start]:
            continue
        stack: list[tuple[int, list[int]]] = [(start, sorted(deps[start]))]
        done[start] = True
        while stack:
            node, todo = stack[-1]
            if todo:
                nxt = todo.pop()
                if not done[nxt]:
                    done[nxt] = True
                    stack.append((nxt, sorted(deps[nxt])))
            else:
                order.append(node)
                stack.pop()
    out = []
    for comp in order:
        eqs = tuple(sorted(zero_e[k] for k in range(n) if labels[k] == comp))
        out.append((eqs, tuple(sorted(int(row_match[e]) for e in eqs))))
    return tuple(out)


def overdetermined_part(X: npt.ArrayLike, eqs: npt.ArrayLike | None = None) -> npt.NDArray[np.intp]:
    """Indices (into the full structure) of the M+ equations of the subsystem `eqs` (default: all)."""
    A = np.asarray(X) != 0
    idx = np.arange(A.shape[0]) if eqs is None else np.asarray(eqs, dtype=np.intp)
    if idx.size == 0:
        return idx
    sub = A[idx]
    dm = dulmage_mendelsohn(sub[:, sub.any(axis=0)])
    return idx[list(dm.plus_eqs)]


def redundancy(X: npt.ArrayLike, eqs: npt.ArrayLike | None = None) -> int:
    """Structural redundancy of the subsystem `eqs`: |M+| - |var(M+)|."""
    A = np.asarray(X) != 0
    idx = np.arange(A.shape[0]) if eqs is None else np.asarray(eqs, dtype=np.intp)
    if idx.size == 0:
        return 0
    sub = A[idx]
    return dulmage_mendelsohn(sub[:, sub.any(axis=0)]).redundancy


def equivalence_classes(X: npt.ArrayLike) -> list[tuple[int, ...]]:
    """The equivalence classes of the overdetermined part M+ (indices into `X`)."""
    A = np.asarray(X) != 0
    plus = overdetermined_part(A)
    remaining = set(int(e) for e in plus)
    classes = []
    for e in sorted(remaining):
        if e not in remaining:
            continue
        rest = np.array(sorted(set(int(x) for x in plus) - {e}), dtype=np.intp)
        kept = set(int(x) for x in overdetermined_part(A, rest))
        cls = tuple(sorted(set(int(x) for x in plus) - kept))
        classes.append(cls)
        remaining -= set(cls)
    return classes
