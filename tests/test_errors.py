"""One error hierarchy per package: every exception class of `fdi_analysis` derives from `FdiError`, every one of
`fdi_host` from `FdiHostError` (itself an `FdiError`), each keeping the built-in base it had so that ``except
ValueError`` callers still catch it; and `fdi_analysis.cli.common.run` turns exactly those (and a missing file)
into one line and exit 1, anything else into its traceback and exit 70."""

from __future__ import annotations

import ast
import importlib
import json
import tomllib
from pathlib import Path

import pytest

from fdi_analysis.cli import common
from fdi_analysis.cli.common import EXIT_BUG, EXIT_ERROR, EXIT_INTERRUPTED, run
from fdi_analysis.errors import ComputationError, FdiError, InputError
from fdi_host.errors import FdiHostError

REPO = Path(__file__).resolve().parents[1]
ROOTS = {"fdi_analysis": REPO / "analysis", "fdi_host": REPO / "host_tools"}

# Each class and the built-in base it keeps beside its root (issue 47: the 27 classes without a common root, and
# the ones added since).
KEEPS: dict[str, type[BaseException] | None] = {
    "fdi_analysis.api.ApiError": ValueError,
    "fdi_analysis.errors.ComputationError": RuntimeError,
    "fdi_analysis.errors.FdiError": None,
    "fdi_analysis.errors.InputError": ValueError,
    "fdi_analysis.export.c_expr.CExprError": ValueError,
    "fdi_analysis.export.c_names.CNameError": ValueError,
    "fdi_analysis.export.can_codec.BusError": ValueError,
    "fdi_analysis.export.capacity.CapacityError": ValueError,
    "fdi_analysis.export.dbc_signals.DbcError": ValueError,
    "fdi_analysis.export.fault_sizes.FaultSizesError": ValueError,
    "fdi_analysis.export.generators.EmitError": ValueError,
    "fdi_analysis.export.signals.SignalsError": ValueError,
    "fdi_analysis.export.table.ExportError": ValueError,
    "fdi_analysis.export.thresholds.MissingSigmaError": ValueError,
    "fdi_analysis.expressions.ExpressionError": ValueError,
    "fdi_analysis.model.ModelError": ValueError,
    "fdi_analysis.residuals.estimation.EstimationError": ValueError,
    "fdi_analysis.residuals.reasons.NotRealizableError": ValueError,
    "fdi_analysis.residuals.selected.SelectionError": ValueError,
    "fdi_analysis.selection.exact.SearchTimeoutError": None,
    "fdi_analysis.selection.practical.ScreeningError": ValueError,
    "fdi_analysis.selection.sat.SatTimeoutError": None,
    "fdi_analysis.selection.sat.SatUnavailableError": RuntimeError,
    "fdi_analysis.structure.StructureError": ValueError,
    "fdi_host.can.dbc.E2EError": ValueError,
    "fdi_host.can.logs.LogError": ValueError,
    "fdi_host.can.logs.MalformedLogError": ValueError,
    "fdi_host.ecu.bindings.EcuError": RuntimeError,
    "fdi_host.errors.FdiHostError": None,
    "fdi_host.executors.ExecutorError": ValueError,
    "fdi_host.fleet.FleetError": ValueError,
    "fdi_host.live.bus.BusConfigError": ValueError,
    "fdi_host.monitor.cli.ClassesFileError": ValueError,
    "fdi_host.quality.fleet_plan.PlanError": ValueError,
    "fdi_host.quality.fleet_plots.FleetReportError": ValueError,
    "fdi_host.quality.suite.QualityError": ValueError,
    "fdi_host.sim.faults.FaultSpecError": ValueError,
    "fdi_host.sim.generic.GenericPlantError": ValueError,
    "fdi_host.sim.plant.PlantError": RuntimeError,
    "fdi_host.sim.road.RoadError": ValueError,
    "fdi_host.sim.scenario.ScenarioError": ValueError,
    "fdi_host.sim.truth_sim.TruthDivergedError": FloatingPointError,
    "fdi_host.sim.tyre.TyreParameterError": ValueError,
    "fdi_host.sim.vehicle_envelope.VehicleDrawError": ValueError,
    "fdi_host.sim.vehicle_sim.SimulationDivergedError": FloatingPointError,
    "fdi_host.tuning.fleet_calibration.CalibrationError": ValueError,
    "fdi_host.tuning.generic.GenericTuningError": ValueError,
    "fdi_host.tuning.on_log.LogError": ValueError,
    "fdi_host.vehicle.VehicleError": ValueError,
}


