"""The house rules of the Python packages, checked on their imports (every `import` and `from ... import`, also
inside functions): no module imports one of a higher layer, and no modules import each other in a circle.

Layers, lowest first (ARCHITECTURE.md draws them): the structural analysis and synthesis (`fdi_analysis`: the
model, then the structural algorithms, the selection, the residual synthesis, the C export, the command
line), then the host tools (`fdi_host`: the simulator, CAN, the ECU bindings, the closed-loop tuning and the
paper's figure, the live bus, the monitor and the quality suite, replay, the `fdi-sim` entry point)."""

from __future__ import annotations

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
ROOTS = {"fdi_analysis": REPO / "analysis", "fdi_host": REPO / "host_tools"}

# (module prefix, layer): the longest matching prefix decides
LAYERS: tuple[tuple[str, int], ...] = (
    ("fdi_analysis", 0), ("fdi_analysis.errors", 0),  # the root of both packages' errors: imports nothing
    ("fdi_analysis.model", 0), ("fdi_analysis.model_loader", 0), ("fdi_analysis.expressions", 0),
    ("fdi_analysis.structure", 0), ("fdi_analysis.random_structures", 0), ("fdi_analysis.uncertainty", 0),
    ("fdi_analysis.dm", 1), ("fdi_analysis.isolability", 1), ("fdi_analysis.fault_matrix", 1),
    ("fdi_analysis.summary", 1), ("fdi_analysis.interpretation", 1), ("fdi_analysis.report", 1),
    ("fdi_analysis.plots", 1), ("fdi_analysis.mso", 1), ("fdi_analysis.robustness", 1), ("fdi_analysis.tables", 0),
    ("fdi_analysis.selection", 2),
    ("fdi_analysis.residuals", 3),
    ("fdi_analysis.export", 4),
    ("fdi_analysis.cli", 5), ("fdi_analysis.api", 5),
    ("fdi_host", 10), ("fdi_host.errors", 10), ("fdi_host.sim", 10),
    ("fdi_host.can", 11),
    ("fdi_host.ecu", 12),
    ("fdi_host.tuning", 13), ("fdi_host.paper", 13),
    ("fdi_host.live", 14),
    ("fdi_host.monitor", 15), ("fdi_host.quality", 15),
    ("fdi_host.replay", 16), ("fdi_host.fleet", 16),
    ("fdi_host.diagnosis", 13), ("fdi_host.diagnosis_plots", 10), ("fdi_host.api", 16),
    ("fdi_host.cli", 17), ("fdi_host.tuning.cli", 17), ("fdi_host.vehicle_cli", 17),
)


# A package root that re-exports an upper layer's names (PEP 562 `__getattr__`, loaded on first use) is a facade
# above its whole package: `fdi_analysis` re-exports the API (layer 5), `fdi_host` its API (layer 16).
FACADES = {"fdi_analysis": 6, "fdi_host": 18}


def layer(module: str) -> int:
    if module in FACADES:
        return FACADES[module]
    best = ("", -1)
    for prefix, lay in LAYERS:
        if (module == prefix or module.startswith(prefix + ".") or module.startswith(prefix + "_")) and len(
                prefix) > len(best[0]):
            best = (prefix, lay)
    assert best[1] >= 0, f"{module} has no layer: add it to LAYERS"
    return best[1]


def modules() -> dict[str, Path]:
    out = {}
    for pkg, root in ROOTS.items():
        for p in sorted((root / pkg).rglob("*.py")):
            rel = p.relative_to(root).with_suffix("")
            parts = list(rel.parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = p
    return out


def imports(name: str, path: Path, known: set[str]) -> set[str]:
    """The project modules `name` imports (a `from pkg import mod` counts as pkg.mod when that is a module)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    pkg = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out: set[str] = set()
    for node in ast.walk(tree):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "import_module"
                and node.args and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str)
                and node.args[0].value.split(".")[0] in ROOTS):  # importlib.import_module("fdi_...") counts too
            out.add(node.args[0].value)
        elif isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name.split(".")[0] in ROOTS}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = pkg.split(".")
                up = up[: len(up) - (node.level - 1)] if node.level > 1 else up
                base = ".".join([*up, *([base] if base else [])])
            if base.split(".")[0] not in ROOTS:
                continue
            for a in node.names:
                full = f"{base}.{a.name}"
                native = any((ROOTS[base.split(".")[0]] / base.replace(".", "/")).glob(f"{a.name}.*[!y]"))
                if full in known or native:  # a Python module, or a compiled one (.so / .c beside a .pyi)
                    out.add(full)
                else:  # a name defined in the module `base`
                    out.add(base)
    return {m for m in out if m != name}


def graph() -> dict[str, set[str]]:
    mods = modules()
    known = set(mods)
    return {m: {i for i in imports(m, p, known) if i in known or i.split(".")[0] in ROOTS} for m, p in mods.items()}


def test_no_import_runs_up_a_layer() -> None:
    bad = [f"{m} (layer {layer(m)}) imports {i} (layer {layer(i)})"
           for m, deps in graph().items() for i in sorted(deps) if layer(i) > layer(m)]
    assert not bad, "\n".join(bad)


def test_no_import_circles() -> None:
    g = graph()
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    circles: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:  # Tarjan's strongly connected components (the graph is small)
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(g.get(v, ())):
            if w not in g:
                continue
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                circles.append(sorted(comp))

    for v in sorted(g):
        if v not in index:
            visit(v)
    assert not circles, f"import circles: {circles}"


def test_the_layer_check_sees_an_upward_import(tmp_path: Path) -> None:
    """The check itself: an import of the quality suite from the simulator is caught, and so is a circle."""
    bad = tmp_path / "m.py"
    bad.write_text("def f():\n    from fdi_host.quality.suite import run_suite\n", encoding="utf-8")
    found = imports("fdi_host.sim.m", bad, {"fdi_host.quality.suite"})
    assert found == {"fdi_host.quality.suite"} and layer("fdi_host.quality.suite") > layer("fdi_host.sim.m")
    bad.write_text("import importlib\ndef f():\n    return importlib.import_module('fdi_analysis.api')\n",
                   encoding="utf-8")
    assert imports("fdi_analysis.dm", bad, {"fdi_analysis.api"}) == {"fdi_analysis.api"}
    assert layer("fdi_analysis.api") > layer("fdi_analysis.dm") and layer("fdi_analysis") > layer("fdi_analysis.api")
