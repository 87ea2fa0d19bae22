"""`fdi-quality`: the diagnosis quality suite (all faults at their required sizes x scenarios x noise seeds,
plus fault-free drives) through the C ECU core, offline; writes quality.json and quality.md."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from tqdm import tqdm

from fdi_analysis.cli.common import add_version, fail, run
from fdi_analysis.errors import FdiError, InputError
from fdi_host.ecu.bindings import Diagnoser, Ecu, EcuError
from fdi_host.quality.report import markdown, write_json, write_markdown
from fdi_host.quality.suite import CASE_SEEDS, DEFAULT_SIZES, SHAPES, SuiteConfig, run_suite
from fdi_host.sim.scenario import SCENARIOS
from fdi_host.vehicle import add_vehicle_argument, resolve

EXAMPLES = """examples:
  fdi-quality --vehicle romo --out out/quality-romo     # full run: 5 scenarios x 3 seeds, steps at the required sizes,
                                                        # 30 min fault-free
  fdi-quality --vehicle romo --quick --out out/quality-quick   # CI size: cornering, one seed, 0.3 min fault-free
  fdi-quality --vehicle romo --faults f6 f10 --scenarios cornering slalom --shapes step ramp --multipliers 1 2
  fdi-quality --vehicle romo --trace f6:straight:2001 --out out/trace   # one case step by step: alarms, candidates,
                                                                        # the exoneration's evidence, ratios plot
                                                                        # (trace-f6-straight-2001.png)
  fdi-quality --vehicle romo --trace f6:slalom:2001 --linearity --out out/trace   # and how far each test's response
                                                        # departs from what its sensitivity predicts (rho), with a
                                                        # plot (linearity-f6-slalom-2001.png)
  fdi-quality --vehicle romo --linearity --seeds 2001 --out out/linearity   # the same over every fault x scenario:
                                                        # where the tests' rho differ by more than the rule's margin
                                                        # (linearity.json, linearity.md, linearity.png)
  fdi-quality --vehicle romo --ecu noise_allowance=2 --out out/quality-na2   # a study with another ECU setting
  fdi-quality --fleet 25 --out out/fleet      # truth-plant fleet: 25 vehicles x 8 scenarios, the model plant beside,
                                              # false alarms per hour, minimum detectable faults (about 40 min)
  fdi-quality --fleet 2 --quick --out out/fleet-quick   # CI size: 2 vehicles, cornering and the wet patch
  fdi-quality --replot out/fleet/fleet.json   # redraw a saved fleet run's plots (fleet.png beside it)