def _module_name(pkg: str, path: Path) -> str:
    parts = list(path.relative_to(ROOTS[pkg]).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def exception_classes() -> dict[str, type[BaseException]]:
    """Every class defined at the top level of a module of the two packages that is an exception (not a
    warning), by qualified name (found in the source, then imported)."""
    out: dict[str, type[BaseException]] = {}
    for pkg, root in ROOTS.items():
        for path in sorted((root / pkg).rglob("*.py")):
            tree = ast.parse(path.read_text(encoding="utf-8"))
            names = [n.name for n in tree.body if isinstance(n, ast.ClassDef) and n.bases]
            if not names or not any(("Error" in ast.unparse(b) or "Exception" in ast.unparse(b))
                                    for n in tree.body if isinstance(n, ast.ClassDef) for b in n.bases):
                continue
            module = _module_name(pkg, path)
            mod = importlib.import_module(module)
            for name in names:
                cls = getattr(mod, name)
                if isinstance(cls, type) and issubclass(cls, BaseException) and not issubclass(cls, Warning):
                    out[f"{module}.{name}"] = cls
    return out


def test_every_exception_class_has_its_package_root() -> None:
    rooted = exception_classes()
    assert sorted(rooted) == sorted(KEEPS), "a new exception class: give it its package root and list it in KEEPS"
    wrong = [n for n, c in rooted.items() if not issubclass(c, FdiHostError if n.startswith("fdi_host.") else FdiError)]
    assert not wrong, f"not under the package's root: {wrong}"
    lost = [n for n, base in KEEPS.items() if base is not None and not issubclass(rooted[n], base)]
    assert not lost, f"lost the built-in base its callers catch: {lost}"
    assert not any(issubclass(c, FdiHostError) for n, c in rooted.items() if n.startswith("fdi_analysis."))


def test_no_class_counts_by_name_any_more() -> None:
    """The three classes that counted by name until their modules could be edited (a log, the bus options, a
    fleet) derive from FdiHostError now; the list of names is gone with the matching by name."""
    assert not hasattr(common, "PENDING_FDI_ERRORS") and not hasattr(common, "is_input_error")


def test_roots() -> None:
    assert issubclass(FdiHostError, FdiError) and not issubclass(FdiError, (ValueError, RuntimeError))
    assert issubclass(InputError, ValueError) and issubclass(ComputationError, RuntimeError)
    from fdi_analysis.model import ModelError

    err = ModelError("bad symbol", file="m.toml", equation="e1", symbol="x")  # typed data stays on the class
    assert (str(err), err.file, err.equation, err.symbol) == ("m.toml: equation 'e1': bad symbol", "m.toml", "e1", "x")
    with pytest.raises(ValueError):  # an existing `except ValueError` still catches it
        raise err


def _raising(exc: BaseException) -> int:
    raise exc


@pytest.mark.parametrize("exc, code, line", [
    (InputError("m.toml: bad"), EXIT_ERROR, "prog: error: m.toml: bad"),
    (FdiHostError("log.blf: holds no data frames"), EXIT_ERROR, "prog: error: log.blf: holds no data frames"),
    (FileNotFoundError(2, "No such file or directory", "a/b.toml"), EXIT_ERROR,
     "prog: error: a/b.toml: No such file or directory"),
    (tomllib.TOMLDecodeError("Expected '='"), EXIT_ERROR, "prog: error: Expected '='"),
    (json.JSONDecodeError("Expecting value", "{", 1), EXIT_ERROR, "prog: error: Expecting value: line 1 column 2 "
     "(char 1)"),
    (KeyboardInterrupt(), EXIT_INTERRUPTED, "prog: interrupted"),
])
def test_run_reports_input_errors_as_one_line(exc: BaseException, code: int, line: str,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    assert run("prog", lambda: _raising(exc)) == code
    assert capsys.readouterr().err.splitlines() == [line]


@pytest.mark.parametrize("exc", [ValueError("bare"), KeyError("k"), ZeroDivisionError("z"), RuntimeError("r"),
                                 TypeError("t")])
def test_run_reports_anything_else_as_a_bug(exc: Exception, capsys: pytest.CaptureFixture[str]) -> None:
    assert run("prog", lambda: _raising(exc)) == EXIT_BUG
    err = capsys.readouterr().err
    assert err.startswith("Traceback (most recent call last)") and f"\n{type(exc).__name__}: " in err
    assert err.splitlines()[-1].startswith(f"prog: internal error ({type(exc).__name__})")


def test_run_names_extra_errors_and_lets_usage_errors_through(capsys: pytest.CaptureFixture[str]) -> None:
    assert run("prog", lambda: _raising(KeyError("k")), errors=(KeyError,)) == EXIT_ERROR
    assert capsys.readouterr().err == "prog: error: 'k'\n"
    with pytest.raises(SystemExit):  # argparse's exit 2 is not swallowed
        run("prog", lambda: _raising(SystemExit(2)))


@pytest.mark.parametrize("name", ["fdi_host.can.logs.LogError", "fdi_host.can.logs.MalformedLogError",
                                  "fdi_host.live.bus.BusConfigError", "fdi_host.fleet.FleetError"])
def test_log_bus_and_fleet_errors_are_fdi_errors(name: str, capsys: pytest.CaptureFixture[str]) -> None:
    """A log, the bus options and a fleet: FdiHostError (so FdiError) by their class, not by their name, and still
    the ValueError their callers catch; a command line reports them as one line, exit 1."""
    module, _, cls_name = name.rpartition(".")
    cls = getattr(importlib.import_module(module), cls_name)
    assert issubclass(cls, FdiHostError) and issubclass(cls, FdiError) and issubclass(cls, ValueError), name
    with pytest.raises(ValueError):
        raise cls("x.blf: bad")
    assert run("prog", lambda: _raising(cls("x.blf: bad"))) == EXIT_ERROR
    assert capsys.readouterr().err.splitlines() == ["prog: error: x.blf: bad"]
