"""Result records of the MSO / MTES analysis (equation and fault sets are int bitsets: bit i = index i)."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass


def bits(mask: int) -> list[int]:
    """Indices of the set bits of a bitset, ascending."""
    out = []
    while mask:
        low = mask & -mask
        out.append(low.bit_length() - 1)
        mask ^= low
    return out


def to_mask(indices: Iterator[int] | Sequence[int]) -> int:
    m = 0
    for i in indices:
        m |= 1 << int(i)
    return m


def lex_before(a: int, b: int) -> bool:
    """True if equation set a comes before b as ascending index lists (sets of equal size)."""
    d = a ^ b
    return d != 0 and bool(a & (d & -d))


@dataclass(frozen=True)
class SignatureEntry:
    """All MSO sets with one fault signature: how many, and the smallest one (fewest equations, then
    lexicographically first)."""

    faults: int
    count: int
    smallest: int
    smallest_size: int

    @property
    def smallest_unknowns(self) -> int:
        return self.smallest_size - 1


@dataclass(frozen=True)
class MsoSummary:
    """Aggregate of an MSO enumeration (the sets themselves are not kept).

    ``by_equations[k]`` counts the MSO sets with k equations (an MSO set has k - 1 unknowns).
    ``complete`` is False when the run was interrupted; the numbers then cover only finished subproblems.
    """

    count: int
    by_equations: dict[int, int]
    signatures: tuple[SignatureEntry, ...]
    complete: bool
    elapsed_s: float
    workers: int
    tasks: int

    @property
    def by_unknowns(self) -> dict[int, int]:
        return {k - 1: v for k, v in self.by_equations.items()}

    def signature_set(self) -> frozenset[int]:
        return frozenset(s.faults for s in self.signatures)


@dataclass(frozen=True)
class TestSupport:
    """A test equation support: a PSO equation set and the faults entering it."""

    equations: int
    faults: int


@dataclass(frozen=True)
class MtesResult:
    """Minimal test equation supports, and optionally every test support visited by the search."""

    mtes: tuple[TestSupport, ...]
    tes: tuple[TestSupport, ...]
    elapsed_s: float

    def minimal_signatures(self) -> frozenset[int]:
        return frozenset(t.faults for t in self.mtes)
