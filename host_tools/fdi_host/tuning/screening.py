"""Practical detectability of every realizable candidate test: its noise level and, per fault of its
signature and per manoeuvre, the share of operating points at which its fault-to-noise ratio clears the gate.

For each realizable candidate MSO set (one smallest per distinct fault signature, `residuals.selected.realizable`)
the residual generator is synthesised and run on the fault-free drives of the calibration (every scenario with
several noise seeds, as the ECU's steps see them, `drives.fault_free_drives`): sigma by the rule of `fdi-tune
calibrate` (`calibrate.calibrate`). Along the fault-free drive of each scenario (its own seed) the fault
effect of every fault of the signature at its required size is evaluated at every operating point (no
simulation per fault: `residuals.sensitivity`, the residual computed with the faults kept, H(u, f)), as the
secant over the required size, for a fault of either sign:

    FNR_j(k) = min over +-size_j of |H(u_k, +-size_j e_j) - H(u_k, 0)| / sigma      (~ |d r / d f_j| size_j / sigma)

The secant, not the derivative times the size: where a fault enters a saturating law (a wheel-speed or
velocity offset in the tyre law's slip) the derivative at f = 0 overpredicts the response to a fault of the
required size by up to 1.6x, while the secant matches simulated step faults within 5 %
(tests/analysis/test_sensitivity.py). The analytic derivative is what runs on board.

A test practically detects fault j in a manoeuvre when FNR_j >= gate * its margin at a share of at least SHARE of
the manoeuvre's operating points, its margin being MARGIN or, for a slow generator, the factor it needs to cross
the gate within DETECT_S of a step (1 / `residuals.evaluate.step_response` at DETECT_S: 1.67 for one filter
stage, 8.5 for two), after its first WARMUP_S seconds (operating points where the test is not
evaluable, outside its domain, count as not detecting). The result is the quantitative counterpart of the
structural fault signature that the practical selection works on (`fdi_analysis.selection.practical`).
"""

from __future__ import annotations

import dataclasses
import math
import multiprocessing as mp
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import sympy
from numpy.typing import NDArray

from fdi_analysis.fault_matrix import Candidate
from fdi_analysis.model import Model
from fdi_analysis.mso.results import bits
from fdi_analysis.residuals.causality import synthesize
from fdi_analysis.residuals.evaluate import (
    SMALL_JDT,
    VECTOR_MODULES,
    FilterDesign,
    in_domain,
    initial_values,
    node_signals,
    sensitivity_estimate,
    step_response,
)
from fdi_analysis.residuals.generator import DOMAIN_FACTOR, XHAT, Generator
from fdi_analysis.residuals.observer import ObserverReference
from fdi_analysis.residuals.reasons import NotRealizableError
from fdi_analysis.residuals.sensitivity import J_FLOOR, faulty_residual
from fdi_analysis.residuals.signals import Node
from fdi_analysis.residuals.solvability import Solver
from fdi_analysis.selection.practical import DETECT_S, MARGIN, CandidateScreen, FaultScreen
from fdi_host.tuning.calibrate import calibrate

FloatArray = NDArray[np.float64]

WARMUP_S = 3.0  # s at the start of every drive and every evaluable run that are not operating points


# ------------------------------------------------------------------------------------------ node values
class NodeBank:
    """Filtered-signal node values on the evaluable runs of a set of drives, cached per operating domain:
    every generator of the same domain reads the same runs, restarted at each run's first sample (as fdi_diag
    re-arms a test on entering its domain)."""

    def __init__(self, drives: Sequence[Mapping[str, FloatArray]], design: FilterDesign) -> None:
        self.drives = drives
        self.design = design
        self._runs: dict[float, list[tuple[int, int, int]]] = {}
        self._values: dict[tuple[float, int, Node], FloatArray] = {}

    def runs(self, g: Generator) -> list[tuple[int, int, int]]:
        """(drive index, first sample, end) of every run of `g`'s domain longer than the warm-up."""
        if g.min_speed not in self._runs:
            warm = round(WARMUP_S / self.design.dt)
            out = []
            for d, sig in enumerate(self.drives):
                ok = in_domain(g, sig)
                edges = np.flatnonzero(np.diff(np.concatenate(([0], ok.astype(np.int8), [0]))))
                out += [(d, a, b) for a, b in zip(edges[0::2].tolist(), edges[1::2].tolist(), strict=True)
                        if b - a > warm]
            self._runs[g.min_speed] = out
        return self._runs[g.min_speed]

    def values(self, g: Generator, run: int) -> dict[Node, FloatArray]:
        d, a, b = self.runs(g)[run]
        out: dict[Node, FloatArray] = {}
        missing = [n for n in g.nodes if (g.min_speed, run, n) not in self._values]
        if missing:
            sig = {k: np.asarray(v[a:b], dtype=float) for k, v in self.drives[d].items()}
            for node, arr in node_signals(g, sig, self.design).items():
                self._values[(g.min_speed, run, node)] = arr
        for n in g.nodes:
            out[n] = self._values[(g.min_speed, run, n)]
        return out

    def raw(self, g: Generator, run: int) -> dict[str, FloatArray]:
        d, a, b = self.runs(g)[run]
        return {k: np.asarray(v[a:b], dtype=float) for k, v in self.drives[d].items()}


