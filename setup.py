"""Declares the C extension of the analysis package; everything else is in pyproject.toml.

`pip install -e .` (or scripts/bootstrap.sh) compiles fdi_analysis.mso._core and fdi_host.ecu._fdi_ecu (the fw/
C diagnoser and ECU core for the ctypes bindings in fdi_host.ecu.bindings) with the system C compiler.
"""

import platform
from pathlib import Path

from setuptools import Extension, setup

_cflags = ["-O3", "-std=c11", "-Wall", "-Wextra", "-fno-strict-aliasing"]
if platform.machine() in ("x86_64", "AMD64"):
    _cflags.append("-mpopcnt")

# Sources of the ECU bindings: the fw library, its generated table, the generated CAN code, the ECU core.
_ECU_DIRS = ("fw/src", "fw/generated", "fw/generated/can", "fw/ecu/src")

setup(
    ext_modules=[
        Extension(
            "fdi_analysis.mso._core",
            sources=["analysis/fdi_analysis/mso/_core.c"],
            depends=["analysis/fdi_analysis/mso/_core_impl.h"],
            extra_compile_args=_cflags,
        ),
        # The C diagnoser + ECU core (fw/) as a shared library for host_tools/fdi_host/ecu/bindings.py (ctypes).
        Extension(
            "fdi_host.ecu._fdi_ecu",
            sources=sorted(
                ["host_tools/fdi_host/ecu/_fdi_ecu.c"]
                + [str(p) for d in _ECU_DIRS for p in Path(d).glob("*.c")]
            ),
            include_dirs=["fw/include", "fw/src", "fw/generated", "fw/generated/can", "fw/ecu/include"],
            depends=sorted(str(p) for d in (*_ECU_DIRS, "fw/include", "fw/ecu/include") for p in Path(d).glob("*.h")),
            extra_compile_args=["-O2", "-std=c99", "-Wall", "-Wextra"],
            libraries=["m"],
        ),
    ]
)
