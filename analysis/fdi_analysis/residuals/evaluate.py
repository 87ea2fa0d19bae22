"""Run a generator offline on sampled signals (logs, simulations): the same filter bank and residual as the
emitted C (fdi_svf recurrences of fw/include/fdi_svf.h, reset at the first sample, residual 0 there), in
double precision. C and Python agree to float rounding (tests/analysis/test_residual_c_vs_python.py)."""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
import sympy
from numpy.typing import NDArray

from fdi_analysis.residuals.generator import ACCEL_SIGNALS, DOMAIN_SIGNAL, XHAT, Generator
from fdi_analysis.residuals.signals import Node, nodes_in
from fdi_analysis.residuals.whole_terms import Composite

FloatArray = NDArray[np.float64]
SMALL_JDT = 1e-6  # below |J dt| the observer step's phi = expm1(J dt) / J is taken as dt


@dataclass(frozen=True)
class FilterDesign:
    """The generator design point of the table (fdi_table_design_t)."""

    dt: float = 0.01
    cutoff_hz: float = 1.0
    zeta: float = 0.7071

    def coefficients(self) -> tuple[float, float, float]:
        w = (2.0 / self.dt) * math.tan(math.pi * self.cutoff_hz * self.dt)
        h = 0.5 * self.dt
        wh = w * h
        two_zwh = 2.0 * self.zeta * wh
        d = 1.0 + two_zwh + wh * wh
        return h, (1.0 - two_zwh) / d, (w * wh) / d


def svf(u: FloatArray, design: FilterDesign) -> tuple[FloatArray, FloatArray]:
    """fdi_svf over a whole signal, reset at u[0]: (y, dy)."""
    h, c1, c2 = design.coefficients()
    n = u.size
    y = np.empty(n)
    dy = np.empty(n)
    x1, x2, up = float(u[0]), 0.0, float(u[0])
    y[0], dy[0] = x1, 0.0
    for k in range(1, n):
        uk = float(u[k])
        e_sum = (up - x1) + (uk - x1)
        x2n = c1 * x2 + c2 * (e_sum - h * x2)
        x1 = x1 + h * (x2 + x2n)
        x2 = x2n
        up = uk
        y[k], dy[k] = x1, x2
    return y, dy


@functools.lru_cache(maxsize=1024)
def _composite_fn(c: Composite) -> tuple[list[Node], Callable[..., object]]:
    """The derived signal's raw-sample nodes and its numpy function (built once per composite: the screening
    evaluates each candidate on many runs)."""
    src = sorted(nodes_in(c.expr))
    return src, sympy.lambdify([n.symbol for n in src], c.expr, modules="numpy")


def node_signals(g: Generator, signals: Mapping[str, FloatArray], design: FilterDesign) -> dict[Node, FloatArray]:
    values: dict[Node, FloatArray] = {}
    for k in g.knowns:
        values[Node(k, 0, 0)] = np.asarray(signals[k], dtype=float)
    if g.composite is not None:
        src, fn = _composite_fn(g.composite)
        n_samples = len(values[src[0]])
        values[Node(g.composite.signal, 0, 0)] = np.broadcast_to(
            np.asarray(fn(*[values[n] for n in src]), dtype=float), (n_samples,)).copy()
    for f in g.filters:
        y, dy = svf(values[f], design)
        values[Node(f.signal, f.level + 1, f.order)] = y
        values[Node(f.signal, f.level + 1, f.order + 1)] = dy
    return values


@functools.lru_cache(maxsize=256)
def _numpy_fn(syms: tuple[sympy.Symbol, ...], expr: sympy.Expr) -> Callable[..., object]:
    fn: Callable[..., object] = sympy.lambdify(list(syms), expr, modules="numpy")
    return fn


@functools.lru_cache(maxsize=256)
def _scalar_fn(syms: tuple[sympy.Symbol, ...], exprs: tuple[sympy.Expr, ...]) -> Callable[..., list[float]]:
    fn: Callable[..., list[float]] = sympy.lambdify(list(syms), list(exprs), modules=SCALAR_MODULES, cse=True)
    return fn


def residual(g: Generator, signals: Mapping[str, FloatArray], design: FilterDesign | None = None) -> FloatArray:
    """The residual at every sample of `signals` (measured signal name -> samples at design.dt)."""
    design = design or FilterDesign()
    values = node_signals(g, signals, design)
    syms = [n.symbol for n in g.nodes]
    if g.observer is not None:
        return observer_residual(g, signals, values, design)
    fn = _numpy_fn(tuple(syms), g.expr)
    r = np.asarray(fn(*[values[n] for n in g.nodes]), dtype=float)
    if r.ndim == 0:
        r = np.full(len(next(iter(values.values()))), float(r))
    r = r.copy()
    r[0] = 0.0
    return r


