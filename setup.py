"""Declares the C extensions and the package data; everything else is in pyproject.toml.

`pip install -e .` (or scripts/bootstrap.sh) compiles fdi_analysis.mso._core and fdi_host.ecu._fdi_ecu (the fw/
C diagnoser and ECU core for the ctypes bindings in fdi_host.ecu.bindings) with the system C compiler.
`pip wheel .` also copies the shipped files (models, DBC, scenarios: the `PACKAGE_DATA` of
fdi_analysis/resources.py and fdi_host/resources.py) from their one source folder into the packages.
"""

import platform
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_py import build_py

sys.path[:0] = ["analysis", "host_tools"]  # the resources modules (standard library only) declare the data
from fdi_analysis import resources as analysis_resources  # noqa: E402
from fdi_host import resources as host_resources  # noqa: E402

del sys.path[:2]


class BuildPyWithData(build_py):
    """build_py, then the shipped folders copied from the repository into the built packages (not for an
    editable install: the checkout reads the source folders)."""

    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):
            return
        for d in (*analysis_resources.PACKAGE_DATA, *host_resources.PACKAGE_DATA):
            dest = Path(self.build_lib, d.package, *d.folder.split("/"))
            self.mkpath(str(dest))
            for src in d.sources(Path.cwd()):
                self.copy_file(str(src), str(dest / src.name))


_cflags = ["-O3", "-std=c11", "-Wall", "-Wextra", "-fno-strict-aliasing"]
if platform.machine() in ("x86_64", "AMD64"):
    _cflags.append("-mpopcnt")

# Sources of the ECU bindings: the generic fw core and ECU core, and the vehicle targets (ROMO: tables, generators,
# CAN bus; three-tank: table, generators).
_ECU_DIRS = ("fw/src", "fw/ecu/src", "fw/vehicles/romo/src", "fw/vehicles/romo/generated",
             "fw/vehicles/romo/generated/can", "fw/vehicles/three_tank/generated")
_ECU_INCLUDES = ("fw/include", "fw/src", "fw/ecu/include", "fw/vehicles/romo/include", "fw/vehicles/romo/generated",
                 "fw/vehicles/romo/generated/can", "fw/vehicles/three_tank/generated")

setup(
    cmdclass={"build_py": BuildPyWithData},
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
            include_dirs=list(_ECU_INCLUDES),
            depends=sorted(str(p) for d in (*_ECU_DIRS, *_ECU_INCLUDES, "fw/include/generated",
                                            "host_tools/fdi_host/ecu") for p in Path(d).glob("*.h")),
            extra_compile_args=["-O2", "-std=c99", "-Wall", "-Wextra"],
            libraries=["m"],
        ),
    ]
)
