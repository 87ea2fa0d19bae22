"""Structural fault diagnosis of a model: model files, DM decomposition, MSO sets, isolability, test selection,
residual generators and their C export.

For a notebook or a script, the API of `fdi_analysis.api`, loaded on first use (``import fdi_analysis`` stays
light)::

    import fdi_analysis as fa
    m = fa.DiagnosisModel.load("romo_grouped")    # a shipped model, a TOML model or an FDT JSON file
    m.dm().redundancy, m.isolability().classes, m.select(method="B").tests
"""

from __future__ import annotations

import importlib
from typing import Any

# The package root is a facade above every layer: these names come from fdi_analysis.api (layer 5), imported
# when one of them is first used (PEP 562), so that importing a low layer never loads the API; the version
# (importlib.metadata, 15 ms) likewise.
API_NAMES = ("DiagnosisModel", "Decomposition", "TestSet", "IsolabilityAnalysis", "MsoAnalysis", "TestSelection",
             "ExportResult", "ApiError")
__all__ = ["__version__", *API_NAMES]


def __getattr__(name: str) -> Any:
    if name == "__version__":
        from fdi_analysis.version import __version__

        return __version__
    if name in API_NAMES:
        return getattr(importlib.import_module("fdi_analysis.api"), name)
    raise AttributeError(f"module 'fdi_analysis' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
