"""Stated fault sizes per (fault, test): a sweep of step faults on simulated drives.

For each fault, step faults of increasing size (a grid 1, 1.5, 2, 3, 5, 7 x 10^k from `lo` up to the fault's
physical limit) are injected one after the other into one fault-free scenario (each ON seconds, then OFF seconds
to settle), and every test of the fault's signature is evaluated as the diagnoser does it: only inside its
operating domain, restarted with a warm-up on entry (`evaluate.evaluable_segments`), raw alarm = |r| > gate
sigma or the two-sided CUSUM (fdi_eval.h) started at the fault onset (CUSUM history before the onset ignored,
which can only make detection later). A size counts as detected when it alarms in the drives of every one of
several noise seeds. The smallest detected grid size is the detection limit of the pair (when the smallest
swept size is already detected, smaller sizes are swept until one is not); the stated size is the next grid
value above it (a margin of 1.3-1.7 against other noise realisations), confirmed in a drive of its own: each
test must alarm at its stated size, in a window that follows only smaller windows of the confirmation, with
the sweep's seeds and three times as many more (CONFIRM_SEED_OFFSETS), else the next grid values are tried (a
chunk at once, in ascending windows): a detection limit on the edge of the CUSUM drift, where the noise realisation
decides, is not stated. A pair
without alarm up to the limit, or whose stated size exceeds the limit, is "not detectable by this test in
practice".
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from fdi_analysis.export.fault_sizes import REACTION_WINDOW_S, FaultSizes
from fdi_analysis.names import in_order
from fdi_analysis.residuals.evaluate import FilterDesign, evaluable_segments
from fdi_analysis.residuals.generator import Generator
from fdi_host.tuning.calibrate import first_alarm
from fdi_host.tuning.seeds import CONFIRM_SEED_OFFSETS

FloatArray = NDArray[np.float64]

MANTISSAS = (1.0, 1.5, 2.0, 3.0, 5.0, 7.0)
START = 6.0  # s, first fault onset (cornering is in steady state from 5 s)
ON, OFF = REACTION_WINDOW_S, 2.0  # s per window
CHUNK = 6  # windows per simulated drive
MAX_DOWN = 3  # chunks swept below the smallest size at most (3 decades)


@dataclass(frozen=True)
class Windowed:
    """One drive with faults (fault, onset, size, end)."""

    faults: tuple[tuple[str, float, float, float], ...]
    duration: float


def grid(lo: float, hi: float) -> list[float]:
    """Grid values v with lo <= v <= hi."""
    out: list[float] = []
    k = math.floor(math.log10(lo)) - 1
    while True:
        for m in MANTISSAS:
            v = float(f"{m * 10.0**k:.6g}")
            if v > hi * (1 + 1e-9):
                return out
            if v >= lo * (1 - 1e-9):
                out.append(v)
        k += 1


def next_grid(v: float) -> float:
    """The grid value above v."""
    return grid(v * 1.0001, v * 10.0)[0]


def windows(fault: str, sizes: Sequence[float]) -> Windowed:
    plan = tuple((fault, START + i * (ON + OFF), s, START + i * (ON + OFF) + ON) for i, s in enumerate(sizes))
    return Windowed(plan, START + len(sizes) * (ON + OFF))


def alarms_in_windows(g: Generator, sigma: float, gate: float, signals: dict[str, FloatArray],
                      onsets: Sequence[float], dt: float, warmup: int,
                      design: FilterDesign | None = None, on: float = ON) -> list[bool]:
    """Per window starting at each onset: a raw alarm of `g` within `on` seconds (inside its domain)."""
    segs = evaluable_segments(g, signals, warmup, design)
    out = []
    for t0 in onsets:
        i0, i1 = round(t0 / dt), round((t0 + on) / dt)
        hit = False
        for a, r in segs:
            b = a + len(r)
            lo, hi = max(i0, a), min(i1, b)
            if hi > lo and first_alarm(r[lo - a:hi - a], sigma, gate) >= 0:
                hit = True
                break
        out.append(hit)
    return out


@dataclass(frozen=True)
class PairLimit:
    fault: str
    test: str
    detected_at: float | None  # smallest grid size with an alarm (None: none up to the limit)
    stated: float | None  # next grid value above it (None when not detectable in practice)
    limit: float


Drive = Callable[[Windowed, int], tuple[FloatArray, dict[str, FloatArray]]]


def scenario_drive(scenario: str) -> Drive:
    """The sweep's drive: the windowed step faults injected in `scenario`, its CAN frames as the ECU sees them."""
    from fdi_host.tuning.drives import drive

    def run(w: Windowed, seed: int) -> tuple[FloatArray, dict[str, FloatArray]]:
        return drive(scenario, faults=list(w.faults), duration=w.duration, seed=seed, as_ecu_sees=True)

    return run


