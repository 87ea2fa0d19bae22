"""Declares the C extension of the analysis package; everything else is in pyproject.toml.

`pip install -e .` (or scripts/bootstrap.sh) compiles fdi_analysis.mso._core with the system C compiler.
"""

import platform

from setuptools import Extension, setup

_cflags = ["-O3", "-std=c11", "-Wall", "-Wextra", "-fno-strict-aliasing"]
if platform.machine() in ("x86_64", "AMD64"):
    _cflags.append("-mpopcnt")

setup(
    ext_modules=[
        Extension(
            "fdi_analysis.mso._core",
            sources=["analysis/fdi_analysis/mso/_core.c"],
            depends=["analysis/fdi_analysis/mso/_core_impl.h"],
            extra_compile_args=_cflags,
        )
    ]
)
