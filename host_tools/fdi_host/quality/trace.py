"""One case of the quality suite, step by step: why a fault was (not) isolated.

`fdi-quality --trace f6:straight:2001` runs the case exactly as the suite does (the same drive, fault onset,
required size and replay through the C ECU core) and reports, in the order they happened, the changes of the
alarm pattern and of the candidate set, naming for every alarmed test whether its signature contains the fault
(a test structurally blind to the fault that alarms excludes it, whatever the other tests say), then, every 0.1 s
while candidates are undecided, the exoneration's evidence (fdi_diag_explain): the size each one would need to
have by the settled alarms, how long the on-line rule has cleared it, and which quiet tests clear it. The plot shows
each test's normalised ratio |r| / (gate sigma) over time, blind tests dashed, with the candidate count below.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from fdi_host.can.dbc import CanDatabase
from fdi_host.can.traffic import build_frames
from fdi_host.ecu.bindings import EcuResult, Evidence, TableInfo, table_info
from fdi_host.ecu.offline import replay_explained
from fdi_host.quality.suite import (
    QualityError,
    SuiteConfig,
    case_onset,
    case_spec,
    check_shape,
    ecu_settings,
    load_fault_sizes,
    replay_start,
)
from fdi_host.sim.faults import FAULT_IDS, FaultSpec
from fdi_host.sim.scenario import SCENARIOS, load_scenario
from fdi_host.sim.vehicle_sim import faulty_drive, simulate

AFTER_ONSET_S = 4.0  # how long after the onset the trace looks
FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class CaseTrace:
    table: TableInfo
    spec: FaultSpec
    scenario: str
    seed: int
    results: tuple[EcuResult, ...]
    # the vehicle after the onset (true states of the simulator), faulty and fault-free: largest |vy| [m/s],
    # largest |psidot| [rad/s], smallest vx [m/s]; a fault that makes the vehicle spin leaves every model's domain
    motion: tuple[tuple[float, float, float], tuple[float, float, float]] = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    evidence: tuple[Evidence, ...] = ()  # the exoneration's evidence after each step of `results`

    @property
    def fault_index(self) -> int:
        return FAULT_IDS.index(self.spec.fault)

    def blind(self, test: int) -> bool:
        """Whether test `test`'s signature lacks the fault (it cannot react to it structurally)."""
        return not self.table.test_fault_masks[test] >> self.fault_index & 1


def parse_case(text: str) -> tuple[str, str, int]:
    """'f6:straight:2001' -> ('f6', 'straight', 2001)."""
    parts = text.split(":")
    if len(parts) != 3 or parts[0] not in FAULT_IDS or parts[1] not in SCENARIOS or not parts[2].isdigit():
        raise QualityError(f"bad case {text!r}; expected FAULT:SCENARIO:SEED, e.g. f6:straight:2001 "
                           f"(scenarios {', '.join(SCENARIOS)})")
    return parts[0], parts[1], int(parts[2])


def trace_case(table: str, fault: str, scenario: str, seed: int, multiplier: float = 1.0,
               cfg: SuiteConfig | None = None, shape: str = "step") -> CaseTrace:
    """Run one case as `run_suite` does (onset, required size x multiplier, a step or a ramp over cfg.ramp_s,
    pre-onset replay)."""
    cfg = cfg if cfg is not None else SuiteConfig(table=table)
    info = table_info(table)
    size = load_fault_sizes(cfg.sizes_file).get(fault)
    if size is None:
        raise QualityError(f"no required size for {fault} in {cfg.sizes_file} [requirement]")
    check_shape(shape)  # before the simulation
    base = simulate(load_scenario(scenario), [], seed=seed)
    onset = case_onset(cfg, base)
    spec, _ = case_spec(cfg, fault, onset, size, shape, multiplier)
    drive = faulty_drive(base, spec)
    frames = build_frames(drive, CanDatabase())
    steps = [s for s in replay_explained(table, frames, t_start=replay_start(cfg, onset), **ecu_settings(cfg))
             if s[0].t_us * 1e-6 <= onset + AFTER_ONSET_S]
    window = (drive.t >= onset) & (drive.t <= onset + AFTER_ONSET_S)

    def motion(true: Mapping[str, FloatArray]) -> tuple[float, float, float]:
        return (float(np.max(np.abs(true["vy"][window]))), float(np.max(np.abs(true["psidot"][window]))),
                float(np.min(true["vx"][window])))

    return CaseTrace(info, spec, scenario, seed, tuple(r for r, _ in steps), (motion(drive.true), motion(base.true)),
                     tuple(e for _, e in steps))


def gates(ratio: float) -> float:
    """|r| / (gate sigma) from the evaluator's test ratio r^2 / (gate^2 sigma^2) (fdi_eval.h)."""
    return math.sqrt(ratio)


def _short(name: str) -> str:
    return name.split(":")[0]


