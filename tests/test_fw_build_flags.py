"""How CMake compiles the generated generators (cmake/FdiGenerated.cmake): with -Os after the build type's flags in
Release and RelWithDebInfo builds, every vehicle's generated generators and nothing else; the build type's own
level with FDI_GENERATED_FOR_SIZE=OFF and in Debug builds. Read from the compile commands of a configured tree."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
GENERATORS = sorted(str(p.relative_to(REPO)) for p in (REPO / "fw/vehicles").glob("*/generated/*_generators.c"))

pytestmark = pytest.mark.skipif(shutil.which("cmake") is None, reason="cmake not installed")


def _commands(tmp_path: Path, *args: str) -> dict[str, list[str]]:
    """source (relative to the repository) -> its compiler arguments, for a host tree configured with args."""
    build = tmp_path / "build"
    subprocess.run(["cmake", "-S", str(REPO), "-B", str(build), "-DCMAKE_EXPORT_COMPILE_COMMANDS=ON",
                    "-DFDI_BUILD_TESTS=OFF", "-DFDI_BUILD_BENCH=OFF", *args], check=True, capture_output=True)
    rows = json.loads((build / "compile_commands.json").read_text())
    return {str(Path(r["file"]).resolve().relative_to(REPO)): r["command"].split() for r in rows}


def _level(argv: list[str]) -> str | None:
    """The optimisation level the compiler uses: its last -O option."""
    levels = [a for a in argv if a.startswith("-O")]
    return levels[-1] if levels else None


def test_generators_are_built_for_size_in_release(tmp_path: Path) -> None:
    assert len(GENERATORS) >= 2  # ROMO and the three-tank benchmark
    cmds = _commands(tmp_path, "-DCMAKE_BUILD_TYPE=Release")
    for src in GENERATORS:
        assert _level(cmds[src]) == "-Os", src
    others = [s for s in cmds if s not in GENERATORS]
    assert "fw/src/fdi_diag.c" in others
    for src in others:
        assert _level(cmds[src]) == "-O3", src


def test_the_option_off_and_debug_builds_keep_the_build_types_level(tmp_path: Path) -> None:
    off = _commands(tmp_path / "off", "-DCMAKE_BUILD_TYPE=Release", "-DFDI_GENERATED_FOR_SIZE=OFF")
    debug = _commands(tmp_path / "debug", "-DCMAKE_BUILD_TYPE=Debug")
    for src in GENERATORS:
        assert _level(off[src]) == "-O3", src
        assert _level(debug[src]) is None, src  # CMake's Debug flags are -g only
