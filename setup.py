"""Declares the C extensions and the package data; everything else is in pyproject.toml.

`pip install -e .` (or scripts/bootstrap.sh) compiles fdi_analysis.mso._core and, with the system C compiler, one
plugin per shipped vehicle (host_tools/vehicles/<name>.toml, fdi_host.vehicle): fdi_host.ecu._plugin_<name>, the fw/ C
diagnoser and ECU core, the host seam and the vehicle's diagnosis, which the ctypes bindings in fdi_host.ecu.bindings
load. A user's vehicle is built by `fdi-vehicle build` instead; nothing here names a vehicle.
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
from fdi_host import vehicle as vehicles  # noqa: E402

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

# The generic part of every vehicle plugin: the fw core, the ECU core and the host seam.
_CORE_DIRS = ("fw/src", "fw/ecu/src")
_CORE_INCLUDES = ("fw/include", "fw/src", "fw/ecu/include", "host_tools/fdi_host/ecu")
_HERE = Path.cwd()


def _plugin(manifest: Path) -> Extension:
    """A shipped vehicle's plugin (fdi_host.ecu._plugin_<name>, loaded by ctypes: no Python module init)."""
    v = vehicles.read_manifest(manifest, shipped=True)
    core = [p for d in _CORE_DIRS for p in Path(d).glob("*.c")] + [Path("host_tools/fdi_host/ecu/fdi_py_seam.c")]
    own = [p.relative_to(_HERE) for p in v.c_sources]
    includes = [*_CORE_INCLUDES, *(str(p.relative_to(_HERE)) for p in v.plugin.include_dirs)]
    return Extension(
        vehicles.plugin_module(v.name),
        sources=sorted(str(p) for p in core) + [str(p) for p in own],
        include_dirs=includes,
        depends=sorted(str(p) for d in (*includes, "fw/include/generated") for p in Path(d).glob("*.h")),
        extra_compile_args=["-O2", "-std=c99", "-Wall", "-Wextra"],
        libraries=["m"],
    )


setup(
    cmdclass={"build_py": BuildPyWithData},
    ext_modules=[
        Extension(
            "fdi_analysis.mso._core",
            sources=["analysis/fdi_analysis/mso/_core.c"],
            depends=["analysis/fdi_analysis/mso/_core_impl.h"],
            extra_compile_args=_cflags,
        ),
        *(_plugin(p) for p in vehicles.SHIPPED.sources(_HERE)),
    ]
)