def events(trace: CaseTrace) -> list[str]:
    """The changes after the onset of the alarm pattern and of the candidates, one line each."""
    lines: list[str] = []
    prev: tuple[int, int, bool, bool] | None = None
    names = [_short(n) for n in trace.table.test_names]
    for r in trace.results:
        t = r.t_us * 1e-6
        if t < trace.spec.onset:
            continue
        key = (r.alarm_mask, r.candidates, r.isolated, r.in_envelope)
        if key == prev:
            continue
        prev = key
        alarmed = [i for i in range(trace.table.n_tests) if r.alarm_mask >> i & 1]
        tests = ", ".join(f"{names[i]}{' (blind)' if trace.blind(i) else ''} {gates(r.ratios[i]):.1f}"
                          for i in alarmed)
        cands = "{" + ", ".join(r.candidate_labels(trace.table)) + "}"
        state = "isolated" if r.isolated else ("detected" if r.detected else "quiet")
        held = "" if r.in_envelope else " (outside the envelope: held)"
        lines.append(f"{t - trace.spec.onset:+6.2f} s  {state:8s} candidates {cands}{held}  alarms: {tests or '-'}")
    return lines


def _size(f: float) -> str:
    return "no bound yet" if f <= 0.0 else f"{f:.3g}"


def evidence(trace: CaseTrace, every_s: float = 0.1) -> list[str]:
    """Every `every_s` while candidates are undecided: for each, the size F the alarms imply (Table I
    units) and for how many steps in a row the on-line rule has cleared it, and the quiet tests that clear it alone
    (fdi_diag.h: a quiet test clears f where |d r / d f| F reaches the margin times its gate)."""
    lines: list[str] = []
    names = [_short(n) for n in trace.table.test_names]
    faults = trace.table.faults
    next_t = 0.0
    for r, e in zip(trace.results, trace.evidence, strict=True):
        t = r.t_us * 1e-6 - trace.spec.onset
        open_ = e.undecided & r.candidates
        if t < next_t - 1e-6 or not open_:
            continue
        next_t = t + every_s
        parts, waiting = [], []
        for j in range(trace.table.n_faults):
            if not open_ >> j & 1:
                continue
            by = [names[i] for i, m in enumerate(e.clears) if m >> j & 1]
            if e.implied[j] <= 0.0 and not e.cleared_run[j] and not by:
                waiting.append(faults[j])
                continue
            n = e.cleared_run[j]
            run = f", cleared {n} step{'' if n == 1 else 's'}" if n else ""
            parts.append(f"{faults[j]} {_size(e.implied[j])}{run}{' by ' + ', '.join(by) if by else ''}")
        if waiting:
            parts.append("no bound yet: " + ", ".join(waiting))
        lines.append(f"{t:+6.2f} s  " + "; ".join(parts))
    return lines


def report(trace: CaseTrace) -> str:
    j = trace.fault_index
    ramp = f" (a ramp over {trace.spec.ramp:g} s)" if trace.spec.shape == "ramp" else ""
    head = (f"{trace.spec.fault} at {trace.spec.magnitude:g}{ramp} ({trace.table.fault_names[j]}), {trace.scenario}, "
            f"seed {trace.seed}, onset {trace.spec.onset:g} s, table {trace.table.name}; expected class "
            f"{{{', '.join(trace.table.fault_labels(trace.table.iso_class[j]))}}}")
    blind = [_short(n) for i, n in enumerate(trace.table.test_names) if trace.blind(i)]
    (vy, r, vx), (vy0, r0, vx0) = trace.motion
    motion = (f"vehicle within {AFTER_ONSET_S:g} s of the onset (fault-free drive in brackets): largest |vy| {vy:.2f} "
              f"({vy0:.2f}) m/s, largest |yaw rate| {r:.2f} ({r0:.2f}) rad/s, smallest vx {vx:.2f} ({vx0:.2f}) m/s")
    return "\n".join([head, motion, f"tests blind to {trace.spec.fault}: {', '.join(blind) or '-'}",
                      "time after onset, state, candidates, alarmed tests with their ratio |r| / (gate sigma):",
                      *events(trace),
                      "undecided candidates every 0.1 s: the size F the alarms imply, how long the on-line "
                      "rule has cleared it, the quiet tests that clear it alone:",
                      *(evidence(trace) or ["-"])])


def plot(trace: CaseTrace, path: Path) -> None:
    """Ratios of every test (blind ones dashed) and the number of candidates over time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    res: Sequence[EcuResult] = trace.results
    t = [r.t_us * 1e-6 - trace.spec.onset for r in res]
    fig, (ax, axc) = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True, height_ratios=(3, 1))
    for i, name in enumerate(trace.table.test_names):
        y = [max(gates(r.ratios[i]), 1e-3) for r in res]
        ax.plot(t, y, "--" if trace.blind(i) else "-", lw=1.2, label=_short(name) + (" (blind)" if trace.blind(i)
                                                                                     else ""))
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_yscale("log")
    ax.set_ylim(1e-2, None)
    ax.set_ylabel("|r| / (gate sigma)")
    ax.legend(ncol=4, fontsize=7, loc="upper left")
    ax.set_title(f"{trace.spec.fault} {trace.spec.magnitude:g}{' ramp' if trace.spec.shape == 'ramp' else ''}, "
                 f"{trace.scenario}, seed {trace.seed} "
                 f"(table {trace.table.name}): ratios, tests blind to the fault dashed")
    axc.step(t, [bin(r.candidates).count("1") for r in res], where="post", label="candidates")
    axc.step(t, [int(r.isolated) for r in res], where="post", label="isolated")
    axc.set_xlabel("time after the fault onset [s]")
    axc.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
