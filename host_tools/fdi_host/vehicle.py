"""A vehicle, as every host tool takes it (``--vehicle NAME|PATH``): its model, thresholds, DBC, drive scenarios
and the plugin the host ECU loads (its compiled diagnosis, host_tools/fdi_host/ecu/fdi_py_plugin.h).

A vehicle is described by a manifest, ``vehicle.toml``; paths in it are relative to the manifest's folder:

    name = "my_car"                  # a C identifier: the plugin is fdi_vehicle_my_car
    model = "model.toml"             # or the name of a shipped model ("romo_quasistatic")
    thresholds = "thresholds.toml"   # optional; a path or a shipped name
    dbc = "my_car.dbc"               # optional: without one the vehicle has no bus (a Diagnoser, not an ECU)
    scenario = "scenario.toml"       # the generic simulator's drives (fdi_host.sim.generic)
    simulator = "generic"            # or "romo": the ROMO simulator and truth plant
    [plugin]                          # what the plugin glue names (fdi_analysis.export.plugin.PluginSpec)
    table = "fdi_my_car_table"
    table_header = "fdi_my_car_table.h"
    glue = "generated/fdi_my_car_plugin.c"   # where the glue is written (fdi-vehicle regenerate)
    sources = ["generated"]          # C files, or folders whose *.c the plugin compiles (besides the glue)
    include_dirs = ["generated"]

A user's vehicle is a folder holding ``vehicle.toml`` (``fdi-vehicle new``), found by its path; its plugin is
``build/libfdi_vehicle_<name>.so`` (``fdi-vehicle build``). The shipped vehicles (ROMO, its kinematic table, the
three-tank system) are manifests of the package (host_tools/vehicles/<name>.toml), found by name; their plugins are
built by setup.py as the modules ``fdi_host.ecu._plugin_<name>``.

Standard library only (and the project's resources and errors): setup.py reads the shipped manifests to build
their plugins.
"""

from __future__ import annotations

import argparse
import importlib.util
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from pathlib import Path

from fdi_analysis.resources import model_file, thresholds_file
from fdi_host.errors import FdiHostError
from fdi_host.resources import DBC, SCENARIOS
from fdi_host.resources import VEHICLES as SHIPPED

__all__ = ["MANIFEST", "SHIPPED", "PluginInfo", "Vehicle", "VehicleError", "add_vehicle_argument", "plugin_module",
           "read_manifest", "resolve", "shipped_vehicles", "vehicle_arg"]

MANIFEST = "vehicle.toml"  # the manifest of a user's vehicle folder
SIMULATORS = ("romo", "generic")
_TOP_KEYS = {"name", "model", "thresholds", "dbc", "scenario", "fault_sizes", "simulator", "plugin"}
_PLUGIN_KEYS = {"glue", "table", "table_header", "bus", "bus_header", "config_default", "config_header", "params",
                "params_header", "sources", "include_dirs"}


class VehicleError(FdiHostError, ValueError):
    """A vehicle that cannot be found or a manifest that cannot be read; the message names the file and the key."""


@dataclass(frozen=True)
class PluginInfo:
    """The [plugin] table of a manifest: the glue's C names and file, and the C the plugin compiles (files or
    folders of them, absolute)."""

    glue: Path
    table: str
    table_header: str
    bus: str = ""
    bus_header: str = ""
    config_default: str = ""
    config_header: str = ""
    params: tuple[tuple[str, str], ...] = ()
    params_header: str = ""
    sources: tuple[Path, ...] = ()
    include_dirs: tuple[Path, ...] = ()


@dataclass(frozen=True)
class Vehicle:
    name: str
    manifest: Path
    model: Path
    plugin: PluginInfo
    simulator: str = "generic"
    thresholds: Path | None = None
    dbc: Path | None = None
    scenario: Path | None = None
    fault_sizes: Path | None = None
    shipped: bool = False

    @property
    def folder(self) -> Path:
        return self.manifest.parent

    @property
    def spec(self) -> str:
        """How the tools name it (``--vehicle``): a shipped vehicle by its name, a user's by its folder."""
        return self.name if self.shipped else str(self.folder)

    @property
    def c_sources(self) -> list[Path]:
        """The vehicle's C files of its plugin, the glue last (without the fw/ core and the seam)."""
        files: list[Path] = []
        for p in self.plugin.sources:
            files += sorted(p.glob("*.c")) if p.is_dir() else [p]
        return [f for f in files if f != self.plugin.glue] + [self.plugin.glue]

    @property
    def has_bus(self) -> bool:
        return bool(self.plugin.bus)

    @property
    def library(self) -> Path:
        """The plugin's shared library: a shipped vehicle's extension module, a user's CMake build."""
        if self.shipped:
            spec = importlib.util.find_spec(plugin_module(self.name))
            if spec is None or spec.origin is None:
                raise VehicleError(f"the plugin of the shipped vehicle {self.name!r} is not built: run "
                                   "`pip install -e .` (scripts/bootstrap.sh)")
            return Path(spec.origin)
        lib = self.folder / "build" / f"libfdi_vehicle_{self.name}.so"
        if not lib.is_file():
            raise VehicleError(f"vehicle {self.name!r}: its plugin {lib} is not built; run "
                               f"`fdi-vehicle build {self.folder}`")
        return lib


def plugin_module(name: str) -> str:
    """The extension module that holds a shipped vehicle's plugin."""
    return f"fdi_host.ecu._plugin_{name}"


def shipped_vehicles() -> list[str]:
    """Names of the vehicles shipped with the package."""
    return sorted(p.stem for p in SHIPPED.path().glob(SHIPPED.pattern))