def _heaviside(v: float, h0: float = 0.0) -> float:
    return 1.0 if v > 0.0 else 0.0


def _sign(v: float) -> float:
    return 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)


# Scalar functions for lambdify: the derivatives hold sign() and Heaviside() (as the C: 0 at 0)
SCALAR_MODULES: list[object] = [{"Heaviside": _heaviside, "sign": _sign}, "math"]
VECTOR_MODULES: list[object] = [{"Heaviside": lambda v, h0=0.0: np.where(np.asarray(v) > 0.0, 1.0, 0.0)}, "numpy"]


def initial_values(g: Generator, signals: Mapping[str, np.ndarray]) -> np.ndarray:
    assert g.observer is not None
    n = len(next(iter(signals.values())))
    init = g.observer.initial
    if not init.free_symbols:
        return np.full(n, float(init))
    syms = sorted(init.free_symbols, key=str)
    fn = sympy.lambdify(syms, init, modules="numpy")
    return np.asarray(fn(*[np.asarray(signals[str(s).split("__L")[0]], dtype=float) for s in syms]),
                      dtype=float) * np.ones(n)


def observer_residual(g: Generator, signals: Mapping[str, FloatArray], values: Mapping[Node, FloatArray],
                      design: FilterDesign) -> FloatArray:
    """The observer generator sample by sample (fdi_analysis.residuals.observer; same steps as the C)."""
    return observer_run(g, signals, values, design)[0]


def observer_run(g: Generator, signals: Mapping[str, FloatArray], values: Mapping[Node, FloatArray],
                 design: FilterDesign) -> tuple[FloatArray, FloatArray]:
    """(residual, estimate xh) of an observer generator at every sample."""
    o = g.observer
    assert o is not None
    syms = [XHAT, *[n.symbol for n in g.nodes]]
    fn = _scalar_fn(tuple(syms), (o.update, o.gain, o.a, o.c, g.expr))
    fn_next = _scalar_fn(tuple(syms), (o.update, g.expr))
    cols = [np.asarray(values[n], dtype=float).tolist() for n in g.nodes]
    rows = list(zip(*cols, strict=True)) if cols else [()] * len(next(iter(signals.values())))
    n = len(rows)
    x0 = float(initial_values(g, {k: np.asarray(v)[:1] for k, v in signals.items()})[0])
    x0 = x0 if math.isfinite(x0) else 0.0  # as the C: the sensor outside the MSO set is not checked
    r = np.zeros(n)
    xs = np.zeros(n)
    f, gain, _, _, e = fn(x0, *rows[0])
    xh, g_prev = x0, f + gain * e
    xs[0] = xh
    dt = design.dt
    for k in range(1, n):
        try:
            f, gain, a, c, e = fn(xh, *rows[k])
            g1 = f + gain * e
            jac = a + gain * c
            phi = math.expm1(jac * dt) / jac if abs(jac * dt) > SMALL_JDT else dt
            xh = xh + phi * 0.5 * (g_prev + g1)
            f, r[k] = fn_next(xh, *rows[k])
            g_prev = f + gain * r[k]  # the input kept for the next step, with this prediction's gain
        except (OverflowError, ZeroDivisionError):  # the estimate has diverged (a large fault): alarm from here on
            r[k:] = math.inf
            xs[k:] = math.nan
            break
        xs[k] = xh
    return r, xs


def sensitivity_estimate(xs: FloatArray) -> FloatArray:
    """Per sample, the estimate at which an observer generator's step computes its sensitivities: the one its
    prediction starts from (the previous sample's estimate; at the first sample, the reset value), where its gain
    and Jacobian are already evaluated."""
    return np.concatenate((xs[:1], xs[:-1]))


@functools.lru_cache(maxsize=256)
def _vector_fn(syms: tuple[sympy.Symbol, ...], exprs: tuple[sympy.Expr, ...]) -> Callable[..., list[object]]:
    """The numpy function of `exprs` over `syms` (one lambdify per expression list: a drive's series costs the
    evaluation only)."""
    fn: Callable[..., list[object]] = sympy.lambdify(list(syms), list(exprs), modules=VECTOR_MODULES, cse=True)
    return fn


def sensitivity_series(g: Generator, signals: Mapping[str, FloatArray],
                       design: FilterDesign | None = None) -> dict[str, FloatArray]:
    """d r / d f of each fault of `g.sensitivities` at every sample (observer generators at the estimate of
    `sensitivity_estimate`)."""
    design = design or FilterDesign()
    if not g.sensitivities:
        return {}
    values = node_signals(g, signals, design)
    syms = [XHAT, *[n.symbol for n in g.nodes]]
    n = len(next(iter(signals.values())))
    xs = sensitivity_estimate(observer_run(g, signals, values, design)[1]) if g.observer is not None else np.zeros(n)
    fn = _vector_fn(tuple(syms), tuple(e for _, e in g.sensitivities))
    out = fn(xs, *[values[node] for node in g.nodes])
    return {f: np.asarray(v, dtype=float) * np.ones(n) for (f, _), v in zip(g.sensitivities, out, strict=True)}


