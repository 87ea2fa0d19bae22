"""A short physical reading of an equation set, in the spirit of the paper's Table II.

Built from the equations' `group` labels (e.g. "kinematics", "wheel 3 tyre") and the measured signals the
set uses: "kinematics; measured ax_m, psidot_m, vx_m, vy_m". Wheel groups are folded per wheel:
"wheel 3 (kinematics, slip, tyre, spin)".
"""

from __future__ import annotations

from collections.abc import Iterable

from fdi_analysis.model import Model


def interpret(model: Model, equation_ids: Iterable[str]) -> str:
    ids = set(equation_ids)
    eqs = [e for e in model.equations if e.id in ids]
    parts: dict[str, list[str]] = {}
    for e in eqs:
        g = e.group or e.id.split(".")[0]
        if g == "sensors":
            continue
        head, _, tail = g.partition(" ")
        if head == "wheel" and " " in tail:
            wheel, _, what = tail.partition(" ")
            key = f"wheel {wheel}"
            if what not in parts.setdefault(key, []):
                parts[key].append(what)
        else:
            parts.setdefault(g, [])
    text = "; ".join(f"{k} ({', '.join(v)})" if v else k for k, v in parts.items())
    knowns = [v.name for v in model.knowns if any(v.name in e.knowns for e in eqs)]
    measured = "measured " + ", ".join(knowns) if knowns else "no measurements"
    return f"{text}; {measured}" if text else measured