"""


def parse_ecu_settings(table: str, items: list[str]) -> tuple[tuple[str, float | int | str], ...]:
    """["noise_allowance=2", ...] -> (("noise_allowance", 2), ...), checked by building an ECU with them."""
    out: list[tuple[str, float | int | str]] = []
    for item in items:
        key, sep, text = item.partition("=")
        if not sep or not key.strip() or not text.strip():
            raise InputError(f"--ecu {item!r}: expected KEY=VALUE, e.g. noise_allowance=2")
        word = text.strip()
        value: float | int | str = word
        if word.lower() in ("true", "false"):  # sensitivities=false must not read as a non-empty string
            value = word.lower() == "true"
        else:
            for kind in (int, float):
                try:
                    value = kind(word)
                    break
                except ValueError:
                    continue
        out.append((key.strip(), value))
    if out:
        try:
            (Ecu if resolve(table).has_bus else Diagnoser)(table, **dict(out))
        except (TypeError, ValueError, EcuError) as exc:
            raise InputError(f"--ecu: {exc}") from exc
    return tuple(out)


def quick_config(table: str) -> SuiteConfig:
    return SuiteConfig(table=table, scenarios=("cornering",), seeds=CASE_SEEDS[:1], fault_free_minutes=0.3)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="fdi-quality", description=__doc__, epilog=EXAMPLES,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    add_version(p)
    add_vehicle_argument(p)
    p.add_argument("--quick", action="store_true", help="small run for CI (cornering, one seed)")
    p.add_argument("--scenarios", nargs="+", default=None, help=f"scenarios (default: {' '.join(SCENARIOS)})")
    p.add_argument("--faults", nargs="+", default=None, help="faults to run (default: every fault of the table)")
    p.add_argument("--seeds", nargs="+", type=int, default=None,
                   help=f"noise seeds of the fault cases (default {' '.join(map(str, CASE_SEEDS))})")
    p.add_argument("--multipliers", nargs="+", type=float, default=None,
                   help="sizes as multiples of the required size (default 1)")
    p.add_argument("--shapes", nargs="+", default=None, choices=SHAPES)
    p.add_argument("--fault-free-minutes", type=float, default=None, help="fault-free driving (default 30)")
    p.add_argument("--sizes", type=Path, default=DEFAULT_SIZES, help="required fault sizes (TOML [requirement])")
    p.add_argument("--ecu", metavar="KEY=VALUE", action="append", default=[],
                   help="an ECU setting other than its default, for studies (repeatable; e.g. noise_allowance=2, "
                        "sens_every=1, cusum_h=100: the options of fdi_host.ecu.bindings.Ecu); the report names them")
    p.add_argument("--trace", metavar="FAULT:SCENARIO:SEED", default=None,
                   help="instead of the suite: one case at its required size (x the first multiplier; a step, or the "
                        "first of --shapes), its alarms and candidates step by step (and a plot of the ratios in "
                        "--out)")
    p.add_argument("--linearity", action="store_true",
                   help="with --trace: each test's response to the fault against the response its sensitivity "
                        "predicts (the linearisation the on-line exoneration relies on), and a plot in --out; "
                        "without: the same over the suite's cases (faults x scenarios x seeds), where the tests' "
                        "departures exceed the rule's margin (linearity.json, .md and .png in --out)")
    p.add_argument("--fleet", type=int, metavar="N", default=None,
                   help="instead of the model-plant suite: the fleet suite on N truth-plant vehicles drawn from the "
                        "envelope (all eight scenarios, the model plant's figures beside; fleet.json, fleet.md and "
                        "fleet.png in --out)")
    p.add_argument("--workers", type=int, default=None, help="with --fleet: local processes (default one per core)")
    p.add_argument("--scheduler", default=None, help="with --fleet: a Dask scheduler (tcp://host:8786) instead")
    p.add_argument("--no-sweep", action="store_true", help="with --fleet: no minimum-detectable-fault search")
    p.add_argument("--repetitions", type=int, metavar="R", default=None,
                   help="with --fleet: fault-free drives per vehicle and scenario, each on its own noise seed of the "
                        "fleet plan (1..4, default 1; the fault cases use the first): 27 vehicles x 3 give > 5 h, "
                        "the false-alarm goal's span")
    p.add_argument("--replot", type=Path, metavar="FLEET_JSON", default=None,
                   help="instead of a run: redraw the plots of a saved fleet run (its fleet.json) into --out "
                        "(default: beside it)")
    p.add_argument("-o", "--out", type=Path, default=None,
                   help="folder for quality.json and quality.md (with --trace or --linearity: their files)")
    args = p.parse_args(argv)
    return run("fdi-quality", lambda: _main(args))


def _main(args: argparse.Namespace) -> int:
    """The chosen job; a bad value, file or setting raises (one line and exit 1 through `run`)."""
    args.ecu = parse_ecu_settings(args.vehicle, args.ecu)
    if args.replot is not None:
        return _replot(args.replot, args.out)
    if resolve(args.vehicle).simulator == "generic":
        return _vehicle_suite(args)
    if args.trace is not None:
        return _trace(args)
    if args.fleet is not None:
        return _fleet(args)
    if args.repetitions is not None:
        raise InputError("--repetitions: with --fleet only (the model-plant suite drives --fault-free-minutes)")
    cfg = _config(args)
    if args.linearity:
        return _survey(cfg, args.out)
    with _progress("quality", "run") as progress:
        result = run_suite(cfg, progress)
    print(markdown(result))
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        write_json(result, args.out / "quality.json")
        write_markdown(result, args.out / "quality.md")
        print(f"wrote {args.out / 'quality.json'} and {args.out / 'quality.md'}")
    return 0


@contextmanager
def _progress(desc: str, unit: str) -> Iterator[Callable[[str], None]]:
    """A progress bar on stderr; the callable counts one unit of work and shows its text."""
    with tqdm(desc=desc, unit=unit, file=sys.stderr) as bar:
        def progress(text: str) -> None:
            bar.set_postfix_str(text[:60])
            bar.update(1)

        yield progress


def _config(args: argparse.Namespace) -> SuiteConfig:
    """The suite's configuration from the command line (--quick's defaults, then what is given)."""
    base = quick_config(args.vehicle) if args.quick else SuiteConfig(table=args.vehicle)
    return SuiteConfig(
        table=args.vehicle,
        scenarios=tuple(args.scenarios) if args.scenarios else base.scenarios,
        seeds=tuple(args.seeds) if args.seeds else base.seeds,
        multipliers=tuple(args.multipliers) if args.multipliers else base.multipliers,
        shapes=tuple(args.shapes) if args.shapes else base.shapes,
        faults=tuple(args.faults) if args.faults else (),
        fault_free_minutes=base.fault_free_minutes if args.fault_free_minutes is None else args.fault_free_minutes,
        sizes_file=args.sizes,
        ecu=args.ecu,
    )


def _vehicle_suite(args: argparse.Namespace) -> int:
    """The suite of a vehicle on the generic simulator: its model plant, its faults, sizes and scenario."""
    from fdi_host.quality import vehicle_suite as vs

    for option, given in (("--fleet", args.fleet is not None), ("--repetitions", args.repetitions is not None),
                          ("--scenarios", bool(args.scenarios)),
                          ("--shapes", bool(args.shapes)), ("--linearity", args.linearity),
                          ("--trace", args.trace is not None)):
        if given:
            raise InputError(f"{option}: ROMO's suite only; vehicle {args.vehicle} runs on the generic simulator")
    base = vs.quick_config(args.vehicle) if args.quick else vs.VehicleSuiteConfig(args.vehicle)
    cfg = dataclasses.replace(
        base, seeds=tuple(args.seeds) if args.seeds else base.seeds, faults=tuple(args.faults or ()),
        multipliers=tuple(args.multipliers) if args.multipliers else base.multipliers,
        fault_free_minutes=base.fault_free_minutes if args.fault_free_minutes is None else args.fault_free_minutes,
        sizes_file=None if args.sizes == DEFAULT_SIZES else args.sizes, ecu=args.ecu)
    with _progress("quality", "run") as progress:
        result = vs.run_vehicle_suite(cfg, progress)
    print(vs.markdown(result))
    if args.out is not None:
        print("wrote " + " and ".join(str(p) for p in vs.write(result, args.out)))
    return 0


def _fleet(args: argparse.Namespace) -> int:
    from fdi_host.quality import fleet, fleet_plots, fleet_report

    try:
        base = fleet.quick_config(args.vehicle) if args.quick else fleet.FleetConfig(table=args.vehicle)
        cfg = dataclasses.replace(
            base, vehicles=args.fleet, scenarios=tuple(args.scenarios) if args.scenarios else base.scenarios,
            faults=tuple(args.faults) if args.faults else (), sizes_file=args.sizes, ecu=args.ecu,
            workers=args.workers, scheduler=args.scheduler, sweep=base.sweep and not args.no_sweep,
            model_plant_seeds=tuple(args.seeds) if args.seeds else base.model_plant_seeds,
            fault_free_repetitions=base.fault_free_repetitions if args.repetitions is None else args.repetitions)
        with _progress("fleet", "task") as progress:
            result = fleet.run_fleet_suite(cfg, progress)
    except (FdiError, OSError) as exc:
        return fail("fdi-quality", exc)
    print(fleet_report.markdown(result))
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        fleet_report.write_json(result, args.out / "fleet.json")
        (args.out / "fleet.md").write_text(fleet_report.markdown(result), encoding="utf-8")
        png = fleet_plots.plot(fleet_report.to_dict(result), args.out / "fleet.png")
        print(f"wrote {args.out / 'fleet.json'}, {args.out / 'fleet.md'} and {png}")
    return 1 if result.errors else 0


def _replot(report: Path, out: Path | None) -> int:
    from fdi_host.quality import fleet_plots

    try:
        data = fleet_plots.load(report)
        folder = report.parent if out is None else out
        folder.mkdir(parents=True, exist_ok=True)
        png = fleet_plots.plot(data, folder / "fleet.png")
    except (fleet_plots.FleetReportError, OSError) as exc:
        return fail("fdi-quality", exc)
    print(f"wrote {png}")
    return 0


def _survey(cfg: SuiteConfig, out: Path | None) -> int:
    from fdi_host.quality import linearity_survey

    with _progress("linearity", "case") as progress:
        survey = linearity_survey.run_survey(cfg, progress)
    print(linearity_survey.markdown(survey))
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        linearity_survey.write_json(survey, out / "linearity.json")
        linearity_survey.write_markdown(survey, out / "linearity.md")
        linearity_survey.plot(survey, out / "linearity.png")
        print(f"wrote {out / 'linearity.json'}, {out / 'linearity.md'} and {out / 'linearity.png'}")
    return 0


def _trace(args: argparse.Namespace) -> int:
    from fdi_host.quality import trace

    try:
        fault, scenario, seed = trace.parse_case(args.trace)
        mult = args.multipliers[0] if args.multipliers else 1.0
        shape = args.shapes[0] if args.shapes else "step"
        case = trace.trace_case(args.vehicle, fault, scenario, seed, mult,
                                SuiteConfig(table=args.vehicle, sizes_file=args.sizes, ecu=args.ecu), shape)
        print(trace.report(case))
        if args.out is not None:
            args.out.mkdir(parents=True, exist_ok=True)
            png = args.out / f"trace-{fault}-{scenario}-{seed}{'' if shape == 'step' else '-' + shape}.png"
            trace.plot(case, png)
            print(f"wrote {png}")
        if args.linearity:
            from fdi_host.quality import linearity

            lin = linearity.check_case(args.vehicle, fault, scenario, seed, mult,
                                       SuiteConfig(table=args.vehicle, sizes_file=args.sizes, ecu=args.ecu), shape)
            print(linearity.report(lin))
            if args.out is not None:
                png = args.out / f"linearity-{fault}-{scenario}-{seed}{'' if shape == 'step' else '-' + shape}.png"
                linearity.plot(lin, png)
                print(f"wrote {png}")
    except (FdiError, OSError) as exc:
        return fail("fdi-quality", exc)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