def in_domain(g: Generator, signals: Mapping[str, FloatArray]) -> NDArray[np.bool_]:
    """Per sample: inside the generator's operating domain (fdi_gen_in_domain of the emitted C, in float)."""
    n = len(next(iter(signals.values())))
    ok = np.ones(n, dtype=bool)
    if g.min_speed > 0.0:
        v = np.asarray(signals[DOMAIN_SIGNAL], dtype=float).astype(np.float32)
        ok &= np.abs(v) >= np.float32(g.min_speed)
    return ok


def in_range(g: Generator, signals: Mapping[str, FloatArray]) -> NDArray[np.bool_]:
    """Per sample: inside the generator's range (fdi_gen_in_range of the emitted C, in float)."""
    n = len(next(iter(signals.values())))
    if g.max_accel <= 0.0:
        return np.ones(n, dtype=bool)
    ax, ay = (np.asarray(signals[k], dtype=float).astype(np.float32) for k in ACCEL_SIGNALS)
    return np.asarray((ax * ax + ay * ay) <= np.float32(g.max_accel * g.max_accel), dtype=bool)


REENTRY = 50  # samples: fdi_diag_config_t.reentry_steps's default (0.5 s at 10 ms)


def evaluable_segments(g: Generator, signals: Mapping[str, FloatArray], warmup: int,
                       design: FilterDesign | None = None, inside: NDArray[np.bool_] | None = None,
                       reentry: int = REENTRY) -> list[tuple[int, FloatArray]]:
    """The residual where the diagnoser evaluates it: per maximal run of in-domain samples the generator is
    restarted at the run's first sample (as fdi_diag re-arms it) and the first `warmup` samples are dropped; within
    it, the samples outside the generator's range (or, given `inside`, outside the table's operating envelope) are not
    evaluated, and after each return the first `reentry` are dropped (the filters ran on: fdi_diag's re-entry).
    Returns (index of the first evaluated sample, residual from there to the end of the evaluated run)."""
    ok = in_domain(g, signals)
    keep = in_range(g, signals) if inside is None else in_range(g, signals) & inside
    edges = np.flatnonzero(np.diff(np.concatenate(([0], ok.astype(np.int8), [0]))))
    out: list[tuple[int, FloatArray]] = []
    for a, b in zip(edges[0::2].tolist(), edges[1::2].tolist(), strict=True):
        if b - a <= warmup:
            continue
        r = residual(g, {k: np.asarray(v)[a:b] for k, v in signals.items()}, design)
        use = keep[a:b].copy()
        use[:warmup] = False
        returns = np.flatnonzero(use & ~np.concatenate(([False], use[:-1])))  # back into the range
        for j in returns.tolist():
            if j > warmup:
                use[j:j + reentry] = False
        inner = np.flatnonzero(np.diff(np.concatenate(([0], use.astype(np.int8), [0]))))
        for c, d in zip(inner[0::2].tolist(), inner[1::2].tolist(), strict=True):
            out.append((a + c, r[c:d]))
    return out


def step_response(g: Generator, t: float, design: FilterDesign | None = None) -> float:
    """The share of its final value that the generator's response to a step fault has reached `t` seconds after
    the step: the step through its chain of `level` filters (each fdi_svf, the y output), times, for an observer
    generator, the share its error pole has absorbed (1 - exp(-pole t))."""
    design = design or FilterDesign()
    n = max(2, math.ceil(t / design.dt) + 1)
    y = np.ones(n)
    y[0] = 0.0
    for _ in range(g.level):
        y = svf(y, design)[0]
    share = float(y[min(n - 1, round(t / design.dt))])
    if g.observer is not None and g.observer.pole > 0.0:
        share *= 1.0 - math.exp(-g.observer.pole * t)
    return share


def response_time(g: Generator, design: FilterDesign | None = None, fraction: float = 0.9) -> float:
    """Seconds after a step fault until the generator's response has reached `fraction` of its final value:
    the step through its chain of `level` filters (each fdi_svf, the y output), plus, for an observer
    generator, the time its error pole (-pole) takes to absorb the step's transient. A quiet test has had its
    chance to react to a fault only once the fault has lasted this long."""
    design = design or FilterDesign()
    n = round(10.0 / design.dt)
    y = np.ones(n)
    y[0] = 0.0
    for _ in range(g.level):
        y = svf(y, design)[0]
    reached = np.flatnonzero(y >= fraction)
    t = float(reached[0]) * design.dt if reached.size else 10.0
    if g.observer is not None and g.observer.pole > 0.0:
        t += -math.log(1.0 - fraction) / g.observer.pole
    return t
