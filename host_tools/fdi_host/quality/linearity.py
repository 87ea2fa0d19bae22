"""How well the on-line rule's linearisation holds in one case: each test's response to the fault against the
response its sensitivity predicts.

The on-line exoneration (fdi_diag.h) takes a test's sensitivity s = d r / d f, which its generator computes at the
measured signals, as if the residual's response to a fault of size F were s F: an alarmed test implies
F >= (|r| - allowance) / |s|, and a quiet test clears a fault where |s| F reaches sensitivity_margin gates. Where the
fault reaches a residual through a saturating law (a tyre near its peak force), the slope at the measured signals
is not the mean slope over the fault, and the settled response is rho s F with rho != 1: an alarmed test with
rho > 1 overstates the size it implies by rho, a quiet test with rho < 1 would show 1 / rho less than the rule
expects. The rule holds while rho stays within the table's sensitivity margin.

`fdi-quality --trace CASE --linearity` measures rho on the case itself: the faulty drive and its fault-free drive
(same seed, same noise) replayed with every sensitivity reported; the response is the difference of the two
residuals (it includes the fault's effect on the vehicle, e.g. a steering offset's), the prediction s F with the
sensitivity of the faulty drive, as the ECU computes it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from fdi_host.can.dbc import CanDatabase
from fdi_host.can.traffic import build_frames
from fdi_host.ecu.bindings import EcuResult, TableInfo, table_info
from fdi_host.ecu.offline import replay
from fdi_host.quality.suite import (
    QualityError,
    SuiteConfig,
    case_onset,
    case_spec,
    ecu_settings,
    load_fault_sizes,
    replay_start,
)
from fdi_host.sim.faults import FAULT_IDS, FaultSpec
from fdi_host.sim.scenario import load_scenario
from fdi_host.sim.vehicle_sim import faulty_drive, simulate

AFTER_ONSET_S = 4.0  # how long after the onset the check looks (as the trace)
SETTLE_S = 1.0  # the summary leaves out the first second after the onset (filters and observers settling)
STANDS_OUT = 3.0  # the summary counts steps whose predicted response exceeds this many fault-free rms
FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class TestResponse:
    """One test's response to the fault over the case (times after the onset)."""

    name: str
    t: FloatArray  # s after the onset
    response: FloatArray  # residual of the faulty drive minus that of the fault-free drive
    predicted: FloatArray  # s F: the sensitivity of the faulty drive times the fault's value
    floor: float  # rms of the fault-free residual over the window: where s F stands out of it
    gate: float = 0.0  # the test's gate [sigma]
    sigma: float = 0.0  # the test's fault-free standard deviation (the table's)
    margin: float = 1.0  # the table's sensitivity margin

    @property
    def gate_sigma(self) -> float:
        """gate * sigma: the residual alarms beyond it."""
        return self.gate * self.sigma

    @property
    def level(self) -> float:
        """gate * sigma / sensitivity margin: from here on the rule may use s F (alarmed or quiet)."""
        return self.gate_sigma / self.margin

    def counted(self) -> NDArray[np.bool_]:
        """The steps of the summary: settled (SETTLE_S after the onset), s F standing out of the floor and reaching
        the level where the rule may use it (below it a quiet test clears the fault only at an implied size more
        than sensitivity_margin times the fault's own)."""
        pred = np.abs(self.predicted)
        return (self.t >= SETTLE_S) & (pred > STANDS_OUT * self.floor) & (pred >= self.level)

    def ratios(self) -> FloatArray:
        """rho = response / (s F) at the counted steps."""
        keep = self.counted()
        return self.response[keep] / self.predicted[keep]


@dataclass(frozen=True)
class Linearity:
    table: TableInfo
    spec: FaultSpec
    scenario: str
    seed: int
    tests: tuple[TestResponse, ...]  # the tests with a sensitivity to the fault, in table order


def _aligned(faulty: Sequence[EcuResult], free: Sequence[EcuResult]) -> list[tuple[EcuResult, EcuResult]]:
    by_time = {r.t_us: r for r in free}
    return [(r, by_time[r.t_us]) for r in faulty if r.t_us in by_time]


