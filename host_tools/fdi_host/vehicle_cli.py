"""fdi-vehicle: a vehicle is a folder the user owns (fdi_host.vehicle). Make one from a model, regenerate everything
in it, build its plugin, or write a shipped vehicle's plugin glue.

examples:
  fdi-vehicle new out/my_motor --model examples/traction_motor/motor.toml \\
      --scenario examples/traction_motor/drive.toml --dbc examples/traction_motor/motor.dbc \\
      --fault-sizes examples/traction_motor/fault_sizes.toml
  fdi-vehicle regenerate out/my_motor     # report, calibration, fault sizes, generated C, CAN codec, glue, CMake file
  fdi-vehicle build out/my_motor          # CMake: out/my_motor/build/libfdi_vehicle_my_motor.so, the host tools' plugin
  fdi-sim --vehicle out/my_motor --fault speed_offset@60s:2 --out out/my_motor.blf   # then every tool takes the folder
  fdi-vehicle glue three_tank --check  # a shipped vehicle's glue is up to date (scripts/generate.sh writes it)
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tomllib
from collections.abc import Callable, Sequence
from pathlib import Path

from fdi_analysis.cli.common import EXIT_ERROR, add_version, run
from fdi_analysis.export.c_names import VehicleNames
from fdi_analysis.export.fault_sizes import FaultSizes
from fdi_analysis.export.plugin import PluginSpec, render_cmake, render_glue
from fdi_analysis.resources import REPO
from fdi_host.vehicle import MANIFEST, Vehicle, VehicleError, read_manifest, resolve

SEAM_DIR = Path(__file__).resolve().parent / "ecu"  # fdi_py_seam.c, fdi_py_plugin.h, fdi_py_seam.h


def plugin_spec(v: Vehicle) -> PluginSpec:
    p = v.plugin
    return PluginSpec(vehicle=v.name, table=p.table, table_header=p.table_header, bus=p.bus, bus_header=p.bus_header,
                      config_default=p.config_default, config_header=p.config_header, params=p.params,
                      params_header=p.params_header)


def _glue_command(v: Vehicle) -> str:
    return f"fdi-vehicle glue {v.name}" if v.shipped else "fdi-vehicle regenerate"


def write_glue(v: Vehicle, check: bool = False) -> bool:
    """Write the vehicle's plugin glue (or, with `check`, say whether the file is up to date)."""
    text = render_glue(plugin_spec(v), _glue_command(v))
    path = v.plugin.glue
    current = path.read_text(encoding="utf-8") if path.is_file() else None
    if check:
        return current == text
    if current != text:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return True


def _rel(path: Path, base: Path) -> str:
    return os.path.relpath(path, base).replace(os.sep, "/")


# ------------------------------------------------------------------------------------------ new
MANIFEST_FMT = """\
# The vehicle {name}: a folder you own (fdi-vehicle new). Paths are relative to this file. After editing the model,
# the thresholds or the DBC: `fdi-vehicle regenerate <this folder>`, then `fdi-vehicle build <this folder>`.
name = "{name}"
model = "{model}"
thresholds = "thresholds.toml"
{optional}simulator = "generic"

[plugin]
table = "{table}"
table_header = "{table}.h"
{bus}sources = ["generated"{can}]
include_dirs = ["generated"{can}]
"""

THRESHOLDS_FMT = """\
# Gates, design point and calibration of {name}'s tests. `fdi-vehicle regenerate` selects the tests (or takes a
# [selection] you write here), calibrates their variances on the drives of the scenario ([generated]) and exports.
gate = 5.0

[design]
dt = 0.01        # s: the diagnosis step (the scenario's drive.dt)
cutoff_hz = 1.0  # the derivative filters' cut-off
zeta = 0.7071
obs_gain = 2.0

[variance]
"""


