"""Shared fixtures: paths of the repository and its model files."""

from __future__ import annotations

import os
import platform
import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
MODELS = REPO / "analysis" / "models"


@pytest.fixture(scope="session")
def repo() -> Path:
    return REPO


@pytest.fixture(scope="session")
def models_dir() -> Path:
    return MODELS



@pytest.fixture(scope="session")
def other_fp_path() -> Callable[[list[str]], subprocess.CompletedProcess[str]]:
    """Runs a command (of the venv, in the repository) in a fresh process that computes on another
    floating-point path than this machine's default: OpenBLAS forced to an older kernel and another thread
    count, numpy's SIMD dispatch switched off (baseline code only). Generated files must come out
    byte-identical under it: they may not depend on the CPU or the BLAS build."""
    from numpy._core._multiarray_umath import __cpu_dispatch__

    env = dict(os.environ)
    env["OPENBLAS_CORETYPE"] = "Prescott" if platform.machine() in ("x86_64", "AMD64") else "ARMV8"
    env["OPENBLAS_NUM_THREADS"] = env["OMP_NUM_THREADS"] = "3"
    env["NPY_DISABLE_CPU_FEATURES"] = " ".join(__cpu_dispatch__)

    def run(argv: list[str]) -> subprocess.CompletedProcess[str]:
        return subprocess.run(argv, cwd=REPO, env=env, capture_output=True, text=True, check=False, timeout=1800)

    return run
