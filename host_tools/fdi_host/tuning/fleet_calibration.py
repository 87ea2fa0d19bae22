"""Calibration on a fleet of truth-plant vehicles: what each test estimates on line, and its sigma.

The model plant's residuals see only sensor noise; a vehicle that differs from the model adds what the model does not
know. Here every test of the table runs, as the ECU sees them (the drives' CAN frames, fdi_host.can.ecu_view), on the
fault-free drives of the calibration vehicles (`fdi_host.tuning.seeds.CALIBRATION_VEHICLES`: never an evaluation
vehicle or seed) in every fleet scenario, with its on-line estimator and adaptive threshold as the diagnoser runs them
(fdi_diag.h; the replica in `fdi_host.tuning.estimator`):

1. What to estimate (`choose_estimation`): the test's uncertain quantities ranked by their median share of its spread
   over the drives' evaluable samples, |d r / d theta| times the quantity's declared half-width; the quantities that
   enter with constant sensitivities lumped into one offset first (the residual cannot tell them apart); inputs
   without a declared drift (the road's friction) never; in that order, each one whose regressor the ones taken
   before it do not already span (R^2 <= COLLINEAR_R2), up to FDI_EST_MAX_PARAMS.
2. Sigma (`calibrate_sigma`): the smallest sigma with no raw alarm (the innovation beyond gate * sigma plus kappa
   times the estimate's prediction spread plus the spread of the quantities it does not estimate, or its CUSUM) in
   any drive, the estimator starting from its prior at each drive's start and learning over its start-up as the ECU
   does, and no smaller than the robust scale of the innovations it leaves (sigma is the filter's noise level too),
   times the margin. Each candidate runs the filter anew.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
import sympy
from numpy.typing import NDArray

from fdi_analysis.export.generators import MAX_ESTIMATED
from fdi_analysis.residuals.estimation import Estimated, estimated
from fdi_analysis.residuals.evaluate import FilterDesign, evaluable_segments, sensitivity_series
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.uncertainty_sensitivity import Uncertainty
from fdi_host.errors import FdiHostError
from fdi_host.tuning.calibrate import CUSUM_H, CUSUM_K, MARGIN
from fdi_host.tuning.estimator import first_raw_alarm, innovations

FloatArray = NDArray[np.float64]
KAPPA = 3.0  # fdi_diag_config_t.estimate_kappa's default (fw/src/fdi_diag.c ESTIMATE_KAPPA)
STARTUP = 100  # samples: fdi_diag_config_t.estimate_startup's default (1 s at 10 ms)
ENVELOPE_PERCENTILE = 99.5  # of each envelope signal's magnitude over the calibration fleet (`envelope_limits`)
# a quantity whose regressor the ones chosen before it explain this well (R^2 over the calibration drives) is left out
# (`choose_estimation`): the filter could not tell them apart, and a fault along their common direction would be
# absorbed by the pair
COLLINEAR_R2 = 0.9


class CalibrationError(FdiHostError, ValueError):
    """A calibration on vehicles that are not calibration vehicles."""


@dataclass(frozen=True)
class Series:
    """One test on one drive, on its evaluable samples (in its domain after each restart's warm-up), concatenated."""

    r: FloatArray
    starts: NDArray[np.bool_]  # an evaluable segment's first sample (the evaluator restarts there)
    sens: dict[str, FloatArray]  # d r / d theta of each uncertain quantity the residual holds


def drive_series(g: Generator, signals: Mapping[str, FloatArray], warmup: int, design: FilterDesign,
                 inside: NDArray[np.bool_] | None = None) -> Series:
    """The residual and its uncertainty sensitivities where the diagnoser evaluates `g` on one drive: in its domain
    and (given `inside`) the table's operating envelope, after each restart's warm-up (a non-finite value ends a
    segment there, as the diagnoser restarts the test)."""
    n = len(next(iter(signals.values())))
    r_full = np.full(n, np.nan)
    for a, r in evaluable_segments(g, signals, warmup, design, inside):
        r_full[a:a + len(r)] = r
    full: dict[str, FloatArray] = {}
    if g.uncertainty and np.isfinite(r_full).any():
        full = {k: np.asarray(v, dtype=float)
                for k, v in sensitivity_series(replace(g, sensitivities=g.uncertainty), signals, design).items()}
    take = np.isfinite(r_full)
    for v in full.values():
        take &= np.isfinite(v)
    starts = take & ~np.concatenate(([False], take[:-1]))
    return Series(r_full[take], starts[take], {k: full[k][take] if full else np.zeros(0)
                                               for k, _ in g.uncertainty})


def _constant(g: Generator) -> set[str]:
    return {n for n, e in g.uncertainty if sympy.sympify(e).is_Number}


def choose_estimation(g: Generator, series: Sequence[Series], quantities: Mapping[str, Uncertainty]
                      ) -> tuple[tuple[str, ...], ...]:
    """The groups of quantities `g`'s estimator follows: the constants lumped, then ranked by median share of the
    spread over the drives; inputs without a drift left out; at most MAX_ESTIMATED groups."""
    def estimable(n: str) -> bool:
        u = quantities[n]
        return not (u.kind == "input" and u.drift <= 0.0)

    names = [n for n, _ in g.uncertainty if estimable(n)]
    const = [n for n in names if n in _constant(g)]
    groups: list[tuple[str, ...]] = [tuple(const)] if const else []
    groups += [(n,) for n in names if n not in const]
    share: dict[tuple[str, ...], float] = {}
    for grp in groups:
        vals = []
        for s in series:
            if not len(s.r):
                continue
            v = np.zeros(len(s.r))
            for n in grp:
                v = v + np.abs(s.sens[n]) * quantities[n].half_width if n in s.sens else v
            vals.append(float(np.median(v)))
        share[grp] = float(np.median(vals)) if vals else 0.0
    ranked = sorted((grp for grp in groups if share[grp] > 0.0), key=lambda grp: (-share[grp], grp))
    chosen: list[tuple[str, ...]] = []
    columns: list[FloatArray] = []
    for grp in ranked:
        if len(chosen) == MAX_ESTIMATED:
            break
        col = _pooled(grp, series)
        if columns and _explained(col, columns) > COLLINEAR_R2:
            continue  # the chosen ones already follow it: estimated too, the two would trade a fault between them
        chosen.append(grp)
        columns.append(col)
    return tuple(chosen)


def _pooled(grp: tuple[str, ...], series: Sequence[Series]) -> FloatArray:
    """A group's regressor over every drive's samples (every 10th: the drives are long)."""
    parts = [np.ones(len(s.r))[::10] if len(grp) > 1 else s.sens[grp[0]][::10] for s in series if len(s.r)]
    return np.concatenate(parts) if parts else np.zeros(0)


def _explained(col: FloatArray, columns: Sequence[FloatArray]) -> float:
    """R^2 of `col` regressed on `columns` (with a constant): how far the chosen regressors already span it."""
    if not len(col) or float(np.var(col)) == 0.0:
        return 1.0 if columns else 0.0
    x = np.column_stack([np.ones(len(col)), *columns])
    coef, *_ = np.linalg.lstsq(x, col, rcond=None)
    return 1.0 - float(np.var(col - x @ coef)) / float(np.var(col))


@dataclass(frozen=True)
class SigmaCalibration:
    sigma: float
    peak: float  # the largest |innovation| over the drives at that sigma
    rms: float  # of the innovations
    share: float  # the median of the threshold's adaptive part over gate * sigma


def _regressors(s: Series, est: Sequence[Estimated]) -> FloatArray:
    cols = [np.ones(len(s.r)) if len(e.names) > 1 else s.sens[e.names[0]] for e in est]
    return np.column_stack(cols) if cols else np.zeros((len(s.r), 0))


def _rest(s: Series, est: Sequence[Estimated], widths: Mapping[str, float]) -> FloatArray:
    taken = {n for e in est for n in e.names}
    out = np.zeros(len(s.r))
    for n, v in s.sens.items():
        if n not in taken:
            out = out + np.abs(v) * widths[n]
    return out


def _alarms(series: Sequence[Series], regs: Sequence[FloatArray], rests: Sequence[FloatArray],
            est: Sequence[Estimated], sigma: float, gate: float, kappa: float) -> bool:
    for s, h, rest in zip(series, regs, rests, strict=True):
        if not len(s.r):
            continue
        nu, a = innovations(h, s.r, est, sigma * sigma)
        skip = STARTUP if est else 0  # the estimator's start-up: learning, not evaluated
        if first_raw_alarm(nu[skip:], (kappa * a + rest)[skip:], s.starts[skip:], sigma, gate, CUSUM_K, CUSUM_H) >= 0:
            return True
    return False


def calibrate_sigma(series: Sequence[Series], est: Sequence[Estimated], widths: Mapping[str, float], gate: float,
                    kappa: float = KAPPA, margin: float = MARGIN) -> SigmaCalibration:
    """The test's sigma: the smallest with no raw alarm in any drive (bisection), times `margin` (3 digits)."""
    regs = [_regressors(s, est) for s in series]
    rests = [_rest(s, est, widths) for s in series]
    peak = max((float(np.max(np.abs(s.r))) for s in series if len(s.r)), default=0.0)
    hi = max(peak / gate, 1e-30)
    while _alarms(series, regs, rests, est, hi, gate, kappa):
        hi *= 2.0
    lo = hi / 1e3
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if _alarms(series, regs, rests, est, mid, gate, kappa):
            lo = mid
        else:
            hi = mid
    # sigma is the residual's standard deviation as well (the filter's noise level): never below the robust scale of
    # the innovations it leaves (1.4826 x their median magnitude: the learning at each drive's start, while the
    # estimates cross their ranges, does not count), however wide the adaptive part (a filter that trusts a tiny sigma
    # follows everything, its estimates then lag and its spread covers the rest: no alarm at any sigma, a degenerate
    # calibration)
    sigma = hi
    for _ in range(8):
        scale = _innovation_scale(series, regs, est, sigma)
        if scale <= sigma * (1.0 + 1e-3):
            break
        sigma = scale
        while _alarms(series, regs, rests, est, sigma, gate, kappa):
            sigma *= 1.05
    sigma = float(f"{sigma * margin:.3g}")
    nus, shares = [], []
    for s, h, rest in zip(series, regs, rests, strict=True):
        if len(s.r):
            nu, a = innovations(h, s.r, est, sigma * sigma)
            nus.append(nu)
            shares.append((kappa * a + rest) / (gate * sigma))
    allnu = np.concatenate(nus) if nus else np.zeros(1)
    return SigmaCalibration(sigma, float(np.max(np.abs(allnu))), float(np.sqrt(np.mean(allnu**2))),
                            float(np.median(np.concatenate(shares))) if shares else 0.0)


def _innovation_scale(series: Sequence[Series], regs: Sequence[FloatArray], est: Sequence[Estimated],
                      sigma: float) -> float:
    nus = [innovations(h, s.r, est, sigma * sigma)[0] for s, h in zip(series, regs, strict=True) if len(s.r)]
    return 1.4826 * float(np.median(np.abs(np.concatenate(nus)))) if nus else 0.0


@dataclass(frozen=True)
class TestCalibration:
    generator: str
    equations: str
    groups: tuple[tuple[str, ...], ...]
    sigma: SigmaCalibration


def envelope_limits(drives: Sequence[Mapping[str, FloatArray]], signals: Sequence[str], margin: float,
                    warmup: int) -> dict[str, float]:
    """The operating envelope's limit of each signal (fdi_table.h): `margin` times the ENVELOPE_PERCENTILE-th
    percentile of its magnitude over the calibration drives after the warm-up. Not their largest value: a truth-plant
    fleet holds the rare moments of a vehicle sliding on ice, and the envelope is where the tests are validated, the
    manoeuvres of the scenarios as a vehicle drives them, not those moments."""
    return {k: margin * float(np.percentile(np.concatenate([np.abs(np.asarray(d[k], dtype=float)[warmup:])
                                                            for d in drives]), ENVELOPE_PERCENTILE))
            for k in signals}


def inside_envelope(drive: Mapping[str, FloatArray], limits: Mapping[str, float], votes: int) -> NDArray[np.bool_]:
    """Per sample: fewer than `votes` of the envelope's signals beyond their limits (fdi_diag.c inside_envelope)."""
    n = len(next(iter(drive.values())))
    count = np.zeros(n, dtype=int)
    for k, lim in limits.items():
        count += (np.abs(np.asarray(drive[k], dtype=np.float32)) > np.float32(lim)).astype(int)
    return np.asarray(count < votes, dtype=bool)


def calibrate_fleet(gens: Sequence[Generator], drives: Sequence[Mapping[str, FloatArray]],
                    quantities: Mapping[str, Uncertainty], gate: float, design: FilterDesign, warmup: int,
                    estimate: bool = True, progress: Callable[[str], None] | None = None,
                    inside: Sequence[NDArray[np.bool_]] | None = None) -> list[TestCalibration]:
    """Every test's estimated quantities (with `estimate`) and sigma on the fault-free `drives` (signals as the
    ECU sees them), on the samples `inside` the operating envelope (all, without)."""
    widths = {n: u.half_width for n, u in quantities.items()}
    out = []
    for g in gens:
        series = [drive_series(g, d, warmup, design, None if inside is None else inside[k])
                  for k, d in enumerate(drives)]
        groups = choose_estimation(g, series, quantities) if estimate else ()
        est = estimated(g, groups, quantities, design.dt)
        cal = calibrate_sigma(series, est, widths, gate)
        out.append(TestCalibration(g.name, " ".join(g.equations), groups, cal))
        if progress is not None:
            progress(f"{g.name}: sigma {cal.sigma:.3g} (innovation RMS {cal.rms:.3g}, peak {cal.peak:.3g}; adaptive "
                     f"part {cal.share:.2f} gates at the median); estimates "
                     + (", ".join(" + ".join(grp) for grp in groups) or "nothing"))
    return out


def fleet_drives(vehicles: Sequence[int], scenarios: Sequence[str], dt: float,
                 progress: Callable[[str], None] | None = None) -> list[dict[str, FloatArray]]:
    """The measured signals, as the ECU sees them, of each calibration vehicle's fault-free drive of each scenario
    (its first noise seed of the fleet plan)."""
    from fdi_host.can.dbc import CanDatabase
    from fdi_host.can.ecu_view import ecu_view
    from fdi_host.can.traffic import build_frames
    from fdi_host.sim.scenario import FLEET_SCENARIOS, load_scenario
    from fdi_host.sim.truth_sim import simulate_truth
    from fdi_host.sim.vehicle_envelope import draw_vehicle
    from fdi_host.tuning.seeds import CALIBRATION_VEHICLES, fleet_noise_seed

    outside = [v for v in vehicles if v not in CALIBRATION_VEHICLES]
    if outside:
        raise CalibrationError(f"vehicles {outside[:5]} are not calibration vehicles ({CALIBRATION_VEHICLES.start} .. "
                         f"{CALIBRATION_VEHICLES.stop - 1})")
    db = CanDatabase()
    out = []
    for v in vehicles:
        vehicle = draw_vehicle(v)
        for sc in scenarios:
            res = simulate_truth(load_scenario(sc), [], vehicle=vehicle,
                                 seed=fleet_noise_seed(v, FLEET_SCENARIOS.index(sc)))
            _, view = ecu_view(build_frames(res, db), dt)
            out.append({k: view[k] for k in res.measured})
        if progress is not None:
            progress(f"calibration vehicle {v}: {len(scenarios)} drives")
    return out
