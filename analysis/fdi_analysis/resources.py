"""Files the wheel ships beside the code (the model files, and for `fdi_host` the DBC and the scenarios), found
the same way in a checkout and in an installed wheel.

Each folder has one source, where people edit it (``analysis/models/``, ``dbc/``, ``host_tools/scenarios/``).
Building the wheel copies it into its package (setup.py's ``build_py`` reads the `DataDir` declarations of
this module and of `fdi_host.resources`); an installed package reads its copy through `importlib.resources`,
a checkout (editable install) the source folder itself, so nothing is duplicated in the repository.

    from fdi_analysis.resources import MODELS, model_file
    MODELS.path() / "romo_grouped.toml"          # the installed copy, or analysis/models/ in a checkout
    model_file("romo_grouped")                   # a shipped model by name; a path stays a path
    thresholds_file("romo_thresholds")           # a shipped thresholds file by name

Standard library only: setup.py imports this module before anything is built.
"""

from __future__ import annotations

import importlib.resources
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]  # the checkout's root when running from the source tree


@dataclass(frozen=True)
class DataDir:
    """A folder of files shipped with `package`: edited at `source` (relative to the repository root), installed
    as `folder` (relative to the package), `pattern` selects the files."""

    package: str
    folder: str
    source: str
    pattern: str

    def installed(self) -> Path:
        """Where an installed package holds its copy (it may not exist: a checkout has none)."""
        root = importlib.resources.files(self.package)
        return Path(str(root.joinpath(*self.folder.split("/"))))

    def path(self) -> Path:
        """The installed copy when there is one, else the repository's folder (a checkout). When neither exists
        the installed path is returned, so that what reads it names the place a wheel should have it."""
        installed = self.installed()
        if installed.is_dir():
            return installed
        checkout = REPO / self.source
        return checkout if checkout.is_dir() else installed

    def sources(self, repo: Path = REPO) -> list[Path]:
        """The files a wheel built from `repo` ships, in the repository."""
        return sorted((repo / self.source).glob(self.pattern))


MODELS = DataDir("fdi_analysis", "data/models", "analysis/models", "*.toml")
PACKAGE_DATA: tuple[DataDir, ...] = (MODELS,)


THRESHOLDS_SUFFIX = "_thresholds"  # a shipped thresholds file is <model>_thresholds.toml, beside its model


def _shipped() -> list[str]:
    return sorted(p.stem for p in MODELS.path().glob(MODELS.pattern))


def shipped_models() -> list[str]:
    """Names of the model files shipped with the package (``romo_grouped``, ...; not the thresholds files)."""
    return [n for n in _shipped() if not n.endswith(THRESHOLDS_SUFFIX)]


def shipped_thresholds() -> list[str]:
    """Names of the thresholds files shipped with the package (``romo_thresholds``, ...)."""
    return [n for n in _shipped() if n.endswith(THRESHOLDS_SUFFIX)]


def _file(name_or_path: str | Path, names: list[str]) -> Path:
    p = Path(name_or_path)
    if p.exists() or p.suffix or len(p.parts) != 1 or p.name not in names:
        return p
    return MODELS.path() / f"{p.name}.toml"


def model_file(name_or_path: str | Path) -> Path:
    """A model file: an existing path as given, else a bare name (no suffix, no folder) of a shipped model, so
    that ``fdi-analyze report romo_quasistatic`` works from any directory. Anything else is returned as given
    (the loader then names the missing file)."""
    return _file(name_or_path, shipped_models())


def thresholds_file(name_or_path: str | Path) -> Path:
    """A thresholds file: an existing path as given, else a bare name of a shipped one (``--thresholds
    romo_thresholds``); anything else as given."""
    return _file(name_or_path, shipped_thresholds())
