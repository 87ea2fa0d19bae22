"""Benchmark of the MSO engine against Fault Diagnosis Toolbox (FDT) MSO(), measured in the same run.

    python analysis/bench/bench_mso.py                  # FDT examples, random structures, grouped ROMO (+FDT, ~2 min)
    python analysis/bench/bench_mso.py --no-fdt-romo    # skip FDT's 100 s grouped ROMO run
    python analysis/bench/bench_mso.py --ungrouped      # also count the 75M MSO sets of the ungrouped model
    python analysis/bench/bench_mso.py --selection-limit 20   # shorter exact selection on the full model
    python analysis/bench/bench_mso.py --selection-without-sat   # also the code-search fallback (no python-sat)

Prints measured times, MSO/s and ratios; nothing is hard-coded.
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar
from unittest import mock

from fdi_analysis import selection_sat
from fdi_analysis.candidates_mtes import candidates_from_mtes
from fdi_analysis.cli_select import optimality
from fdi_analysis.mso import find_msos, isolability, iter_msos, load_reference, mtes, prepare
from fdi_analysis.random_structures import sparse_random_structure
from fdi_analysis.selection import greedy, optimal
from fdi_analysis.structure import Structure

T = TypeVar("T")

REF = Path(__file__).resolve().parents[2].parent / "shared" / "reference" / "romo_model"


def random_structure(seed: int, ne: int, phi: int) -> Structure:
    return sparse_random_structure(seed, ne, phi)



def redundancy(s: Structure) -> tuple[int, int]:
    p = prepare(s)
    eqs = [e for e in range(s.ne) if p.root >> e & 1]
    nvars = int(s.incidence[eqs].any(axis=0).sum()) if eqs else 0
    return len(eqs), len(eqs) - nvars


def timed(run: Callable[[], T], min_total_s: float = 0.3) -> tuple[T, float]:
    """Result and mean wall time per call; sub-50-ms calls are repeated (the same rule for both tools)."""
    t = time.perf_counter()
    res = run()
    once = time.perf_counter() - t
    if once >= 0.05:
        return res, once
    n = max(3, int(min_total_s / max(once, 1e-6)))
    t = time.perf_counter()
    for _ in range(n):
        run()
    return res, (time.perf_counter() - t) / n


def fdt_msos(s: Structure) -> tuple[set[int], float]:
    """FDT's MSO() on the same matrix; only the call is timed, converting its output to bitsets is not."""
    from faultdiagnosistoolbox import dmperm

    res, dt = timed(lambda: dmperm.MSO(s.X))
    return {sum(1 << int(e) for e in m) for m in res}, dt


def ours_msos(s: Structure) -> tuple[set[int], float]:
    res, dt = timed(lambda: list(iter_msos(s)))
    out = set(res)
    assert len(out) == len(res), "duplicate MSO set"
    return out, dt


def peak_rss_mb() -> tuple[float, float]:
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    kids = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    return own, kids