# ------------------------------------------------------------------------------------------ evaluation
def _observer_batch(g: Generator, bank: NodeBank, runs: Sequence[int]) -> list[tuple[FloatArray, FloatArray]]:
    """(residual, estimate) of an observer generator on several runs at once (lockstep, padded): the steps
    of `evaluate.observer_run`, vectorised over the runs."""
    o = g.observer
    assert o is not None
    vals = [bank.values(g, r) for r in runs]
    lens = np.array([len(next(iter(v.values()))) if v else 0 for v in vals])
    n = int(lens.max())
    m = len(runs)
    cols = []
    for node in g.nodes:
        arr = np.empty((m, n))
        for i, v in enumerate(vals):
            x = v[node]
            arr[i, : len(x)] = x
            arr[i, len(x):] = x[-1]
        cols.append(arr)
    syms = [XHAT, *[node.symbol for node in g.nodes]]
    fn = sympy.lambdify(syms, [o.update, o.gain, o.a, o.c, g.expr], modules=VECTOR_MODULES, cse=True)
    fn_next = sympy.lambdify(syms, [o.update, g.expr], modules=VECTOR_MODULES, cse=True)
    x0 = np.array([float(initial_values(g, {k: v[:1] for k, v in bank.raw(g, r).items()})[0]) for r in runs])
    x0 = np.where(np.isfinite(x0), x0, 0.0)
    xh = x0
    r = np.zeros((m, n))
    xs = np.zeros((m, n))
    xs[:, 0] = xh
    f0, gain0, _, _, e0 = (np.asarray(v, dtype=float) * np.ones(m) for v in fn(xh, *[c[:, 0] for c in cols]))
    g_prev = f0 + gain0 * e0
    dt = bank.design.dt
    for k in range(1, n):
        args = [c[:, k] for c in cols]
        f, gain, a, c, e = (np.asarray(v, dtype=float) * np.ones(m) for v in fn(xh, *args))
        g1 = f + gain * e
        jac = a + gain * c
        small = np.abs(jac * dt) <= SMALL_JDT
        phi = np.where(small, dt, np.expm1(jac * dt) / np.where(small, 1.0, jac))
        xh = xh + phi * 0.5 * (g_prev + g1)
        nxt, res = fn_next(xh, *args)
        g_prev = np.asarray(nxt, dtype=float) * np.ones(m) + gain * res  # with this prediction's gain
        r[:, k] = res
        xs[:, k] = xh
    return [(r[i, : lens[i]], xs[i, : lens[i]]) for i in range(m)]


def _residuals(g: Generator, bank: NodeBank) -> list[tuple[FloatArray, FloatArray]]:
    """(residual, observer estimate or zeros) on every run of `g`'s domain (residual 0 at each run's start)."""
    runs = list(range(len(bank.runs(g))))
    if not runs:
        return []
    if g.observer is not None:
        return _observer_batch(g, bank, runs)
    fn = sympy.lambdify([node.symbol for node in g.nodes], g.expr, modules=VECTOR_MODULES, cse=True)
    out = []
    for r in runs:
        vals = bank.values(g, r)
        n = len(next(iter(bank.raw(g, r).values())))
        res = np.asarray(fn(*[vals[node] for node in g.nodes]), dtype=float) * np.ones(n)
        res[0] = 0.0
        out.append((res, np.zeros(n)))
    return out


