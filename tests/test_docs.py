"""Every module a document names exists: the dotted names of the two packages (``fdi_host.ecu.bindings``,
``fdi_analysis.residuals.uncertainty_sensitivity.offset_like``: a module, then a name it defines) and the ``.py``
paths (``sim/plant.py``, ``tests/host/test_plant.py``, a bare ``e2e.py``) in the project's documents. Every relative
link of a document leads to a file of the checkout, and the README stays a manual under 15 KB (its commands are run
by tests/test_readme_commands.py)."""

from __future__ import annotations

import ast
import functools
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
ROOTS = {"fdi_analysis": REPO / "analysis", "fdi_host": REPO / "host_tools"}
DOCUMENTS = ("ARCHITECTURE.md", "README.md", "host_tools/README.md", "analysis/models/README.md", "fw/README.md",
             "fw/ecu/README.md", "fw/MISRA_DEVIATIONS.md", "CHANGELOG.md", "docs/results.md")
README_LIMIT_BYTES = 15_000
SOURCE_FOLDERS = ("analysis", "host_tools", "tests", "fw", "scripts", "examples", "cmake", "dbc")

LINK = re.compile(r"\]\(([^)\s]+)\)")
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


def _exported(body: list[ast.stmt]) -> set[str]:
    """The names of a module's ``__all__``, given as a literal or as ``list(NAMES)`` / ``tuple(NAMES)`` of a literal
    of the module: a lazy facade (PEP 562 ``__getattr__``) defines them only there."""
    literals: dict[str, list[str]] = {}
    exported: set[str] = set()
    for node in body:
        if not (isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name)):
            continue
        value = node.value
        if isinstance(value, ast.Call) and isinstance(value.func, ast.Name) and value.func.id in ("list", "tuple") \
                and len(value.args) == 1:
            value = value.args[0]
        if isinstance(value, ast.Name):
            names = literals.get(value.id, [])
        elif isinstance(value, (ast.List, ast.Tuple)):
            names = [e.value for e in value.elts if isinstance(e, ast.Constant) and isinstance(e.value, str)]
        else:
            continue
        literals[node.targets[0].id] = names
        if node.targets[0].id == "__all__":
            exported |= set(names)
    return exported


@functools.cache
def defined_names(path: Path) -> dict[str, set[str] | None]:
    """Top-level names of a module (and those its ``__all__`` exports): a class maps to the names of its body,
    anything else to None."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out: dict[str, set[str] | None] = dict.fromkeys(_exported(tree.body))
    for node in tree.body:
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
    assert dotted_exists("fdi_host.simulate") and not dotted_exists("fdi_host.nothing")  # the lazy facade's names
    assert py_path_exists("sim/plant.py", doc) and py_path_exists("tests/host/test_plant.py", doc)
    assert py_path_exists("fdi_host/can/log_columns.py", doc) and py_path_exists("e2e.py", doc)
    assert not py_path_exists("ecu_lib.py", doc) and not py_path_exists("analysis/bench/compare_causality.py", doc)


def broken_links(doc: Path) -> list[str]:
    """The relative links of a Markdown document (``[text](path#anchor)``, images too) whose file does not exist."""
    bad = []
    for target in LINK.findall(doc.read_text(encoding="utf-8")):
        if re.match(r"^[a-z]+:", target) or target.startswith("#"):
            continue  # a URL, or an anchor in the document itself
        path = (doc.parent / target.split("#")[0]).resolve()
        if path.exists():
            continue
        bad.append(target)
    return bad


@pytest.mark.parametrize("document", DOCUMENTS)
def test_every_link_of_a_document_exists(document: str) -> None:
    broken = broken_links(REPO / document)
    assert not broken, f"{document} links files that do not exist: {broken}"


def test_the_link_check_finds_broken_links(tmp_path: Path) -> None:
    doc = tmp_path / "doc.md"
    doc.write_text("[a](README.md) [b](nothing.md#x) ![c](pic.png) [d](https://example.org/x) [e](#top)\n",
                   encoding="utf-8")
    (tmp_path / "README.md").write_text("x", encoding="utf-8")
    assert broken_links(doc) == ["nothing.md#x", "pic.png"]


def test_the_readme_is_a_manual() -> None:
    """Under 15 KB; results and history live elsewhere, and the README links them."""
    readme = REPO / "README.md"
    assert readme.stat().st_size < README_LIMIT_BYTES, f"README.md is {readme.stat().st_size} bytes"
    text = readme.read_text(encoding="utf-8")
    for target in ("docs/results.md", "CHANGELOG.md", "ARCHITECTURE.md", "fw/README.md", "host_tools/README.md",
                   "analysis/models/README.md", "docs/robust_diagnosis.md", "examples/romo_tour.ipynb"):
        assert f"]({target}" in text, f"README.md does not link {target}"