def row(name: str, ne: int, mp: int, phi: int, n: int, same: bool | None, t_ours: float, t_fdt: float | None) -> None:
    ratio = f"{t_fdt / t_ours:8.1f}x" if t_fdt is not None and t_ours > 0 else "       -"
    tf = f"{t_fdt * 1e3:10.4g}" if t_fdt is not None else "         -"
    print(
        f"{name:<24} {ne:>4} {mp:>4} {phi:>4} {n:>9} {'-' if same is None else ('yes' if same else 'NO'):>5} "
        f"{t_ours * 1e3:10.4g} {tf} {ratio} {n / t_ours if t_ours > 0 else 0:12.0f}"
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--no-fdt-romo", action="store_true", help="do not run FDT on grouped ROMO (about 100 s)")
    ap.add_argument("--ungrouped", action="store_true", help="count the ungrouped ROMO MSO sets (75M) on 2 workers")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--selection-limit", type=float, default=60.0,
                    help="time limit [s] of each optimal selection on the full vertical model (default 60)")
    ap.add_argument("--selection-without-sat", action="store_true",
                    help="also run the optimal selection without python-sat (the code-search fallback)")
    ap.add_argument("--slow", action="store_true", help="add a 150-equation case where FDT needs minutes")
    args = ap.parse_args(argv)

    try:
        import faultdiagnosistoolbox as fdt
        from faultdiagnosistoolbox import models
    except ImportError:
        print("faultdiagnosistoolbox is not importable; the benchmark needs it as the anchor", file=sys.stderr)
        return 2
    print(f"FDT {fdt.__version__}; wall-clock milliseconds per call on this machine, same run (calls under 50 ms are "
          "repeated for 0.3 s and averaged, for both tools); load average "
          f"{os.getloadavg()[0]:.2f}")
    print(
        f"{'structure':<24} {'ne':>4} {'M+':>4} {'phi':>4} {'MSOs':>9} {'same':>5} {'ours[ms]':>10} {'FDT[ms]':>10} "
        f"{'ratio':>9} {'ours MSO/s':>12}"
    )
    cases: list[tuple[str, Structure]] = []
    for m in (models.three_tank, models.electric_motor, models.induction_motor):
        cases.append((m.name, Structure.from_fdt_dict({"X": m.X.tolist(), "F": m.F.tolist()})))
    randoms = [(100, 40, 3), (101, 60, 5), (102, 80, 6), (105, 70, 8), (103, 110, 4)]
    if args.slow:
        randoms.append((104, 150, 3))  # FDT needs about 5 minutes here
    for seed, ne, phi in randoms:
        cases.append((f"random s{seed} n{ne}", random_structure(seed, ne, phi)))
    tot_ours = tot_fdt = 0.0
    ratios: list[float] = []
    for name, s in cases:
        mp, phi = redundancy(s)
        ours, t_ours = ours_msos(s)
        theirs, t_fdt = fdt_msos(s)
        tot_ours += t_ours
        ratios.append(t_fdt / t_ours)
        tot_fdt += t_fdt
        row(name, s.ne, mp, phi, len(ours), ours == theirs, t_ours, t_fdt)
    print(
        f"{'all of the above':<24} {'':>4} {'':>4} {'':>4} {'':>9} {'':>5} "
        f"{tot_ours * 1e3:10.4g} {tot_fdt * 1e3:10.4g} "
        f"{tot_fdt / tot_ours:8.1f}x"
    )
    print(
        f"per structure: smallest ratio {min(ratios):.1f}x, geometric mean "
        f"{math.exp(sum(math.log(r) for r in ratios) / len(ratios)):.1f}x"
    )

    print("\nROMO reference structures (find_msos: C aggregation, nothing stored)")
    g = load_reference(REF / "romo_dual_track_grouped.json")
    mp, phi = redundancy(g)
    s1 = find_msos(g, workers=1, progress=False)
    s2 = find_msos(g, workers=args.workers, progress=False)
    same_par = (s1.count, s1.by_equations, s1.signatures) == (s2.count, s2.by_equations, s2.signatures)
    print(
        f"grouped: {s1.count} MSO sets, {len(s1.signatures)} fault signatures; serial {s1.elapsed_s:.2f} s "
        f"({s1.count / s1.elapsed_s:,.0f} MSO/s), {args.workers} workers {s2.elapsed_s:.2f} s "
        f"({s2.count / s2.elapsed_s:,.0f} MSO/s, {s2.tasks} tasks); parallel == serial: {same_par}"
    )
    if not args.no_fdt_romo:
        from faultdiagnosistoolbox import dmperm

        t = time.perf_counter()
        n_fdt = len(dmperm.MSO(g.X))
        t_fdt = time.perf_counter() - t
        print(
            f"grouped FDT MSO(): {n_fdt} MSO sets in {t_fdt:.1f} s -> ours serial {t_fdt / s1.elapsed_s:.0f}x, "
            f"{args.workers} workers {t_fdt / s2.elapsed_s:.0f}x faster; same count: {n_fdt == s1.count}"
        )

    full = load_reference(REF / "romo_dual_track_full.json")
    iso = isolability(full)
    t = time.perf_counter()
    mt = mtes(full)
    t_mt = time.perf_counter() - t
    print(
        f"full vertical ({full.ne} eq.): single-fault isolability in {iso.elapsed_s * 1000:.1f} ms, "
        f"non-isolable pairs {iso.non_isolable_pairs()}; {len(mt.mtes)} MTES "
        f"({len(mt.minimal_signatures())} distinct fault supports) in {t_mt:.1f} s"
    )
    t = time.perf_counter()
    cands = candidates_from_mtes(full, mt)
    t_c = time.perf_counter() - t
    budget = args.selection_limit
    print(f"full vertical test selection on the MTES candidates ({t_c:.1f} s to build them), optimal with "
          f"{budget:.0f} s limit per method:")
    solvers = [("SAT", True)] if selection_sat.HAVE_SAT else [("code search, python-sat missing", False)]
    if args.selection_without_sat and selection_sat.HAVE_SAT:
        solvers.append(("code search", False))
    exact_total = iso.elapsed_s + t_mt + t_c  # isolability, MTES, candidates, then both optimal selections
    for method in ("A", "B"):
        t = time.perf_counter()
        g = greedy(cands, full.nf, method)
        t_g = time.perf_counter() - t
        print(f"  method {method}: greedy {len(g.tests)} tests, {g.total_cost} unknowns ({t_g:.1f} s)")
        for label, use_sat in solvers:
            load = os.getloadavg()[0]
            t = time.perf_counter()
            with mock.patch.object(selection_sat, "HAVE_SAT", use_sat):
                o = optimal(cands, full.nf, method, time_limit_s=budget)
            t_o = time.perf_counter() - t
            print(f"    optimal ({label}): {len(o.tests)} tests, {o.total_cost} unknowns in {t_o:.1f} s: "
                  f"{optimality(o)} (load average {load:.1f} at the start)")
            if label == solvers[0][0]:
                exact_total += t_o
    print(f"  full vertical, isolability + MTES candidates + optimal selections A and B ({solvers[0][0]}): "
          f"{exact_total:.1f} s")

    if args.ungrouped:
        u = load_reference(REF / "romo_dual_track_63x73.json")
        su = find_msos(u, workers=args.workers, progress=True)
        own, kids = peak_rss_mb()
        print(
            f"ungrouped ({u.ne} eq.): {su.count} MSO sets, {len(su.signatures)} fault signatures, complete="
            f"{su.complete}, {su.elapsed_s:.1f} s on {args.workers} workers ({su.count / su.elapsed_s:,.0f} MSO/s); "
            f"peak RSS main {own:.0f} MB, largest worker {kids:.0f} MB"
        )
        hist = ", ".join(f"{k}:{v}" for k, v in sorted(su.by_equations.items()))
        print(f"  MSO sets by number of equations: {hist}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
