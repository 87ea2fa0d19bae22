"""Residual variances and reaction sizes of the hand-made kinematic table (fw/vehicles/romo/src/fdi_kin_table.c) from
simulated drives through the C ECU core: the rules of `fdi-tune calibrate` and `fdi-tune fault-sizes`
for the generated table.

The kinematic generators are hand-written C (fw/vehicles/romo/src/fdi_romo_kin.c), so their residuals are taken
from the ECU itself (fdi_host.ecu.bindings, every evaluable step of every drive). Per test, the calibrated sigma is the
smallest sigma with no raw alarm (|r| > gate sigma or CUSUM k = 1.5, h = 150) in any drive, times the margin
1.25 (fdi_host.tuning.calibrate). Drives: every quality-suite scenario with the noise seeds of SEEDS,
which neither the quality suite's fault cases (the scenario's own seed) nor its fault-free drives
(1000 + 17 k) use. Each variance is at least the one measured on the C unit tests' synthetic manoeuvre
(SYNTHETIC_VARIANCE): the table must hold in both environments. Reaction sizes (which quiet test may
exonerate which fault, fw/include/fdi_iso.h): `reaction_sizes`. Output:
fw/vehicles/romo/generated/fdi_kin_calibration.h, included by fdi_kin_table.c.

    fdi-tune kin-calibration --out fw/vehicles/romo/generated/fdi_kin_calibration.h    # regenerate (~3 min)
    fdi-tune kin-calibration --check fw/vehicles/romo/generated/fdi_kin_calibration.h  # exit 1 when stale
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from fdi_analysis.export import kin_calibration as emit_kin
from fdi_analysis.export.fault_sizes import EXONERATION_MARGIN, FaultSizes
from fdi_analysis.export.kin_calibration import KinCalibrationFile, KinTest, labels_of
from fdi_host.can.dbc import CanDatabase
from fdi_host.can.traffic import build_frames
from fdi_host.ecu.bindings import table_info
from fdi_host.ecu.offline import replay
from fdi_host.sim.faults import FaultSpec
from fdi_host.sim.scenario import FAULT_SIZES_FILE, SCENARIOS, load_scenario
from fdi_host.sim.vehicle_sim import faulty_drive, simulate
from fdi_host.tuning.calibrate import MARGIN, Calibration, calibrate, first_alarm
from fdi_host.tuning.sweep import ON, grid, next_grid

SEEDS: tuple[int, ...] = (500, 501, 502)
# Variances measured on the synthetic manoeuvre of the C unit tests (tests/fw/fdi_test_vehicle.h: turn at 10 m/s
# and 0.5 rad/s plus sinusoidal speed, side-slip and yaw manoeuvres, white sensor noise), sigma rounded up by
# ~20 %: the table must hold in both environments, so each variance is the larger of the two.
SYNTHETIC_VARIANCE: tuple[float, ...] = (1.3e-4, 1.44e-4, 3.2e-4, 3.8e-4)
SIZE_SEEDS: tuple[int, ...] = (777, 778)  # noise seeds of the reaction-size sweep (as `fdi-tune fault-sizes`)
SIZE_ONSET = 6.0  # s, fault step in the cornering drive (steady state from 5 s)
GATE = 5.0  # the kinematic table's gate [sigma]
COMMAND = "fdi-tune kin-calibration --out fw/vehicles/romo/generated/fdi_kin_calibration.h"


def kin_residuals(progress: Callable[[str], None] | None = None) -> list[list[np.ndarray]]:
    """Per test of the kinematic table, the residual of every drive on its evaluable steps."""
    n = table_info("kin").n_tests
    per_test: list[list[np.ndarray]] = [[] for _ in range(n)]
    db = CanDatabase()
    for name in SCENARIOS:
        scen = load_scenario(name)
        for seed in SEEDS:
            res = replay("kin", build_frames(simulate(scen, [], seed=seed), db))
            for i in range(n):
                r = [x.residuals[i] for x in res if x.test_status[i] != "not_evaluable"]
                if r:
                    per_test[i].append(np.asarray(r, dtype=np.float64))
            if progress is not None:
                progress(f"{name} seed {seed}: {len(res)} steps")
    return per_test


def calibrations(progress: Callable[[str], None] | None = None) -> list[Calibration]:
    drives = kin_residuals(progress)
    empty = [i for i, d in enumerate(drives) if not d]
    if empty:
        raise RuntimeError(f"kinematic test(s) {empty} never evaluable in the calibration drives")
    return [calibrate(d, GATE, MARGIN) for d in drives]


def variances(cals: list[Calibration]) -> list[float]:
    """The table's variance per test: the simulator calibration, at least the synthetic-manoeuvre value."""
    return [max(float(f"{c.variance:.3g}"), synth) for c, synth in zip(cals, SYNTHETIC_VARIANCE, strict=True)]


