"""The second model end to end: the three-tank benchmark (analysis/models/three_tank.toml, written from its
physics) through the whole chain, on the same generic C library as ROMO.

analysis (structure, MSO sets, the realizable selection) -> thresholds calibrated on drives of the generic
simulator and the fault-size sweep (fdi-tune calibrate|fault-sizes --vehicle three_tank) -> generated C of its own
vehicle target (fw/vehicles/three_tank/generated, fdi-analyze export-c) -> the generic diagnoser running it (the
ctypes bindings: Diagnoser("three_tank")) -> simulated fault runs (host_tools/scenarios/three_tank.toml
[[fault_run]]): detected within 2 s, no alarm before, the candidates as stated; the C residuals and sensitivities
equal the Python twin's.
The committed generated files (C and the thresholds/fault-size tables) come out byte for byte from their sources
in another process on another floating-point path. (tests/fw/test_three_tank.c: the same runs in pure C.)"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from fdi_analysis.export.thresholds import Thresholds
from fdi_analysis.isolability import isolability
from fdi_analysis.model import Model
from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.evaluate import FilterDesign, residual, sensitivity_series
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.selected import realizable
from fdi_host.ecu.bindings import Diagnoser, table_info
from fdi_host.sim.generic import GenericPlant, Scenario
from fdi_host.tuning import generic

MODEL = Path("analysis/models/three_tank.toml")
THRESHOLDS = Path("analysis/models/three_tank_thresholds.toml")
SCENARIO = Path("host_tools/scenarios/three_tank.toml")
SIZES = Path("host_tools/scenarios/three_tank_fault_sizes.toml")
OUT = Path("fw/vehicles/three_tank/generated")
NAME = "fdi_three_tank_table"


@pytest.fixture(scope="module")
def model(repo: Path) -> Model:
    return load_model(repo / MODEL)


@pytest.fixture(scope="module")
def scenario(repo: Path) -> Scenario:
    return Scenario.load(repo / SCENARIO)


@pytest.fixture(scope="module")
def gens(repo: Path, model: Model, scenario: Scenario) -> list[Generator]:
    th = Thresholds.load(repo / THRESHOLDS)
    from fdi_analysis.residuals.selected import selected_generators

    return selected_generators(model, th.observer_reference(), selection=th.selection, max_tyre_accel=th.max_tyre_accel,
                               sensitivities=True)[1]


def test_model_analyses(model: Model) -> None:
    """10 faults, all detectable; classes {fP, fL1} and {fL3, fC3} (a leak and the flow it shares), all else
    isolable; 14 of the 18 MSO sets have a realizable residual generator."""
    iso = isolability(model.structure())
    assert model.counts()["faults"] == 10 and iso.detectable.all()
    classes = sorted(sorted(iso.faults[i] for i in c) for c in iso.classes if len(c) > 1)
    assert classes == [["fC3", "fL3"], ["fL1", "fP"]]
    assert len(realizable(model)) == 14


def test_generated_files_reproduce(repo: Path, tmp_path: Path,
                                   other_fp_path: Callable[[list[str]], subprocess.CompletedProcess[str]]) -> None:
    """The committed generated C and the generated tables of the thresholds and fault-size files are what the
    chain computes now, in another process on another floating-point path."""
    res = other_fp_path([sys.executable, "-m", "fdi_analysis.cli", "export-c", str(MODEL), "--thresholds",
                         str(THRESHOLDS), "--fault-sizes", str(SIZES), "--out", str(tmp_path), "--name", NAME,
                         "--no-progress"])
    assert res.returncode == 0, res.stderr
    made = {p.name: p.read_text(encoding="utf-8").replace(f"--out {tmp_path.as_posix()}", f"--out {OUT.as_posix()}")
            for p in tmp_path.iterdir()}
    committed = {p.name: p.read_text(encoding="utf-8") for p in (repo / OUT).iterdir() if p.suffix in (".c", ".h")}
    assert set(made) == set(committed)
    for name, text in made.items():
        assert committed[name] == text, f"{OUT / name} is stale: run scripts/generate.sh"
    for cmd in ("calibrate", "fault-sizes"):
        res = other_fp_path([sys.executable, "-m", "fdi_host.tuning.cli", cmd, "--vehicle", "three_tank", "--check"])
        assert res.returncode == 0, res.stderr


def test_table_is_the_selection(gens: list[Generator]) -> None:
    info = table_info("three_tank")
    assert info.signal_names == ("u", "y1", "y2", "y3")
    assert info.n_tests == len(gens) == 5 and all(info.has_generator)
    assert info.mso_ids == tuple(int(g.name[3:]) for g in gens)
    faults = [f.split()[0] for f in info.fault_names]
    for g, mask in zip(gens, info.sens_masks, strict=True):
        assert mask == sum(1 << faults.index(f) for f, _ in g.sensitivities)


def test_c_equals_the_python_twin(gens: list[Generator], model: Model, scenario: Scenario) -> None:
    """On a fault run the residuals of the generic C diagnoser (after each test's warm-up) and its sensitivities
    equal the Python evaluation of the same generators (float against double: within 1e-3 of the scale)."""
    plant = GenericPlant(model)
    sig = generic.fault_run_signals(plant, scenario, scenario.fault_runs[0])
    run = Diagnoser("three_tank", sensitivities=True).run(sig, results=False)
    warm = 400  # > the diagnoser's warm-up (320 steps): the C residual is 0 before
    faults = [f.name for f in model.faults]
    for k, g in enumerate(gens):
        py = residual(g, sig, FilterDesign())
        scale = float(np.max(np.abs(py[warm:])))
        err = float(np.max(np.abs(run.residuals[warm:, k] - py[warm:])))
        assert scale > 0.0 and err < 1e-3 * scale, f"{g.name}: C vs Python {err:.3g}, scale {scale:.3g}"
        sens = sensitivity_series(g, sig)
        for j, f in enumerate(sorted(sens, key=faults.index)):
            s_scale = float(np.max(np.abs(sens[f][warm:])))
            s_err = float(np.max(np.abs(run.sensitivities[k][warm:, j] - sens[f][warm:])))
            assert s_err <= 1e-3 * s_scale, f"{g.name} d r / d {f}: C vs Python {s_err:.3g}, scale {s_scale:.3g}"


def test_fault_free_drive_gives_no_detection(model: Model, scenario: Scenario) -> None:
    sig = generic.drive(GenericPlant(model), scenario, seed=99)
    results = Diagnoser("three_tank").run(sig).results
    assert not any(r.detected for r in results)
    assert results[-1].evaluable_mask == (1 << table_info("three_tank").n_tests) - 1


@pytest.mark.parametrize("index", [0, 1, 2])
def test_fault_run_is_detected_and_isolated(index: int, model: Model, scenario: Scenario) -> None:
    fr = scenario.fault_runs[index]
    info = table_info("three_tank")
    sig = generic.fault_run_signals(GenericPlant(model), scenario, fr)
    results = Diagnoser("three_tank").run(sig).results
    onset = round(fr.onset / scenario.dt)
    first = next(k for k, r in enumerate(results) if r.detected)
    assert onset <= first <= onset + round(2.0 / scenario.dt), f"{fr.fault}: detected at step {first}"
    final = info.fault_labels(results[-1].candidates)
    assert fr.fault in final and set(final) <= set(fr.candidates), final
    if len(fr.candidates) == 1:
        assert results[-1].isolated
    j = [n.split()[0] for n in info.fault_names].index(fr.fault)
    excluded = [k for k, r in enumerate(results) if r.candidates and not r.candidates >> j & 1]
    assert not excluded, f"{fr.fault} excluded from the candidates at step {excluded[0]}"
    classes = {info.iso_class[j] for j in range(info.n_faults) if results[-1].candidates >> j & 1}
    assert results[-1].isolated == (len(classes) == 1)
