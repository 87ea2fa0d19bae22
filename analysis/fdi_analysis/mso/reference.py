"""Small pure-Python reference implementations, for cross-checking the native engine in tests only.

Straightforward and slow on purpose: own bipartite matching, the basic MSO algorithm (remove one equation
at a time, take the overdetermined part, recurse, remember visited sets), brute-force MTES and
isolability from their definitions.
"""

from __future__ import annotations

from itertools import combinations

from ..structure import Structure
from .results import bits


def _rows(structure: Structure) -> list[frozenset[int]]:
    return [frozenset(int(v) for v in row.nonzero()[0]) for row in structure.incidence]


def _faults(structure: Structure) -> list[int]:
    out = []
    for row in structure.F:
        m = 0
        for f in row.nonzero()[0]:
            m |= 1 << int(f)
        out.append(m)
    return out


def mplus(rows: list[frozenset[int]], eqs: frozenset[int]) -> frozenset[int]:
    """Overdetermined part of an equation set: equations free in some maximum matching."""
    var_eq: dict[int, int] = {}
    eq_var: dict[int, int] = {}
    col: dict[int, list[int]] = {}
    for e in sorted(eqs):
        for v in rows[e]:
            col.setdefault(v, []).append(e)

    def augment(v: int, seen: set[int]) -> bool:
        for e in col[v]:
            if e not in seen:
                seen.add(e)
                if e not in eq_var or augment(eq_var[e], seen):
                    eq_var[e] = v
                    var_eq[v] = e
                    return True
        return False

    for v in sorted(col):
        augment(v, set())
    reach = {e for e in eqs if e not in eq_var}
    stack = list(reach)
    while stack:
        w = stack.pop()
        for v in rows[w]:
            u = var_eq.get(v)
            if u is not None and u not in reach:
                reach.add(u)
                stack.append(u)
    return frozenset(reach)


def msos(structure: Structure) -> set[int]:
    """All MSO sets (bitsets) by the basic removal algorithm."""
    rows = _rows(structure)
    found: set[int] = set()
    seen: set[frozenset[int]] = set()

    def rec(s: frozenset[int]) -> None:
        if not s or s in seen:
            return
        seen.add(s)
        nvars = len(frozenset().union(*(rows[e] for e in s)))
        if len(s) - nvars == 1:
            found.add(sum(1 << e for e in s))
            return
        for e in s:
            rec(mplus(rows, s - {e}))

    rec(mplus(rows, frozenset(range(structure.ne))))
    return found


def isolability(structure: Structure) -> tuple[list[bool], list[list[bool]]]:
    """(detectable[i], isolable[i][j]): fault i is isolable from fault j (definition: some equation of fault i
    lies in the overdetermined part of the model without the equations of fault j)."""
    rows = _rows(structure)
    allq = frozenset(range(structure.ne))
    feq = [frozenset(int(e) for e in structure.F[:, f].nonzero()[0]) for f in range(structure.nf)]
    mp = mplus(rows, allq)
    det = [bool(feq[i] & mp) for i in range(structure.nf)]
    iso = [[False] * structure.nf for _ in range(structure.nf)]
    for j in range(structure.nf):
        mj = mplus(rows, allq - feq[j])
        for i in range(structure.nf):
            iso[i][j] = i != j and bool(feq[i] & mj)
    return det, iso


def mtes(structure: Structure) -> set[tuple[int, int]]:
    """Minimal test equation supports (equations, faults) by brute force over removed faulty equations:
    TES = (M \\ D)+ for D a subset of the faulty equations, holding a faulty equation; MTES = minimal TES."""
    rows = _rows(structure)
    fmask = _faults(structure)
    faulty = [e for e in range(structure.ne) if fmask[e]]
    allq = frozenset(range(structure.ne))
    tes: set[frozenset[int]] = set()
    for k in range(len(faulty) + 1):
        for d in combinations(faulty, k):
            t = mplus(rows, allq - frozenset(d))
            if any(fmask[e] for e in t):
                tes.add(t)
    minimal = [t for t in tes if not any(o < t for o in tes)]
    out = set()
    for t in minimal:
        f = 0
        for e in t:
            f |= fmask[e]
        out.add((sum(1 << e for e in t), f))
    return out


def signature(structure: Structure, eqs: int) -> int:
    fmask = _faults(structure)
    f = 0
    for e in bits(eqs):
        f |= fmask[e]
    return f
