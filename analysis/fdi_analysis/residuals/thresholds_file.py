"""Write the [generated] table (variance per generated residual) into the thresholds TOML file, keeping the
hand-maintained part above it byte for byte."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

MARKER = "# ---- generated residuals: written by `fdi-analyze calibrate`, do not edit below ----"


def write_generated(path: Path, rows: Sequence[tuple[str, float, str]], provenance: str) -> None:
    """rows: (equation set, variance, comment)."""
    text = path.read_text(encoding="utf-8")
    head = text.split(MARKER)[0].rstrip("\n") + "\n\n"
    lines = [MARKER, f"# {provenance}", "[generated]"]
    for eqs, var, comment in rows:
        lines.append(f"# {comment}")
        lines.append(f'"{eqs}" = {var:.4g}')
    path.write_text(head + "\n".join(lines) + "\n", encoding="utf-8")