def new(folder: Path, model: Path, name: str | None, scenario: Path | None, dbc: Path | None,
        fault_sizes: Path | None) -> Vehicle:
    """Create a vehicle folder from a model (and its scenario, DBC, fault-size file), copied in."""
    if (folder / MANIFEST).exists():
        raise VehicleError(f"{folder / MANIFEST} exists: a vehicle folder is made once (edit it, or remove it)")
    name = name or folder.resolve().name.replace("-", "_")
    if not name.isidentifier() or not name.isascii():
        raise VehicleError(f"vehicle name {name!r} is not a C identifier: give --name")
    for what, path in (("model", model), ("scenario", scenario), ("dbc", dbc), ("fault sizes", fault_sizes)):
        if path is not None and not path.is_file():
            raise VehicleError(f"{what} {path}: no such file")
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(model, folder / "model.toml")
    optional = ""
    for key, path, dest in (("scenario", scenario, "scenario.toml"), ("dbc", dbc, f"{name}.dbc"),
                            ("fault_sizes", fault_sizes, "fault_sizes.toml")):
        if path is not None:
            shutil.copyfile(path, folder / dest)
            optional += f'{key} = "{dest}"\n'
    (folder / "thresholds.toml").write_text(THRESHOLDS_FMT.format(name=name), encoding="utf-8")
    names = VehicleNames(name)
    bus = (f'bus = "fdi_{name}_bus"\nbus_header = "fdi_{name}_bus.h"\n' if dbc is not None else "")
    (folder / MANIFEST).write_text(MANIFEST_FMT.format(
        name=name, model="model.toml", optional=optional, table=names.table, bus=bus,
        can=', "generated/can"' if dbc is not None else ""), encoding="utf-8")
    return read_manifest(folder / MANIFEST)


# ------------------------------------------------------------------------------------------ regenerate
def _step(what: str, main: Callable[[list[str]], int], argv: list[str]) -> None:
    print(f"fdi-vehicle: {what}", flush=True)
    rc = main(argv)
    if rc:
        raise VehicleError(f"{what} failed (exit {rc}): {' '.join(argv)}")


def _calibrated(thresholds: Path) -> bool:
    raw = tomllib.loads(thresholds.read_text(encoding="utf-8"))
    return bool(raw.get("generated"))


def regenerate(v: Vehicle, workers: int, keep_calibration: bool = False) -> None:
    """Everything generated in a vehicle folder, from its model, thresholds, scenario and DBC."""
    from fdi_analysis.cli import main as analyze
    from fdi_host.tuning.generic import tune_vehicle

    if v.shipped:
        raise VehicleError(f"{v.name} is a shipped vehicle: scripts/generate.sh regenerates it in the checkout")
    if v.thresholds is None:
        raise VehicleError(f"{v.manifest}: regenerate needs a thresholds file (thresholds = ...)")
    folder, out = v.folder, v.folder / "generated"
    model, thr = str(v.model), str(v.thresholds)
    common = ["--workers", str(workers), "--no-progress"]
    _step("structural report -> report/", analyze, ["report", model, "-o", str(folder / "report")])
    if v.simulator == "generic" and v.scenario is not None and not (keep_calibration and _calibrated(v.thresholds)):
        _step("calibration on the scenario's fault-free drives -> thresholds [generated]",
              lambda _: tune_vehicle(v, "calibrate", workers), [])
        if v.fault_sizes is not None and FaultSizes.load(v.fault_sizes).limits:
            _step("fault-size sweep -> fault sizes", lambda _: tune_vehicle(v, "fault-sizes", workers), [])
        elif v.fault_sizes is not None:
            print(f"fdi-vehicle: no fault-size sweep: {v.fault_sizes} has no [limits] (per fault, the largest size "
                  "to sweep up to); every test of a fault's signature may exonerate it")
    uncalibrated = [] if _calibrated(v.thresholds) else ["--uncalibrated"]
    sizes = ["--fault-sizes", str(v.fault_sizes)] if v.fault_sizes is not None else []
    _step("generated C -> generated/", analyze,
          ["export-c", model, "--thresholds", thr, *sizes, "--out", str(out), "--name", v.plugin.table,
           "--report", str(folder / "report"), *uncalibrated, *common])
    if v.dbc is not None:
        _step("CAN codec from the DBC -> generated/can/", analyze,
              ["export-can", model, "--dbc", str(v.dbc), "--out", str(out / "can"), "--name", v.plugin.table])
    write_glue(v)
    (folder / "CMakeLists.txt").write_text(
        render_cmake(v.name, [_rel(p, folder) for p in v.c_sources], [_rel(p, folder) for p in v.plugin.include_dirs]),
        encoding="utf-8")
    print(f"fdi-vehicle: {folder} regenerated; build its plugin with `fdi-vehicle build {folder}`")


# ------------------------------------------------------------------------------------------ build
def fdi_source(given: Path | None) -> Path:
    """The fdi source tree the plugin is built from: --fdi-source, FDI_SOURCE_DIR, or this package's checkout."""
    for cand in (given, Path(os.environ["FDI_SOURCE_DIR"]) if os.environ.get("FDI_SOURCE_DIR") else None, REPO):
        if cand is not None and (cand / "fw" / "CMakeLists.txt").is_file():
            return cand.resolve()
    raise VehicleError("no fdi source tree to build the plugin from: give --fdi-source DIR (the folder with "
                       "CMakeLists.txt and fw/; the C package's source archive, `cpack --config "
                       "CPackSourceConfig.cmake`) or set FDI_SOURCE_DIR")