def _str(d: dict[str, object], key: str, where: str, default: str = "") -> str:
    v = d.get(key, default)
    if not isinstance(v, str):
        raise VehicleError(f"{where}: {key} must be a string, not {v!r}")
    return v


def _paths(d: dict[str, object], key: str, where: str, base: Path) -> tuple[Path, ...]:
    v = d.get(key, [])
    if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
        raise VehicleError(f"{where}: {key} must be a list of paths, not {v!r}")
    return tuple((base / x).resolve() for x in v)


def read_manifest(path: Path, shipped: bool = False) -> Vehicle:
    """The vehicle a manifest describes (a clear error naming the file and the key for a bad one)."""
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise VehicleError(f"{path}: cannot read the vehicle manifest ({exc.strerror})") from None
    except tomllib.TOMLDecodeError as exc:
        raise VehicleError(f"{path}: not TOML ({exc})") from None
    where = str(path)
    unknown = sorted(set(raw) - _TOP_KEYS)
    if unknown:
        raise VehicleError(f"{where}: unknown key(s) {unknown}; a manifest has {sorted(_TOP_KEYS)}")
    base = path.parent
    name = _str(raw, "name", where)
    if not name.isidentifier() or not name.isascii():
        raise VehicleError(f"{where}: name {name!r} is not a C identifier (the plugin is fdi_vehicle_<name>)")
    simulator = _str(raw, "simulator", where, "generic")
    if simulator not in SIMULATORS:
        raise VehicleError(f"{where}: simulator {simulator!r}; use one of {SIMULATORS}")

    def file(key: str, shipped: Callable[[str], Path]) -> Path | None:
        """The file `key` names: beside the manifest, else a shipped file of that name."""
        text = _str(raw, key, where)
        if not text:
            return None
        for found in (base / text, shipped(text)):
            if found.exists():
                return found.resolve()
        raise VehicleError(f"{where}: {key} = {text!r}: no such file beside the manifest nor a shipped one")

    def shipped_scenario(n: str) -> Path:
        return SCENARIOS.path() / f"{n}.toml"

    model = file("model", model_file)
    if model is None:
        raise VehicleError(f"{where}: no model (model = \"model.toml\")")
    plug = raw.get("plugin")
    if not isinstance(plug, dict):
        raise VehicleError(f"{where}: no [plugin] table (its table, table_header, sources, include_dirs)")
    pw = f"{where} [plugin]"
    unknown = sorted(set(plug) - _PLUGIN_KEYS)
    if unknown:
        raise VehicleError(f"{pw}: unknown key(s) {unknown}; it has {sorted(_PLUGIN_KEYS)}")
    params = plug.get("params", {})
    if not isinstance(params, dict) or not all(isinstance(v, str) for v in params.values()):
        raise VehicleError(f"{pw}: params must map a parameter's name to its C index constant")
    glue = _str(plug, "glue", pw) or f"generated/fdi_{name}_plugin.c"
    info = PluginInfo(
        glue=(base / glue).resolve(), table=_str(plug, "table", pw), table_header=_str(plug, "table_header", pw),
        bus=_str(plug, "bus", pw),
        bus_header=_str(plug, "bus_header", pw), config_default=_str(plug, "config_default", pw),
        config_header=_str(plug, "config_header", pw), params=tuple(sorted(params.items())),
        params_header=_str(plug, "params_header", pw), sources=_paths(plug, "sources", pw, base),
        include_dirs=_paths(plug, "include_dirs", pw, base))
    if not info.table or not info.table_header:
        raise VehicleError(f"{pw}: table and table_header are required")
    return Vehicle(name=name, manifest=path.resolve(), model=model, plugin=info, simulator=simulator,
                   thresholds=file("thresholds", thresholds_file), dbc=file("dbc", lambda n: DBC.path() / f"{n}.dbc"),
                   scenario=file("scenario", shipped_scenario), fault_sizes=file("fault_sizes", shipped_scenario),
                   shipped=shipped)


@cache
def resolve(spec: str | Path) -> Vehicle:
    """``--vehicle NAME|PATH``: a shipped vehicle by name, else a vehicle folder (or its manifest) by path (its
    manifest read once per process)."""
    text = str(spec)
    p = Path(text)
    if len(p.parts) == 1 and not p.suffix and text in shipped_vehicles():
        return read_manifest(SHIPPED.path() / f"{text}.toml", shipped=True)
    manifest = p / MANIFEST if p.is_dir() else p
    if manifest.is_file():
        return read_manifest(manifest)
    raise VehicleError(f"no vehicle {text!r}: neither a shipped one ({', '.join(shipped_vehicles())}) nor a folder "
                       f"with {MANIFEST} (fdi-vehicle new PATH --model MODEL makes one)")


def vehicle_arg(text: str) -> str:
    """argparse type of ``--vehicle``: a shipped vehicle's name as given, a vehicle folder as its absolute path."""
    try:
        v = resolve(text)
    except VehicleError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return v.spec


def add_vehicle_argument(ap: argparse.ArgumentParser, what: str = "the ECU's diagnosis",
                         default: str = "romo") -> None:
    """``--vehicle NAME|PATH`` (``--table``, its former name, still accepted) into ``args.vehicle``."""
    ap.add_argument("--vehicle", "--table", dest="vehicle", type=vehicle_arg, default=default, metavar="NAME|PATH",
                    help=f"{what}: a shipped vehicle ({', '.join(shipped_vehicles())}) or a vehicle folder "
                         f"(fdi-vehicle new) (default {default}; --table is its former name)")
