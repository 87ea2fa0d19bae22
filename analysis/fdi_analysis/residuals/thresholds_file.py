"""The [generated] table (variance per generated residual) of the thresholds TOML file, the hand-maintained
part above it kept byte for byte."""

from __future__ import annotations

from collections.abc import Sequence

MARKER = "# ---- generated residuals: written by `fdi-analyze calibrate`, do not edit below ----"


def with_generated(text: str, rows: Sequence[tuple[str, float, str]], provenance: str) -> str:
    """The file's text with its [generated] table replaced; rows: (equation set, variance, comment)."""
    head = text.split(MARKER)[0].rstrip("\n") + "\n\n"
    lines = [MARKER, f"# {provenance}", "[generated]"]
    for eqs, var, comment in rows:
        lines.append(f"# {comment}")
        lines.append(f'"{eqs}" = {var:.4g}')
    return head + "\n".join(lines) + "\n"

