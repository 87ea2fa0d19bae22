"""The bipartite structure of a diagnosis model: which equation holds which unknown, known and fault.

This is what every structural algorithm works on (DM decomposition, MSO sets, isolability). It is the
same information Fault Diagnosis Toolbox users hold as incidence matrices X, F, Z, and it converts to and
from that JSON form (`to_fdt_json` / `from_fdt_json`).

X uses the Fault Diagnosis Toolbox convention: 0 = no incidence, 1 = the variable appears in the
equation, and in a differential constraint ``dx = d/dt x`` the derivative ``dx`` is marked 3 and the
integrated variable ``x`` is marked 2. F and Z are 0/1.
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from fdi_analysis.errors import FdiError

IntMatrix = npt.NDArray[np.int8]

INCIDENCE = 1
DIFF_INTEGRATED = 2
DIFF_DERIVATIVE = 3


class StructureError(FdiError, ValueError):
    """A structure that is not well formed (wrong shapes, bad markings, duplicate names)."""


class StructureWarning(UserWarning):
    """A structure Fault Diagnosis Toolbox accepts and this project loads after a change it names (a repeated
    name renamed) or with a part that takes no part in the analysis (a variable in no equation)."""


def warn_structure(source: str, message: str) -> None:
    """One warning line ``<source>: <message>`` (no source-code line under it)."""
    warnings.warn_explicit(message, StructureWarning, filename=source, lineno=0)


def unique_names(names: Sequence[str], label: str, source: str) -> tuple[str, ...]:
    """The names with repeats renamed (second ``e3`` -> ``e3_2``), each rename warned about."""
    taken = set(names)
    seen: dict[str, int] = {}
    out = []
    for n in names:
        if n not in seen:
            seen[n] = 1
            out.append(n)
            continue
        k = seen[n]
        while True:
            k += 1
            new = f"{n}_{k}"
            if new not in taken:
                break
        seen[n] = k
        taken.add(new)
        out.append(new)
        warn_structure(source, f"{label} name {n!r} repeats; this one renamed to {new!r}")
    return tuple(out)


@dataclass(frozen=True)
class Structure:
    """Incidence matrices and names of a structural model (rows = equations)."""

    equations: tuple[str, ...]
    unknowns: tuple[str, ...]
    knowns: tuple[str, ...]
    faults: tuple[str, ...]
    X: IntMatrix
    F: IntMatrix
    Z: IntMatrix
    name: str = ""
    equation_kinds: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        ne = len(self.equations)
        for label, mat, cols in (
            ("X", self.X, self.unknowns),
            ("F", self.F, self.faults),
            ("Z", self.Z, self.knowns),
        ):
            if mat.shape != (ne, len(cols)):
                raise StructureError(
                    f"{self.name or 'structure'}: {label} has shape {mat.shape}, expected {(ne, len(cols))}"
                )
        for label, names in (
            ("equation", self.equations),
            ("unknown", self.unknowns),
            ("known", self.knowns),
            ("fault", self.faults),
        ):
            seen: set[str] = set()
            for n in names:
                if n in seen:
                    raise StructureError(f"{self.name or 'structure'}: {label} {n!r} declared twice")
                seen.add(n)
        if self.equation_kinds and len(self.equation_kinds) != ne:
            raise StructureError("equation_kinds must have one entry per equation")
        bad = np.argwhere((self.X < 0) | (self.X > DIFF_DERIVATIVE))
        if bad.size:
            e, v = bad[0]
            raise StructureError(
                f"{self.name or 'structure'}: equation {self.equations[e]!r}, variable {self.unknowns[v]!r}: "
                f"X entry {int(self.X[e, v])} is not one of 0, 1, 2, 3"
            )
        for e in range(ne):
            row = self.X[e]
            n_der = int(np.count_nonzero(row == DIFF_DERIVATIVE))
            n_int = int(np.count_nonzero(row == DIFF_INTEGRATED))
            if (n_der or n_int) and (n_der != 1 or n_int != 1 or int(np.count_nonzero(row)) != 2):
                raise StructureError(
                    f"{self.name or 'structure'}: equation {self.equations[e]!r} is marked as a "
                    "differential constraint but does not pair exactly one derivative (3) with one "
                    "integrated variable (2)"
                )

    # -- sizes --------------------------------------------------------------------------------------
    @property
    def ne(self) -> int:
        return len(self.equations)

    @property
    def nx(self) -> int:
        return len(self.unknowns)

    @property
    def nf(self) -> int:
        return len(self.faults)

    @property
    def nz(self) -> int:
        return len(self.knowns)

    @property
    def incidence(self) -> npt.NDArray[np.bool_]:
        """Boolean equation x unknown incidence (mixed causality: derivative markings ignored)."""
        return np.asarray(self.X != 0)

    def differential_constraints(self) -> list[tuple[int, int, int]]:
        """(equation, derivative variable, integrated variable) index triples."""
        out = []
        for e in range(self.ne):
            d = np.flatnonzero(self.X[e] == DIFF_DERIVATIVE)
            i = np.flatnonzero(self.X[e] == DIFF_INTEGRATED)
            if d.size == 1 and i.size == 1:
                out.append((e, int(d[0]), int(i[0])))
        return out

    def fault_equations(self, fault: int) -> npt.NDArray[np.intp]:
        return np.flatnonzero(self.F[:, fault])

    def equation_faults(self, eqs: npt.ArrayLike) -> npt.NDArray[np.bool_]:
        """Boolean vector of the faults that enter the given equations (eq. 1 of the paper)."""
        idx = np.asarray(eqs, dtype=np.intp)
        if idx.size == 0:
            return np.zeros(self.nf, dtype=bool)
        return np.asarray(self.F[idx].any(axis=0))

    # -- Fault Diagnosis Toolbox JSON ---------------------------------------------------------------
    def to_fdt_dict(self) -> dict[str, Any]:
        return {
            "type": "MatrixStruc",
            "name": self.name,
            "e": list(self.equations),
            "x": list(self.unknowns),
            "f": list(self.faults),
            "z": list(self.knowns),
            "X": self.X.astype(int).tolist(),
            "F": self.F.astype(int).tolist(),
            "Z": self.Z.astype(int).tolist(),
        }

    def to_fdt_json(self, path: Path) -> None:
        path.write_text(json.dumps(self.to_fdt_dict(), indent=1) + "\n", encoding="utf-8")

    @staticmethod
    def from_fdt_dict(d: dict[str, Any], source: str = "<dict>") -> Structure:
        """A structure from Fault Diagnosis Toolbox's model definition: ``MatrixStruc`` (X, F, Z matrices, name
        lists e, x, f, z optional) or ``VarStruc`` (``rels``: the variable names of each equation). Repeated
        names are renamed with a warning, as FDT accepts them (its AddSensors repeats e1, e2, ...)."""
        if d.get("type") == "VarStruc" or ("rels" in d and "X" not in d):
            d = _matrices_from_rels(d, source)
        if "X" not in d:
            raise StructureError(f"{source}: missing key 'X'")
        mats: dict[str, npt.NDArray[np.int8]] = {}
        for key in ("X", "F", "Z"):
            raw = d.get(key)
            try:
                mat = np.asarray(raw if raw is not None and len(raw) else [], dtype=np.int8)
            except (TypeError, ValueError) as exc:
                raise StructureError(f"{source}: {key} is not a numeric matrix: {exc}") from exc
            if mat.size == 0 and key != "X":
                mat = np.zeros((mats["X"].shape[0], 0), dtype=np.int8)
            if mat.ndim != 2:
                raise StructureError(f"{source}: {key} must be a 2-D matrix (a list of equal-length rows)")
            if key != "X" and mat.shape[0] != mats["X"].shape[0]:
                raise StructureError(
                    f"{source}: {key} has {mat.shape[0]} rows but X has {mats['X'].shape[0]} (one per equation)"
                )
            mats[key] = mat
        X, F, Z = mats["X"], mats["F"], mats["Z"]
        ne = X.shape[0]
        x = d.get("x") or [f"x{i + 1}" for i in range(X.shape[1])]
        f = d.get("f") or [f"f{i + 1}" for i in range(F.shape[1])]
        z = d.get("z") or [f"z{i + 1}" for i in range(Z.shape[1])]
        e = d.get("e") or [f"e{i + 1}" for i in range(ne)]
        for label, names, n in (("x", x, X.shape[1]), ("f", f, F.shape[1]), ("z", z, Z.shape[1]), ("e", e, ne)):
            if len(names) != n:
                raise StructureError(f"{source}: name list {label!r} has {len(names)} entries, matrix has {n}")
        if ((F != 0) & (F != 1)).any() or ((Z != 0) & (Z != 1)).any():
            raise StructureError(f"{source}: F and Z must hold only 0 and 1")
        try:
            return Structure(
                equations=unique_names([str(n) for n in e], "equation", source),
                unknowns=unique_names([str(n) for n in x], "unknown", source),
                knowns=unique_names([str(n) for n in z], "known", source),
                faults=unique_names([str(n) for n in f], "fault", source),
                X=X,
                F=F,
                Z=Z,
                name=str(d.get("name", "")),
            )
        except StructureError as exc:
            raise StructureError(f"{source}: {exc}") from exc

    @staticmethod
    def from_fdt_json(path: Path) -> Structure:
        try:
            d = json.loads(Path(path).read_text(encoding="utf-8"))
        except json.JSONDecodeError as exc:
            raise StructureError(f"{path}: not valid JSON: {exc}") from exc
        if not isinstance(d, dict):
            raise StructureError(f"{path}: expected a JSON object with X, F, Z and name lists")
        return Structure.from_fdt_dict(d, source=str(path))

    def subsystem(self, eqs: npt.ArrayLike) -> Structure:
        """The structure restricted to some equations (all variables kept)."""
        idx = np.asarray(eqs, dtype=np.intp)
        return Structure(
            equations=tuple(self.equations[i] for i in idx),
            unknowns=self.unknowns,
            knowns=self.knowns,
            faults=self.faults,
            X=self.X[idx],
            F=self.F[idx],
            Z=self.Z[idx],
            name=self.name,
            equation_kinds=tuple(self.equation_kinds[i] for i in idx) if self.equation_kinds else (),
        )


def _matrices_from_rels(d: dict[str, Any], source: str) -> dict[str, Any]:
    """FDT's VarStruc form (``rels``: a list of variable-name lists, one per equation) as matrices."""
    rels = d.get("rels")
    if not isinstance(rels, list):
        raise StructureError(f"{source}: 'rels' must be a list with the variable names of each equation")
    cols: dict[str, list[str]] = {}
    for key in ("x", "f", "z"):
        names = d.get(key, [])
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            raise StructureError(f"{source}: {key!r} must be a list of names")
        cols[key] = names
    where = {n: (key, i) for key in ("z", "f", "x") for i, n in enumerate(cols[key])}
    mats = {key: [[0] * len(cols[key]) for _ in rels] for key in ("x", "f", "z")}
    for r, rel in enumerate(rels):
        if not isinstance(rel, list):
            raise StructureError(f"{source}: equation {r + 1} of 'rels' is not a list of variable names")
        for n in rel:
            if n not in where:
                raise StructureError(
                    f"{source}: equation {r + 1} of 'rels': variable {n!r} is not declared in x, f or z"
                )
            key, i = where[n]
            mats[key][r][i] = 1
    out = {k: v for k, v in d.items() if k != "rels"}
    out.update(type="MatrixStruc", X=mats["x"], F=mats["f"], Z=mats["z"])
    return out
