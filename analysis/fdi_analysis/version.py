"""The version of romo-fdi. One source: the VERSION file at the repository's root, which pyproject.toml (the
wheel's metadata) and CMakeLists.txt (the C package fdi::fdi) read too."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

DISTRIBUTION = "romo-fdi"


def package_version() -> str:
    """The installed distribution's version; from a source tree that is not installed, its VERSION file."""
    try:
        return version(DISTRIBUTION)
    except PackageNotFoundError:
        file = Path(__file__).resolve().parents[2] / "VERSION"
        return file.read_text(encoding="utf-8").strip() if file.is_file() else "0+unknown"


__version__ = package_version()