def build(v: Vehicle, source: Path | None, jobs: int) -> Path:
    """Configure and build the vehicle's plugin with CMake; the shared library it made."""
    if v.shipped:
        raise VehicleError(f"{v.name} is a shipped vehicle: its plugin is built by `pip install -e .`")
    if not (v.folder / "CMakeLists.txt").is_file():
        raise VehicleError(f"{v.folder}: no CMakeLists.txt yet; run `fdi-vehicle regenerate {v.folder}` first")
    cmake = shutil.which("cmake")
    if cmake is None:
        raise VehicleError("cmake is not on PATH (apt-get install cmake)")
    build_dir = v.folder / "build"
    src = fdi_source(source)
    for argv in ([cmake, "-S", str(v.folder), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release",
                  f"-DFDI_SOURCE_DIR={src}", f"-DFDI_SEAM_DIR={SEAM_DIR}"],
                 [cmake, "--build", str(build_dir), "--parallel", str(jobs)]):
        print("fdi-vehicle: " + " ".join(argv), flush=True)
        done = subprocess.run(argv, capture_output=True, text=True, check=False)
        if done.returncode != 0:
            sys.stderr.write(done.stdout[-4000:] + done.stderr[-4000:])
            raise VehicleError(f"building the plugin of {v.name} failed (exit {done.returncode}): {' '.join(argv)}")
    return v.library


# ------------------------------------------------------------------------------------------ CLI
def _parser() -> argparse.ArgumentParser:
    doc = __doc__ or ""
    ap = argparse.ArgumentParser(prog="fdi-vehicle", description=doc.split("\n\n")[0],
                                 epilog=doc.split("\n\n", 1)[1], formatter_class=argparse.RawDescriptionHelpFormatter)
    add_version(ap)
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("new", help="make a vehicle folder from a model (copied in, with a thresholds file)")
    p.add_argument("folder", type=Path, help="the folder to make (anywhere on disk)")
    p.add_argument("--model", type=Path, required=True, help="the model file (.toml, analysis/models/README.md)")
    p.add_argument("--name", help="the vehicle's name, a C identifier (default: the folder's name)")
    p.add_argument("--scenario", type=Path, help="drives of the generic simulator (as host_tools/scenarios/"
                                                 "three_tank.toml): calibration and fdi-sim")
    p.add_argument("--dbc", type=Path, help="the vehicle's CAN database with ModelSignal attributes (a bus)")
    p.add_argument("--fault-sizes", type=Path, help="required fault sizes ([requirement], [limits])")
    p = sub.add_parser("regenerate", help="regenerate everything in a vehicle folder")
    p.add_argument("vehicle", help="the vehicle folder")
    p.add_argument("--workers", type=int, default=2, help="processes of the MSO search (default 2)")
    p.add_argument("--keep-calibration", action="store_true",
                   help="keep the thresholds' [generated] and the fault sizes' per-test tables as they are (default: "
                        "calibrate and sweep again on the scenario, for the tests selected now)")
    p = sub.add_parser("build", help="build a vehicle folder's plugin (CMake)")
    p.add_argument("vehicle", help="the vehicle folder")
    p.add_argument("--fdi-source", type=Path, help="the fdi source tree (default: FDI_SOURCE_DIR or this checkout)")
    p.add_argument("--jobs", type=int, default=2, help="parallel compile jobs (default 2)")
    p = sub.add_parser("glue", help="write a vehicle's plugin glue (fdi_<vehicle>_plugin.c)")
    p.add_argument("vehicle", help="a shipped vehicle's name or a vehicle folder")
    p.add_argument("--check", action="store_true", help="exit 1 when the committed glue is stale")
    return ap


def _main(argv: Sequence[str] | None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "new":
        v = new(args.folder, args.model, args.name, args.scenario, args.dbc, args.fault_sizes)
        print(f"fdi-vehicle: made {v.folder} ({v.name}); next: fdi-vehicle regenerate {args.folder}")
        return 0
    v = resolve(args.vehicle)
    if args.command == "regenerate":
        regenerate(v, args.workers, args.keep_calibration)
    elif args.command == "build":
        print(f"fdi-vehicle: built {build(v, args.fdi_source, args.jobs)}")
    elif not write_glue(v, args.check):
        print(f"fdi-vehicle: {v.plugin.glue} is stale: run fdi-vehicle glue {args.vehicle}", file=sys.stderr)
        return EXIT_ERROR
    else:
        print(v.plugin.glue)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    return run("fdi-vehicle", lambda: _main(argv))
