"""Every module a document names exists: the dotted names of the two packages (``fdi_host.ecu.bindings``,
``fdi_analysis.residuals.uncertainty_sensitivity.offset_like``: a module, then a name it defines) and the ``.py``
paths (``sim/plant.py``, ``tests/host/test_plant.py``, a bare ``e2e.py``) in the project's documents."""

from __future__ import annotations

import ast
import functools
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
ROOTS = {"fdi_analysis": REPO / "analysis", "fdi_host": REPO / "host_tools"}
DOCUMENTS = ("ARCHITECTURE.md", "README.md", "host_tools/README.md", "analysis/models/README.md", "fw/README.md",
             "fw/ecu/README.md", "fw/MISRA_DEVIATIONS.md")
SOURCE_FOLDERS = ("analysis", "host_tools", "tests", "fw", "scripts", "examples", "cmake", "dbc")

DOTTED = re.compile(r"\b(?:fdi_analysis|fdi_host)(?:\.[A-Za-z_]\w*)+")
PY_PATH = re.compile(r"(?<![\w./-])([\w./-]*\w\.py)\b")


def module_path(name: str) -> Path | None:
    """The source file of module or package `name` (a compiled extension: its C source), or None."""
    parts = name.split(".")
    base = ROOTS[parts[0]].joinpath(*parts)
    for p in (base.with_suffix(".py"), base / "__init__.py", base.with_suffix(".pyi"), base.with_suffix(".c")):
        if p.is_file():
            return p
    return None


@functools.cache
def defined_names(path: Path) -> dict[str, set[str] | None]:
    """Top-level names of a module: a class maps to the names of its body, anything else to None."""
    out: dict[str, set[str] | None] = {}
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.ClassDef):
            members: set[str] = set()
            for item in node.body:
                if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                    members.add(item.name)
                elif isinstance(item, ast.AnnAssign) and isinstance(item.target, ast.Name):
                    members.add(item.target.id)
                elif isinstance(item, ast.Assign):
                    members |= {t.id for t in item.targets if isinstance(t, ast.Name)}
            out[node.name] = members
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            out[node.name] = None
        elif isinstance(node, ast.Assign):
            out |= {t.id: None for t in node.targets if isinstance(t, ast.Name)}
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            out[node.target.id] = None
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            out |= {(a.asname or a.name).split(".")[0]: None for a in node.names}
    return out


def dotted_exists(name: str) -> bool:
    """A module, or a module and a name it defines (and, for a class, one of its members)."""
    parts = name.split(".")
    for k in range(len(parts), 0, -1):
        path = module_path(".".join(parts[:k]))
        if path is None:
            continue
        rest = parts[k:]
        if not rest:
            return True
        if path.suffix == ".c":
            return True  # the names an extension module defines are not checked
        names = defined_names(path)
        if rest[0] not in names:
            return False
        members = names[rest[0]]
        return len(rest) == 1 or members is None or rest[1] in members
    return False


@functools.cache
def py_files() -> frozenset[str]:
    """The names of every Python file of the repository's source folders."""
    return frozenset(p.name for folder in SOURCE_FOLDERS for p in (REPO / folder).rglob("*.py")) | frozenset(
        p.name for p in REPO.glob("*.py"))


def py_path_exists(text: str, doc: Path) -> bool:
    """A path from the repository root, the document's folder or a package's root (``sim/plant.py`` in
    host_tools/README.md), or ``fdi_host/...`` from its folder; a bare file name anywhere in the sources."""
    if "/" not in text:
        return text in py_files()
    bases = [REPO, doc.parent, *ROOTS.values(), *(root / pkg for pkg, root in ROOTS.items())]
    return any((base / text).is_file() for base in bases)


def stale_names(doc: Path) -> list[str]:
    text = doc.read_text(encoding="utf-8")
    bad = [m for m in sorted(set(DOTTED.findall(text))) if not dotted_exists(m)]
    bad += [m for m in sorted(set(PY_PATH.findall(text))) if not py_path_exists(m, doc)]
    return bad


@pytest.mark.parametrize("document", DOCUMENTS)
def test_every_module_named_in_a_document_exists(document: str) -> None:
    stale = stale_names(REPO / document)
    assert not stale, f"{document} names modules that do not exist: {stale}"


def test_the_check_finds_stale_names() -> None:
    doc = REPO / "host_tools" / "README.md"
    assert dotted_exists("fdi_host.ecu.bindings.Ecu.process") and dotted_exists("fdi_analysis.cli.common")
    assert dotted_exists("fdi_analysis.residuals.uncertainty_sensitivity.offset_like")
    assert not dotted_exists("fdi_analysis.candidates_mtes") and not dotted_exists("fdi_host.ecu.bindings.Nothing")
    assert not dotted_exists("fdi_host.ecu.bindings.Ecu.nothing")
    assert py_path_exists("sim/plant.py", doc) and py_path_exists("tests/host/test_plant.py", doc)
    assert py_path_exists("fdi_host/can/log_columns.py", doc) and py_path_exists("e2e.py", doc)
    assert not py_path_exists("ecu_lib.py", doc) and not py_path_exists("analysis/bench/compare_causality.py", doc)
