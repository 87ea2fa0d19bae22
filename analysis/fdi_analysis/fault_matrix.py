"""Fault signature matrix and the paper's fault matrix, evaluation methods A and B.

A test (a residual from an MSO set) is sensitive to the faults of its equations (paper eq. 1). The
*signature* of fault j is the set of tests sensitive to it. Fault matrices have a row per occurred fault
and a column per diagnosed fault, both including "fault 0" (no fault) at index 0:

- method A (no exoneration, the paper's conservative method): occurred fault j can be interpreted as fault
  i when signature(j) is contained in signature(i) ("i explains j"); asymmetric; fault 0 is explained by
  every fault.
- method B: j and i are confused only when their signatures are identical; symmetric.

Fault sets are int bitmasks over the model's faults (bit k = fault k).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt

Method = Literal["A", "B"]
BoolMatrix = npt.NDArray[np.bool_]


@dataclass(frozen=True)
class Candidate:
    """A candidate test: an MSO (or test support) with its fault set and cost (number of unknowns)."""

    equations: int
    faults: int
    cost: int
    label: str = ""


def signature_matrix(tests: Sequence[Candidate], nf: int) -> BoolMatrix:
    """FSM[t, k] = test t is sensitive to fault k."""
    fsm = np.zeros((len(tests), nf), dtype=bool)
    for t, test in enumerate(tests):
        for k in range(nf):
            fsm[t, k] = bool(test.faults >> k & 1)
    return fsm


def fault_signatures(fault_sets: Sequence[int], nf: int) -> list[int]:
    """Per fault (index 0 = no fault, then 1..nf), the bitmask of the tests sensitive to it."""
    sig = [0] * (nf + 1)
    for t, fs in enumerate(fault_sets):
        k = 0
        m = fs
        while m:
            if m & 1:
                sig[k + 1] |= 1 << t
            m >>= 1
            k += 1
    return sig


def fault_matrix(fault_sets: Sequence[int], nf: int, method: Method) -> BoolMatrix:
    """(nf+1) x (nf+1) matrix, row = occurred fault, column = fault it can be interpreted as (0 = none)."""
    sig = fault_signatures(fault_sets, nf)
    n = nf + 1
    fm = np.zeros((n, n), dtype=bool)
    for j in range(n):
        for i in range(n):
            fm[j, i] = (sig[j] & ~sig[i]) == 0 if method == "A" else sig[j] == sig[i]
    return fm


def distinguished_pairs(fault_set: int, nf: int, method: Method) -> list[tuple[int, int]]:
    """The fault-matrix entries (row j, column i; 0 = no fault) that one test with `fault_set` clears.

    Method A: the test fires for j and not for i. Method B: it fires for exactly one of them (both
    orders are listed, so the matrices stay comparable entry by entry).
    """
    inside = [k + 1 for k in range(nf) if fault_set >> k & 1]
    outside = [0] + [k + 1 for k in range(nf) if not fault_set >> k & 1]
    pairs = [(j, i) for j in inside for i in outside]
    if method == "B":
        pairs += [(i, j) for j, i in pairs]
    return pairs