def reaction_sizes(variance: list[float], progress: Callable[[str], None] | None = None) -> list[list[float]]:
    """Per fault of the kinematic table and per test of its signature, the size at which the test reacts: a
    step at SIZE_ONSET of the cornering drive, raw alarm (gate or CUSUM from the onset, at the table's
    sigma) within ON seconds with every seed of SIZE_SEEDS, sizes on the grid of `fdi-tune fault-sizes`
    from [requirement] / 10 up to [limits] of fault_sizes.toml; stated = the grid value above the first alarm
    (as there). 0 where a test of the signature does not react up to the limit."""
    info = table_info("kin")
    sizes = FaultSizes.load(FAULT_SIZES_FILE)
    sigma = [float(np.sqrt(v)) for v in variance]
    db = CanDatabase()
    scen = load_scenario("cornering")
    bases = [simulate(scen, [], seed=seed) for seed in SIZE_SEEDS]
    out: list[list[float]] = []
    for j in range(info.n_faults):
        fault = info.faults[j]
        tests = [i for i in range(info.n_tests) if info.test_fault_masks[i] >> j & 1]
        row = [0.0] * info.n_tests
        pending = set(tests)
        for m in grid(sizes.requirement[fault] / 10.0, sizes.limits[fault]):
            hit = set(pending)
            for base in bases:
                res = replay("kin", build_frames(faulty_drive(base, FaultSpec(fault, SIZE_ONSET, m)), db),
                             t_start=SIZE_ONSET - 5.0)
                window = [r for r in res if SIZE_ONSET <= r.t_us * 1e-6 < SIZE_ONSET + ON]
                for i in list(hit):
                    r = np.asarray([x.residuals[i] for x in window if x.test_status[i] != "not_evaluable"])
                    if r.size == 0 or first_alarm(r, sigma[i], GATE) < 0:
                        hit.discard(i)
            for i in hit:
                row[i] = next_grid(m)
            pending -= hit
            if progress is not None:
                progress(f"{fault} at {m:g}: {len(tests) - len(pending)}/{len(tests)} tests react")
            if not pending:
                break
        out.append(row)
    return out


def render(cals: list[Calibration], sizes: list[list[float]]) -> str:
    """The header's text (fdi_analysis.export.kin_calibration renders it)."""
    info = table_info("kin")
    tests = tuple(KinTest(label, c.rms, c.peak, c.sigma, c.variance, synth, var) for c, label, synth, var in zip(
        cals, labels_of(info.test_names), SYNTHETIC_VARIANCE, variances(cals), strict=True))
    return emit_kin.render(KinCalibrationFile(
        command=COMMAND, gate=GATE, margin=MARGIN, scenarios=tuple(SCENARIOS), seeds=SEEDS, tests=tests,
        faults=info.faults, sizes=tuple(tuple(row) for row in sizes), window_s=ON, size_seeds=SIZE_SEEDS,
        exoneration_margin=EXONERATION_MARGIN))