def _hits(tests: Sequence[tuple[Generator, float]], gate: float, fault: str, sizes: Sequence[float], drive: Drive,
          seeds: Sequence[int], dt: float, warmup: int) -> dict[str, list[bool]]:
    """Per test: per size, an alarm in the drives of every seed."""
    w = windows(fault, sizes)
    out = {g.name: [True] * len(sizes) for g, _ in tests}
    for seed in seeds:
        _, sig = drive(w, seed)
        for g, s in tests:
            hits = alarms_in_windows(g, s, gate, sig, [f[1] for f in w.faults], dt, warmup)
            out[g.name] = [a and b for a, b in zip(out[g.name], hits, strict=True)]
    return out


def sweep_fault(gens: Sequence[Generator], sigmas: Sequence[float], gate: float, fault: str, lo: float,
                limit: float, drive: Drive, seeds: Sequence[int], dt: float = 0.01, warmup: int = 300,
                log: Callable[[str], None] | None = None) -> list[PairLimit]:
    """Detection limits of `fault` for every test whose signature holds it (alarm with every noise seed)."""
    tests = [(g, s) for g, s in zip(gens, sigmas, strict=True) if fault in g.faults]
    levels = grid(lo, limit)
    first: dict[str, float] = {}
    for c in range(0, len(levels), CHUNK):
        todo = [(g, s) for g, s in tests if g.name not in first]
        if not todo:
            break
        chunk = levels[c:c + CHUNK]
        hits = _hits(todo, gate, fault, chunk, drive, seeds, dt, warmup)
        for g, _ in todo:
            for size, hit in zip(chunk, hits[g.name], strict=True):
                if hit:
                    first[g.name] = size
                    break
        if log is not None:
            log(f"{fault}: sizes {chunk[0]:g}..{chunk[-1]:g}: " +
                ", ".join(f"{g.name} {first.get(g.name, '-')}" for g, _ in tests))
    low = [(g, s) for g, s in tests if first.get(g.name) == levels[0]]
    rounds = 0
    while low and rounds < MAX_DOWN:  # alarm already at the smallest size: go down until a size without alarm
        rounds += 1
        below = grid(levels[0] / 20.0, levels[0] * 0.999)[-CHUNK:]
        hits = _hits(low, gate, fault, below, drive, seeds, dt, warmup)
        for g, _ in low:
            k = len(below)
            while k > 0 and hits[g.name][k - 1]:
                k -= 1
            if k < len(below):
                first[g.name] = below[k]
        levels = below
        low = [(g, s) for g, s in low if first[g.name] == levels[0]]
        if log is not None:
            log(f"{fault}: sizes {below[0]:g}..{below[-1]:g}: " +
                ", ".join(f"{g.name} {first.get(g.name, '-')}" for g, _ in tests))
    stated = _confirmed(tests, gate, fault, {n: next_grid(d) for n, d in first.items()}, limit, drive, seeds, dt,
                        warmup, log)
    return [PairLimit(fault, g.name, first.get(g.name), stated.get(g.name), limit) for g, _ in tests]


def _confirmed(tests: Sequence[tuple[Generator, float]], gate: float, fault: str, stated: dict[str, float],
               limit: float, drive: Drive, seeds: Sequence[int], dt: float, warmup: int,
               log: Callable[[str], None] | None) -> dict[str, float]:
    """The stated sizes confirmed (see the module docstring): raised along the grid until the test alarms at its
    size with every seed; tests whose size would exceed the limit are left out. The first round tries each stated
    size; a test that fails it tries the next CHUNK grid values at once, in ascending windows of one drive per seed
    (each window still follows only smaller ones), and keeps the smallest that every seed detects."""
    todo = {n: [v] for n, v in stated.items() if v <= limit}
    out: dict[str, float] = {}
    more = [*seeds, *(seed + k for k in CONFIRM_SEED_OFFSETS for seed in seeds)]
    while todo:
        sizes = sorted({v for vs in todo.values() for v in vs})
        hits = _hits([(g, s) for g, s in tests if g.name in todo], gate, fault, sizes, drive, more, dt, warmup)
        raised: dict[str, list[float]] = {}
        for name, candidates in todo.items():
            ok = [v for v in candidates if hits[name][sizes.index(v)]]
            if ok:
                out[name] = ok[0]
                continue
            batch = _next_sizes(candidates[-1], limit)
            if batch:
                raised[name] = batch
        if raised and log is not None:
            log(f"{fault}: not confirmed, raised: " + ", ".join(
                f"{n} {todo[n][-1]:g} -> {v[0]:g}" + (f"..{v[-1]:g}" if len(v) > 1 else "") for n, v in raised.items()))
        todo = raised
    return out


def _next_sizes(size: float, limit: float) -> list[float]:
    """Up to CHUNK grid values above `size`, none beyond `limit`."""
    out: list[float] = []
    v = size
    while len(out) < CHUNK and next_grid(v) <= limit:
        v = next_grid(v)
        out.append(v)
    return out


