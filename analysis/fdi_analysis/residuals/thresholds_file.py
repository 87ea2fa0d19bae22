"""The generated parts of the thresholds TOML file, the hand-maintained part above them kept byte for byte:
the [augment] table (tests added to the structural selection for practical detectability, written by
`fdi-analyze augment`) and, last, the [generated] table (variance per generated residual, written by
`fdi-analyze calibrate`)."""

from __future__ import annotations

from collections.abc import Sequence

MARKER = "# ---- generated residuals: written by `fdi-analyze calibrate`, do not edit below ----"
AUGMENT_MARKER = "# ---- tests added for practical detectability: written by `fdi-analyze augment` ----"


def with_generated(text: str, rows: Sequence[tuple[str, float, str]], provenance: str) -> str:
    """The file's text with its [generated] table replaced; rows: (equation set, variance, comment)."""
    head = text.split(MARKER)[0].rstrip("\n") + "\n\n"
    lines = [MARKER, f"# {provenance}", "[generated]"]
    for eqs, var, comment in rows:
        lines.append(f"# {comment}")
        lines.append(f'"{eqs}" = {var:.4g}')
    return head + "\n".join(lines) + "\n"


def with_augment(text: str, tests: Sequence[tuple[str, str]], provenance: str) -> str:
    """The file's text with its [augment] table replaced (placed just above the [generated] table, which is
    kept); tests: (equation set, comment)."""
    hand, _, generated = text.partition(MARKER)
    head = hand.split(AUGMENT_MARKER)[0].rstrip("\n") + "\n\n"
    lines = [AUGMENT_MARKER, *(f"# {p}" for p in provenance.splitlines()), "[augment]", "tests = ["]
    for eqs, comment in tests:
        lines.append(f"    # {comment}")
        lines.append(f'    "{eqs}",')
    lines.append("]")
    tail = ("\n" + MARKER + generated) if generated or MARKER in text else ""
    return head + "\n".join(lines) + "\n" + tail
