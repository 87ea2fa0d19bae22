"""Names of faults, tests and signals: any identifier. The one home of their order and labels: the model's declared
order (the order its author wrote them, `in_order`), else the natural order (``f2`` before ``f10``, ``tank2`` before
``tank10``, plain text otherwise), and their short labels on crowded plot axes. Nothing else in the project may
assume a shape like ``f<number>``."""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence

_DIGITS = re.compile(r"([0-9]+)")
_NUMBERED = re.compile(r"f[0-9]+")


def natural_key(name: str) -> tuple[tuple[int, int | str], ...]:
    """Sort key: the name's runs of digits compare as numbers, the rest as text (numbers before text at a tie)."""
    parts = _DIGITS.split(name)  # text, digits, text, ... (the odd ones are the runs of digits)
    return tuple((0, int(part)) if k % 2 else (1, part) for k, part in enumerate(parts) if part)


def natural_sorted(names: Iterable[str]) -> list[str]:
    """The names in natural order (natural_key)."""
    return sorted(names, key=natural_key)


def in_order(names: Iterable[str], order: Sequence[str]) -> list[str]:
    """The names in `order` (the model's declaration), any not in it after those in natural order."""
    rank = {n: k for k, n in enumerate(order)}
    return sorted(names, key=lambda n: (rank.get(n, len(rank)), natural_key(n)))


def axis_labels(names: Iterable[str]) -> list[str]:
    """Labels for a crowded axis: the numbers alone where every name is ``f<number>`` (the paper's f1 .. f25), else
    the names themselves."""
    listed = list(names)
    if listed and all(_NUMBERED.fullmatch(n) for n in listed):
        return [n[1:] for n in listed]
    return listed
