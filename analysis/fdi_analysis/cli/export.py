"""`fdi-analyze export-c MODEL`: the firmware's diagnosis table (selected MSOs, signatures, classes) as C."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from fdi_analysis.export import generators as emit_c
from fdi_analysis.export import report
from fdi_analysis.export import signals as emit_signals
from fdi_analysis.export import table as emit_table
from fdi_analysis.export.c_names import VehicleNames
from fdi_analysis.export.c_text import banner
from fdi_analysis.export.capacity import DEFAULT as DEFAULT_CAPACITY
from fdi_analysis.export.capacity import MACROS, Capacity
from fdi_analysis.export.fault_sizes import FaultSizes
from fdi_analysis.export.thresholds import Thresholds
from fdi_analysis.model_loader import load_model

EXAMPLE = ("example: fdi-analyze export-c analysis/models/romo_grouped.toml "
           "--thresholds analysis/models/romo_thresholds.toml --fault-sizes host_tools/scenarios/fault_sizes.toml "
           "--out fw/vehicles/romo/generated")


def register(sub: Any) -> None:
    p = sub.add_parser(
        "export-c",
        help="write the C diagnosis table (fdi_table_t) and residual generators of the tests on board",
        description="Take the tests of the thresholds file's [selection] table (fdi-analyze practical: selection "
        "by practical isolability) or, without one, the optimal MSO selection of MODEL (method B, fewest tests "
        "then fewest unknowns) among the realizable candidates, and write the vehicle target's generated C: "
        "NAME.h / NAME.c (tests with fault bitmasks, signals, generator descriptors, gates and variances, fault "
        "names, the signature matrix and the isolability classes), fdi_<vehicle>_generators.h/.c (the residual "
        "generators, with their fault sensitivities) and fdi_<vehicle>_signals.h/.c (the signal frame); the "
        "vehicle is NAME without fdi_ and _table.",
        epilog=EXAMPLE,
    )
    p.add_argument("model", type=Path, help="model file (.toml) or FDT structure (.json)")
    p.add_argument("--thresholds", type=Path, required=True, help="gates, variances and generator design point")
    p.add_argument("--fault-sizes", type=Path, default=None,
                   help="stated fault sizes per test (fdi-tune fault-sizes); a test exonerates a fault only when "
                   "it reacts at the fault's stated size (default: every test of the signature exonerates)")
    p.add_argument("--out", type=Path, required=True, help="output folder (fw/vehicles/<vehicle>/generated)")
    p.add_argument("--report", type=Path, default=None,
                   help="also write generators.md / .json / .png here: per test its MSO set, residual equation, "
                   "causality, inputs, domain, sigma and the stated fault sizes of --fault-sizes")
    p.add_argument("--name", default="fdi_romo_table", help="C name of the table (default fdi_romo_table)")
    p.add_argument("--uncalibrated", action="store_true",
                   help="export even when the thresholds file has no calibrated variance ([generated], fdi-tune "
                   "calibrate) for a test: placeholders (1.0), the files marked UNCALIBRATED (not for a vehicle); "
                   "without it such a table is refused")
    p.add_argument("--capacity", action="append", default=[], metavar="MACRO=N",
                   help="a capacity the firmware is built with when not the library's default (cmake -DMACRO=N), "
                   f"repeatable; MACRO one of {', '.join(MACROS.values())}: a table or generator set beyond the "
                   "capacities is refused, naming both numbers")
    p.add_argument("--workers", type=int, default=2, help="worker processes of the MSO search (default 2)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def command_line(model: Path, thresholds: Path, out: Path, name: str, sizes: Path | None = None,
                 uncalibrated: bool = False, capacity: Capacity = DEFAULT_CAPACITY) -> str:
    return (f"fdi-analyze export-c {model.as_posix()} --thresholds {thresholds.as_posix()}"
            + (f" --fault-sizes {sizes.as_posix()}" if sizes is not None else "")
            + f" --out {out.as_posix()}" + (f" --name {name}" if name != "fdi_romo_table" else "")
            + (" --uncalibrated" if uncalibrated else "") + capacity.options())


def generate(model_path: Path, thresholds_path: Path, out: Path, name: str, workers: int = 2,
             progress: bool = False, sizes_path: Path | None = None, uncalibrated: bool = False,
             capacity: Capacity = DEFAULT_CAPACITY) -> tuple[str, str]:
    files = generate_all(model_path, thresholds_path, out, name, workers, progress, sizes_path,
                         uncalibrated=uncalibrated, capacity=capacity)
    return files[f"{name}.h"], files[f"{name}.c"]


def generate_all(model_path: Path, thresholds_path: Path, out: Path, name: str, workers: int = 2,
                 progress: bool = False, sizes_path: Path | None = None,
                 report_dir: Path | None = None, uncalibrated: bool = False,
                 capacity: Capacity = DEFAULT_CAPACITY) -> dict[str, str]:
    """The table and the generated residual generators of the optimal selection among realizable MSOs (and the
    generator report in `report_dir`). A test without a calibrated variance in the thresholds file is an
    `ExportError` unless `uncalibrated` (then placeholders, the table files marked UNCALIBRATED); a table or
    generator set beyond `capacity` (the firmware's capacities, export.capacity) is refused."""
    from fdi_analysis.residuals.estimation import estimated
    from fdi_analysis.residuals.evaluate import FilterDesign, response_time
    from fdi_analysis.residuals.selected import selected_generators
    from fdi_analysis.residuals.uncertainty_sensitivity import half_widths, uncertainties

    model = load_model(model_path)
    command = command_line(model_path, thresholds_path, out, name, sizes_path, uncalibrated, capacity)
    sizes = FaultSizes.load(sizes_path) if sizes_path is not None else None
    thresholds = Thresholds.load(thresholds_path)
    tests, gens = selected_generators(model, thresholds.observer_reference(), workers=workers, progress=progress,
                                      selection=thresholds.selection, max_tyre_accel=thresholds.max_tyre_accel,
                                      sensitivities=True, uncertainty=True)
    names = VehicleNames.of_table(name)
    top = banner(command)
    design = FilterDesign(*thresholds.design[:3])
    response = [response_time(g, design) for g in gens]
    header, source = emit_table.render_file(emit_table.table_file(model, tests, thresholds, names, top, sizes=sizes,
                                                                  response_s=response,
                                                                  domain_inputs=[emit_c.inputs(g) for g in gens],
                                                                  uncalibrated=uncalibrated, capacity=capacity))
    if report_dir is not None:
        sigmas = thresholds.sigmas(gens)
        rows = report.rows(gens, sigmas, thresholds.gate, sizes, sizes.limits if sizes is not None else {})
        for path in report.write(report_dir, name, rows, list(model.structure().faults),
                                 sizes_path.as_posix() if sizes_path is not None else "(no fault-size file)"):
            print(f"wrote {path}")
    faults = [f.name for f in model.faults]
    quantities = {u.name: u for u in uncertainties(model)}
    est = {g.name: estimated(g, thresholds.estimation.get(" ".join(g.equations), ()), quantities, design.dt)
           for g in gens}
    gh, gc = emit_c.render(emit_c.generators_file(gens, names, faults, top, signals=[k.name for k in model.knowns],
                                                  widths=half_widths(model), estimation=est,
                                                  capacity=capacity))
    sh, sc = emit_signals.render(emit_signals.signals_file(model, names, top))
    return {f"{name}.h": header, f"{name}.c": source, f"{names.generators}.h": gh, f"{names.generators}.c": gc,
            f"{names.signals}.h": sh, f"{names.signals}.c": sc}


def generators_name(table_name: str) -> str:
    return VehicleNames.of_table(table_name).generators


def run(args: argparse.Namespace) -> int:
    files = generate_all(args.model, args.thresholds, args.out, args.name, args.workers, not args.no_progress,
                         args.fault_sizes, args.report, args.uncalibrated, Capacity.parse(args.capacity))
    args.out.mkdir(parents=True, exist_ok=True)
    for fname, text in files.items():
        (args.out / fname).write_text(text, encoding="utf-8")
        print(f"wrote {args.out / fname}")
    return 0