def _sensitivity_fn(model: Model, g: Generator, solver: Solver) -> Callable[..., dict[str, FloatArray]] | None:
    """A function (node arrays..., xh, sizes) -> d r / d f_j per fault by central differences of H(u, f)."""
    h = faulty_residual(model, g, solver)
    if h is None:
        return None
    faults = list(h.faults)
    syms = [XHAT, *[node.symbol for node in g.nodes], *faults]
    fh = sympy.lambdify(syms, h.residual, modules=VECTOR_MODULES, cse=True)
    fu = sympy.lambdify(syms, h.update, modules=VECTOR_MODULES, cse=True) if h.update is not None else None
    o = g.observer
    lin = (sympy.lambdify(syms[: 1 + len(g.nodes)], [o.a, o.c, o.gain], modules=VECTOR_MODULES, cse=True)
           if o is not None else None)
    names = [str(f) for f in faults]

    def sens(xh: FloatArray, args: list[FloatArray], steps: Mapping[str, float],
             one_sided: int = 0) -> dict[str, FloatArray]:
        """Central differences (one_sided 0), or forward (+1) / backward (-1) ones."""
        n = len(xh)
        out: dict[str, FloatArray] = {}
        zeros = [0.0] * len(faults)
        for j, name in enumerate(names):
            d = steps[name]
            up, dn = list(zeros), list(zeros)
            up[j] = d if one_sided >= 0 else 0.0
            dn[j] = -d if one_sided <= 0 else 0.0
            width = up[j] - dn[j]

            def diff(fn: Callable[..., object], up: list[float], dn: list[float], width: float) -> FloatArray:
                hi = np.asarray(fn(xh, *args, *up), dtype=float)
                lo = np.asarray(fn(xh, *args, *dn), dtype=float)
                return np.asarray((hi - lo) / width, dtype=float) * np.ones(n)

            de = diff(fh, up, dn, width)
            if fu is None or lin is None:
                out[name] = -de
                continue
            df = diff(fu, up, dn, width)
            a, c, gain = (np.asarray(v, dtype=float) * np.ones(n) for v in lin(xh, *args))
            pole = np.minimum(a + gain * c, -J_FLOOR)
            out[name] = (c * df - a * de) / pole
        return out

    return sens


def operation_count(g: Generator) -> int:
    """Arithmetic operations of one step of the residual (common subexpressions once), plus ten per filter
    and twenty for an observer's integration: the candidate's cost in the selection."""
    exprs = [g.expr] if g.observer is None else [g.expr, g.observer.update, g.observer.gain]
    if g.composite is not None:
        exprs.append(g.composite.expr)
    subs, red = sympy.cse(exprs, order="none")
    ops = sum(int(sympy.count_ops(e)) for _, e in subs) + sum(int(sympy.count_ops(e)) for e in red)
    return ops + 10 * len(g.filters) + (20 if g.observer is not None else 0)


@dataclass(frozen=True)
class ScreenSetup:
    """What every candidate is screened on."""

    model: Model
    reference: ObserverReference
    gate: float
    design: FilterDesign
    sizes: dict[str, float]  # the required fault sizes
    calibration: list[dict[str, FloatArray]]  # fault-free drives (all seeds) for sigma
    scenarios: dict[str, int]  # index in `calibration` of each scenario's own drive (its operating points)
    margin: float = MARGIN  # the FNR must clear the gate by this factor
    # where a tyre-law test is evaluable: |vx| >= domain_factor x v_eps (the generators' DOMAIN_FACTOR; a study
    # of a lower domain, e.g. `fdi-tune screen --domain-factor 0` at standstill, screens with another)
    domain_factor: float = DOMAIN_FACTOR


