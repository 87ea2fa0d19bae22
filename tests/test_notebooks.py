"""The example notebooks (examples/*.ipynb) run from top to bottom without an error, through nbclient on an
ipykernel of the Python running the tests (the venv: no kernel installed anywhere else is used, and every Jupyter
folder lies in the test's temporary folder). A kernel that cannot start fails the test. The notebooks are committed
without outputs."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

REPO = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((REPO / "examples").glob("*.ipynb"))
KERNEL = "romo-fdi-test"
BUDGET_S = 120.0  # the tour takes well under a minute; twice that on a loaded machine


@pytest.fixture
def kernel(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> str:
    """A kernel spec for this Python (sys.executable -m ipykernel_launcher) in a temporary Jupyter path."""
    spec = tmp_path / "jupyter" / "kernels" / KERNEL
    spec.mkdir(parents=True)
    (spec / "kernel.json").write_text(json.dumps({
        "argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
        "display_name": "romo-fdi (tests)", "language": "python",
    }), encoding="utf-8")
    monkeypatch.setenv("JUPYTER_PATH", str(tmp_path / "jupyter"))
    for var, sub in (("JUPYTER_DATA_DIR", "data"), ("JUPYTER_RUNTIME_DIR", "runtime"),
                     ("JUPYTER_CONFIG_DIR", "config"), ("IPYTHONDIR", "ipython"), ("MPLCONFIGDIR", "mpl")):
        monkeypatch.setenv(var, str(tmp_path / sub))
    monkeypatch.setenv("JUPYTER_PLATFORM_DIRS", "1")
    monkeypatch.delenv("MPLBACKEND", raising=False)  # the kernel's inline backend
    return KERNEL


def test_there_is_a_notebook_and_it_is_committed_without_outputs() -> None:
    assert REPO / "examples" / "romo_tour.ipynb" in NOTEBOOKS
    for path in NOTEBOOKS:
        nb = nbformat.read(path, as_version=4)
        nbformat.validate(nb)
        code = [c for c in nb.cells if c.cell_type == "code"]
        assert code, path
        assert all(c.outputs == [] and c.execution_count is None for c in code), f"{path.name}: clear its outputs"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_the_notebook_runs(path: Path, kernel: str, tmp_path: Path) -> None:
    nb = nbformat.read(path, as_version=4)
    work = tmp_path / "work"
    work.mkdir()
    client = NotebookClient(nb, timeout=300, kernel_name=kernel, resources={"metadata": {"path": str(work)}})
    t0 = time.perf_counter()
    client.execute()  # raises on a cell's error and when the kernel does not start
    elapsed = time.perf_counter() - t0
    assert elapsed < BUDGET_S, f"{path.name} took {elapsed:.0f} s"
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    html = [o["data"]["text/html"] for o in outputs if "text/html" in o.get("data", {})]
    assert html, "no result showed as an HTML table"
    if path.name == "romo_tour.ipynb":
        text = "\n".join(html)
        for label in ("cannot be isolated from", "f10 -&gt; f6", "MSO6", "Diagnosis(romo", "candidate faults over"):
            assert label in text, label
        assert any("image/png" in o.get("data", {}) for o in outputs), "no figure"
        last = nb.cells[-1].outputs[-1]["data"]["text/plain"]
        assert last.endswith("np.True_)") or last.endswith("True)"), last  # the log diagnosed as the drive
