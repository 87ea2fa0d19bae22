"""Fault Diagnosis Toolbox's example models, as FDT builds them, for the benchmark and the compatibility test.

Shipped with the package (faultdiagnosistoolbox.models): three tank, electric motor, induction motor.
Written here from their published structure (FDT's examples, MatrixStruc form): Commault et al.'s example and
the small linear model. Each also with the sensors FDT's own sensor placement proposes (AddSensors): that
is how FDT's examples repeat equation names (AddSensors names the new equations e1, e2, ... again) and
leave knowns in no equation.

`fdt_dict(model)` is the model in FDT's MatrixStruc JSON form (what `fdi-analyze` loads from a .json file).
"""

from __future__ import annotations

import contextlib
import io
from typing import Any

# Commault, Dion, Agha Yacoub: "Quantitative fault detection and isolation ..." as in FDT's example
COMMAULT: dict[str, Any] = {
    "type": "MatrixStruc",
    "X": [
        [0, 0, 0, 0, 1, 0, 0],
        [0, 0, 0, 0, 0, 0, 1],
        [0, 0, 0, 0, 0, 1, 0],
        [1, 0, 0, 0, 1, 0, 1],
        [0, 1, 0, 0, 0, 1, 0],
        [1, 1, 1, 0, 0, 0, 0],
        [1, 1, 0, 1, 0, 0, 0],
        [0, 0, 1, 0, 0, 0, 0],
        [0, 0, 1, 1, 0, 0, 0],
        [0, 0, 0, 1, 0, 0, 0],
    ],
    "F": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 1], [0, 0, 0, 0], [0, 0, 1, 0]] + [[0, 0, 0, 0]] * 5,
    "Z": [[0, 0, 0]] * 7 + [[1, 0, 0], [0, 1, 0], [0, 0, 1]],
}

SMALL_LINEAR: dict[str, Any] = {
    "type": "MatrixStruc",
    "X": [[1, 1, 0, 0, 1], [0, 1, 1, 1, 0], [0, 0, 1, 0, 1], [0, 0, 0, 1, 1], [0, 0, 0, 0, 1]],
    "F": [[0, 0, 0, 0], [0, 0, 0, 0], [1, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]],
    "Z": [],
}


def fdt_dict(model: Any) -> dict[str, Any]:
    """An FDT DiagnosisModel in FDT's MatrixStruc JSON form (lists, names as FDT holds them)."""
    return {
        "type": "MatrixStruc",
        "name": str(model.name),
        "e": [str(n) for n in model.e],
        "x": [str(n) for n in model.x],
        "f": [str(n) for n in model.f],
        "z": [str(n) for n in model.z],
        "X": model.X.astype(int).tolist(),
        "F": model.F.astype(int).tolist(),
        "Z": model.Z.astype(int).tolist(),
    }


def _with_sensors(model: Any, label: str) -> Any | None:
    """The model with the first non-empty sensor set FDT's sensor placement proposes (isolability), or
    else sensors on its first two unknowns; None when it has no unknown."""
    m = model.copy()
    with contextlib.redirect_stdout(io.StringIO()):
        m.SensorLocationsWithFaults(m.x)  # every new sensor may fail, as in FDT's examples
        sets, _ = m.SensorPlacementIsolability()
    chosen = next((list(s) for s in sets if len(s)), list(m.x[:2]))
    if not chosen:
        return None
    with contextlib.redirect_stdout(io.StringIO()):
        m.AddSensors(chosen)
    m.name = f"{label} + sensors"
    return m


def example_models() -> list[tuple[str, Any]]:
    """(label, FDT DiagnosisModel) of every example available offline, with and without added sensors."""
    import faultdiagnosistoolbox as fdt
    from faultdiagnosistoolbox import models

    base: list[tuple[str, Any]] = [
        ("three tank", models.three_tank),
        ("electric motor", models.electric_motor),
        ("induction motor", models.induction_motor),
    ]
    with contextlib.redirect_stdout(io.StringIO()):
        base.append(("Commault", fdt.DiagnosisModel(COMMAULT, name="Commault")))
        base.append(("small linear", fdt.DiagnosisModel(SMALL_LINEAR, name="small linear")))
    out = list(base)
    for label, m in base:
        s = _with_sensors(m, label)
        if s is not None:
            out.append((f"{label} + sensors", s))
    return out