def screen_candidate(setup: ScreenSetup, c: Candidate, solver: Solver, solver_f: Solver,
                     bank: NodeBank) -> CandidateScreen:
    model = setup.model
    names = [e.id for e in model.equations]
    eqs = [names[i] for i in bits(c.equations)]
    try:
        g = synthesize(model, eqs, c.label, solver, setup.reference)
    except NotRealizableError as exc:
        return CandidateScreen(c.label, " ".join(eqs), (), math.nan, 0.0, 0, {}, str(exc))
    if setup.domain_factor != DOMAIN_FACTOR and g.min_speed > 0.0:
        g = dataclasses.replace(g, min_speed=g.min_speed / DOMAIN_FACTOR * setup.domain_factor)
    warm = round(WARMUP_S / setup.design.dt)
    runs = _residuals(g, bank)
    segs = [r[warm:] for r, _ in runs if len(r) > warm]
    if not segs:
        return CandidateScreen(c.label, " ".join(eqs), g.faults, math.nan, g.min_speed, 0, {},
                               "never evaluable on the calibration drives")
    sigma = calibrate(segs, setup.gate).sigma
    if not math.isfinite(sigma):  # e.g. at standstill, where a study lowers the domain (--domain-factor)
        return CandidateScreen(c.label, " ".join(eqs), g.faults, math.nan, g.min_speed, 0, {},
                               "residual not finite on the calibration drives")
    margin = max(setup.margin, 1.0 / max(step_response(g, DETECT_S, setup.design), 1e-6))
    sens_fn = _sensitivity_fn(model, g, solver_f)
    steps = {f: setup.sizes.get(f, 1.0) for f in g.faults}
    per: dict[str, dict[str, tuple[float, float]]] = {f: {} for f in g.faults}
    evaluable: dict[str, float] = {}
    for sc, d in setup.scenarios.items():
        total = max(1, len(next(iter(setup.calibration[d].values()))) - warm)
        evaluable[sc] = round(sum(b - a - warm for drive_index, a, b in bank.runs(g) if drive_index == d) / total, 3)
        hits = dict.fromkeys(g.faults, 0)
        fnrs: dict[str, list[FloatArray]] = {f: [] for f in g.faults}
        mine = [k for k, (drive_index, _, _) in enumerate(bank.runs(g)) if drive_index == d]
        for run in mine if sens_fn is not None else []:
            assert sens_fn is not None
            vals = bank.values(g, run)
            xs = sensitivity_estimate(runs[run][1])  # where the C computes the sensitivities
            keep = slice(warm, None)  # after the run's own warm-up (and so after the drive's first seconds)
            args = [vals[node] for node in g.nodes]
            up, down = sens_fn(xs, args, steps, one_sided=1), sens_fn(xs, args, steps, one_sided=-1)
            for f in up:
                effect = np.minimum(np.abs(up[f][keep]), np.abs(down[f][keep])) * setup.sizes.get(f, 0.0)
                fnr = np.where(np.isfinite(effect), effect / sigma, 0.0)
                hits[f] += int(np.count_nonzero(fnr >= setup.gate * margin))
                fnrs[f].append(fnr)
        for f in g.faults:
            allf = np.concatenate(fnrs[f]) if fnrs[f] else np.zeros(0)
            per[f][sc] = (round(hits[f] / total, 3), float(f"{np.median(allf):.3g}") if allf.size else 0.0)
    per_fault = {f: FaultScreen({s: v[0] for s, v in d.items()}, {s: v[1] for s, v in d.items()})
                 for f, d in per.items()}
    return CandidateScreen(c.label, " ".join(eqs), g.faults, sigma, g.min_speed, operation_count(g), per_fault,
                           evaluable=evaluable, margin=round(margin, 3))


# ------------------------------------------------------------------------------------------ the whole pool
_SETUP: ScreenSetup | None = None


def _work(chunk: Sequence[Candidate]) -> list[CandidateScreen]:
    setup = _SETUP
    assert setup is not None
    solver, solver_f = Solver(setup.model), Solver(setup.model, keep_faults=True)
    bank = NodeBank(setup.calibration, setup.design)
    # a candidate whose observer diverges on a drive gives overflows and NaNs on the way: they are handled (a
    # non-finite effect counts as not detecting), and numpy's warnings about them would only bury the progress
    with np.errstate(all="ignore"):
        return [screen_candidate(setup, c, solver, solver_f, bank) for c in chunk]


def screen(setup: ScreenSetup, candidates: Sequence[Candidate], workers: int = 2,
           progress: Callable[[int, int], None] | None = None) -> list[CandidateScreen]:
    """Every candidate screened, in candidate order, on `workers` processes (forked: they share `setup`)."""
    global _SETUP
    _SETUP = setup
    chunks = [list(candidates[i::max(1, 8 * workers)]) for i in range(max(1, 8 * workers))]
    done: dict[str, CandidateScreen] = {}
    try:
        if workers <= 1:
            results = map(_work, chunks)
            for res in results:
                for r in res:
                    done[r.label] = r
                if progress is not None:
                    progress(len(done), len(candidates))
        else:
            with mp.get_context("fork").Pool(workers) as pool:
                for res in pool.imap_unordered(_work, chunks):
                    for r in res:
                        done[r.label] = r
                    if progress is not None:
                        progress(len(done), len(candidates))
    finally:
        _SETUP = None
    return [done[c.label] for c in candidates]
