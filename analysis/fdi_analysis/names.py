"""Names of faults, tests and signals: any identifier. Their natural order (``f2`` before ``f10``, ``tank2`` before
``tank10``, plain text otherwise) and their short labels on crowded plot axes."""

from __future__ import annotations

import re
from collections.abc import Iterable

_DIGITS = re.compile(r"(\d+)")
_NUMBERED = re.compile(r"f\d+")


def natural_key(name: str) -> tuple[tuple[int, int | str], ...]:
    """Sort key: the name's runs of digits compare as numbers, the rest as text (numbers before text at a tie)."""
    return tuple((0, int(part)) if part.isdigit() else (1, part) for part in _DIGITS.split(name) if part)


def natural_sorted(names: Iterable[str]) -> list[str]:
    """The names in natural order (natural_key)."""
    return sorted(names, key=natural_key)


def axis_labels(names: Iterable[str]) -> list[str]:
    """Labels for a crowded axis: the numbers alone where every name is ``f<number>`` (the paper's f1 .. f25), else
    the names themselves."""
    listed = list(names)
    if listed and all(_NUMBERED.fullmatch(n) for n in listed):
        return [n[1:] for n in listed]
    return listed