def check_case(table: str, fault: str, scenario: str, seed: int, multiplier: float = 1.0,
               cfg: SuiteConfig | None = None, shape: str = "step") -> Linearity:
    """The case of the suite (onset, required size x multiplier, shape) and its fault-free drive, replayed with every
    sensitivity reported; per test with a sensitivity to `fault`, its response against s F."""
    cfg = cfg if cfg is not None else SuiteConfig(table=table)
    info = table_info(table)
    size = load_fault_sizes(cfg.sizes_file).get(fault)
    if size is None:
        raise QualityError(f"no required size for {fault} in {cfg.sizes_file} [requirement]")
    j = FAULT_IDS.index(fault)
    base = simulate(load_scenario(scenario), [], seed=seed)
    onset = case_onset(cfg, base)
    spec, _ = case_spec(cfg, fault, onset, size, shape, multiplier)
    db = CanDatabase()
    settings = {**ecu_settings(cfg), "sensitivities": True}
    start = replay_start(cfg, onset)
    pairs = [(a, b) for a, b in _aligned(replay(table, build_frames(faulty_drive(base, spec), db), t_start=start,
                                                **settings),
                                         replay(table, build_frames(base, db), t_start=start, **settings))
             if onset <= a.t_us * 1e-6 <= onset + AFTER_ONSET_S]
    if not pairs:
        raise QualityError(f"{fault}:{scenario}:{seed}: no diagnosis step after the onset")
    t = np.array([a.t_us * 1e-6 for a, _ in pairs])
    value = spec.profile(t)
    tests = []
    for i in range(info.n_tests):
        faults = info.sens_faults(i)
        if j not in faults:
            continue
        k = faults.index(j)
        r_faulty = np.array([a.residuals[i] for a, _ in pairs])
        r_free = np.array([b.residuals[i] for _, b in pairs])
        s = np.array([a.sensitivities[i][k] for a, _ in pairs])
        tests.append(TestResponse(info.test_names[i].split(":")[0], t - onset, r_faulty - r_free, s * value,
                                  float(np.sqrt(np.mean(r_free ** 2))), info.gates[i], info.sigmas[i],
                                  info.sensitivity_margin))
    return Linearity(info, spec, scenario, seed, tuple(tests))


def _fmt(x: float) -> str:
    return f"{x:,.4g}" if abs(x) < 1e4 else f"{x:,.0f}"


def report(lin: Linearity, every_s: float = 0.5) -> str:
    """Per test: rho (median, range) over the counted steps, then the response and s F every `every_s`."""
    head = (f"linearisation of the on-line rule, {lin.spec.fault} {lin.spec.magnitude:g}, {lin.scenario}, seed "
            f"{lin.seed}: the response of each test with a sensitivity to {lin.spec.fault} (faulty minus fault-free "
            f"residual, same noise) against s F (its sensitivity on the faulty drive times the fault); rho = "
            f"response / (s F) from {SETTLE_S:g} s after the onset where s F exceeds {STANDS_OUT:g} x the "
            f"fault-free rms and reaches gate x sigma / sensitivity margin (where the rule may use it)")
    lines = [head]
    if not lin.tests:
        return "\n".join([*lines, f"  no test of the table has a sensitivity to {lin.spec.fault}"])
    for tr in lin.tests:
        rho = tr.ratios()
        summary = (f"rho median {np.median(rho):.2f}, range {rho.min():.2f} to {rho.max():.2f} over {rho.size} steps"
                   if rho.size else f"s F never reaches {_fmt(tr.level)} (gate x sigma / margin) or stands out of "
                                    f"the fault-free residual: no rho")
        lines.append(f"  {tr.name}: {summary}")
        marks = np.arange(0.0, float(tr.t[-1]) + 1e-9, every_s)
        idx = sorted({int(np.argmin(np.abs(tr.t - m))) for m in marks})
        lines.append("    response / s F: " + "; ".join(
            f"{tr.t[n]:+.1f} s {_fmt(float(tr.response[n]))} / {_fmt(float(tr.predicted[n]))}" for n in idx))
    return "\n".join(lines)


def plot(lin: Linearity, path: Path) -> None:
    """Per test with a sensitivity to the fault: its response and s F over time (one panel each)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = max(len(lin.tests), 1)
    cols = 2 if n > 1 else 1
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(10, 2.2 * rows + 0.8), sharex=True, squeeze=False)
    for ax, tr in zip(axes.flat, lin.tests, strict=False):
        ax.plot(tr.t, tr.response, lw=1.2, label="response (faulty - fault-free)")
        ax.plot(tr.t, tr.predicted, "--", lw=1.2, label="s F (sensitivity x fault)")
        band = max(STANDS_OUT * tr.floor, tr.level)
        ax.axhspan(-band, band, color="0.9", lw=0)
        rho = tr.ratios()
        ax.set_title(f"{tr.name}: rho {np.median(rho):.2f} ({rho.min():.2f} to {rho.max():.2f})" if rho.size
                     else f"{tr.name}: s F below the level the rule uses", fontsize=9)
        ax.tick_params(labelsize=8)
    for ax in list(axes.flat)[len(lin.tests):]:
        ax.set_visible(False)
    axes.flat[0].legend(fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("time after the fault onset [s]")
    fig.suptitle(f"{lin.spec.fault} {lin.spec.magnitude:g}, {lin.scenario}, seed {lin.seed} (table {lin.table.name}): "
                 f"response against the linearised s F (grey: below {STANDS_OUT:g} x fault-free rms or gate x sigma / "
                 f"margin)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