@dataclass(frozen=True)
class SizeFile:
    """The fault-size file as the sweep reads it: [requirement] (the required sizes; the sweep starts at a tenth
    of them), [limits] (physical limits, where it stops) and the generated [per_test.<fault>] tables."""

    sizes: Mapping[str, float]
    limits: Mapping[str, float]
    per_test: Mapping[str, Mapping[str, float | str]]

    @staticmethod
    def load(path: Path) -> SizeFile:
        f = FaultSizes.load(path)
        return SizeFile(f.requirement, f.limits, f.per_test)

    def lacking(self, faults: Sequence[str]) -> list[str]:
        """The faults without a [requirement] or a [limits] entry (they cannot be swept)."""
        return [f for f in faults if f not in self.sizes or f not in self.limits]

    def detection_limits(self, gens: Sequence[Generator], sigmas: Sequence[float], gate: float, fault: str,
                         drive: Drive, seeds: Sequence[int],
                         log: Callable[[str], None] | None = None) -> list[PairLimit]:
        """`sweep_fault` from [requirement] / 10 up to [limits]."""
        return sweep_fault(gens, sigmas, gate, fault, self.sizes[fault] / 10.0, self.limits[fault], drive, seeds,
                           log=log)


MARKER = "# ---- per-test stated sizes: written by `fdi-tune fault-sizes`, do not edit below ----"
NOT_DETECTABLE = "not detectable by this test in practice"
ELSEWHERE = "per_test_scenario"  # tables of the pairs stated in another manoeuvre (sweep_manoeuvres)


@dataclass(frozen=True)
class ScenarioLimit:
    """A pair the primary sweep does not state, stated in another scenario (sweep_manoeuvres)."""

    fault: str
    test: str
    scenario: str
    detected_at: float  # smallest grid size with an alarm with every seed
    stated: float  # confirmed size


def _reason(p: PairLimit) -> str:
    """Why the primary sweep states no size for `p`."""
    if p.detected_at is not None and next_grid(p.detected_at) <= p.limit:
        return f"first alarm at {p.detected_at:g}, but no size up to the limit {p.limit:g} confirmed with every seed"
    if p.detected_at is not None:
        return f"first alarm at {p.detected_at:g}, stated size {next_grid(p.detected_at):g} above the limit {p.limit:g}"
    return f"no alarm up to the limit {p.limit:g}"


def render_section(pairs: Sequence[PairLimit], provenance: str, test_order: Sequence[str], scenario: str = "",
                   elsewhere: Sequence[ScenarioLimit] = (), others: Sequence[str] = (),
                   fault_order: Sequence[str] = ()) -> str:
    """The generated [per_test.<fault>] tables: test = stated size in the primary sweep's `scenario`, or a
    string saying why there is none; the pairs stated in another scenario (`elsewhere`, swept in `others`)
    are then listed in [per_test_scenario.<fault>] tables as {scenario, size}. Faults in `fault_order` (the
    model's), any others after them in natural order (`fdi_analysis.names.in_order`)."""
    lines = [MARKER, *(f"# {p}" for p in provenance.splitlines())]
    found = {(e.fault, e.test): e for e in elsewhere}
    faults = in_order({p.fault for p in pairs}, fault_order)
    where = f"in {scenario}: " if scenario else ""
    for f in faults:
        lines.append(f"[per_test.{f}]")
        for p in sorted((p for p in pairs if p.fault == f), key=lambda p: test_order.index(p.test)):
            if p.stated is not None:
                lines.append(f"{p.test} = {p.stated:g}  # first alarm at {p.detected_at:g}")
            elif (e := found.get((f, p.test))) is not None:
                lines.append(f'{p.test} = "stated in {e.scenario} ([{ELSEWHERE}.{f}]); {where}{_reason(p)}"')
            elif others:
                lines.append(f'{p.test} = "{NOT_DETECTABLE}: {where}{_reason(p)}; in {", ".join(others)}: no size '
                             f'up to the limit confirmed with every seed"')
            else:
                lines.append(f'{p.test} = "{NOT_DETECTABLE}: {where}{_reason(p)}"')
    for f in in_order({e.fault for e in elsewhere}, fault_order):
        lines.append(f"[{ELSEWHERE}.{f}]")
        for e in sorted((e for e in elsewhere if e.fault == f), key=lambda e: test_order.index(e.test)):
            lines.append(f'{e.test} = {{ scenario = "{e.scenario}", size = {e.stated:g} }}  '
                         f"# first alarm at {e.detected_at:g}")
    return "\n".join(lines) + "\n"


def write_section(text: str, section: str) -> str:
    """`text` with everything from MARKER on replaced by `section` (the hand-written part kept)."""
    head = text.split(MARKER)[0].rstrip("\n") + "\n\n"
    return head + section
