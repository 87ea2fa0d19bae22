"""Benchmark of the MSO engine against Fault Diagnosis Toolbox (FDT) `MSO()`, measured in the same run.

    python analysis/bench/bench_mso.py            # FDT examples, random structures, ROMO grouped + ungrouped
    python analysis/bench/bench_mso.py --quick    # CI size: smaller cases, FDT capped at 10 s per structure
    python analysis/bench/bench_mso.py --stretch  # also count the full vertical-dynamics model (about 1.6e9 sets)

Goal per structure: our `iter_msos` (one core, every MSO set returned as a Python int) at least 10x faster
than FDT's `DiagnosisModel.MSO()` on the same structure, with the same sets (checked in the run). FDT runs in a
child process with a time limit: `--fdt-timeout`, raised to 10.5x our time where that is longer, so that a
structure FDT does not finish still shows whether the goal holds; the ratio is then a lower bound
(limit / our time). Structures whose MSO sets do not fit FDT's in-memory list (more than `--fdt-max-sets`)
are timed for us only, on `--workers` processes (counting, no per-set Python objects). Nothing is
hard-coded: every number printed is measured now; the goal line says PASS or MISS per structure.

Structures: FDT's example models (`fdt_examples.py`: shipped three tank, electric and induction motor,
Commault's and the small linear example, each also with FDT's proposed sensors); random structures of
40-300 equations, redundancy 2-14, from generators the engine was not tuned on (`generators.py`: banded
chains, Bernoulli denser and sparser, clustered subsystems); the ROMO models of analysis/models/.

Why the cost per MSO set grew with the model (33 us per set at 150 equations against 3 us at 80, before
this benchmark): the search visited subtrees that hold no MSO set. The subtree of a node (S, R) holds exactly
the MSO sets M of S with S \\ M inside R, so every one of them holds T = S \\ R (and every class of S not
inside R). A proper subset of an MSO set is matchable, so when T has structural redundancy >= 1 and is not
itself an MSO set, the subtree is empty; the algorithm of Krysander et al. (and FDT) still expands it down
to redundancy 1. On a 150-equation structure whose overdetermined part has redundancy 20, 97% of the nodes
were such dead subtrees (140 nodes per MSO set, against 1-3 on small models), and their share grows with
size and redundancy. The engine now keeps a maximum matching of T along each path (one augmenting path per
equation added) and cuts a node the moment T stops being matchable. Per-node cost is O(edges x words); the
number of words follows the equations (one up to 64, five for 282), there is no size limit.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import math
import multiprocessing as mp
import os
import shlex
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

sys.path.insert(0, str(Path(__file__).resolve().parent))

import fdt_examples
import generators

from fdi_analysis.model_loader import load_model
from fdi_analysis.mso import MsoSummary, find_msos, iter_msos, prepare
from fdi_analysis.structure import Structure

T = TypeVar("T")
MODELS = Path(__file__).resolve().parents[1] / "models"
GOAL = 10.0

# (generator, seed, equations, nominal redundancy, keyword arguments): fixed before any ratio was measured
RANDOM: list[tuple[str, int, int, int, dict[str, Any]]] = [
    ("banded", 1, 40, 2, {}),
    ("banded", 2, 80, 6, {}),
    ("banded", 3, 120, 10, {}),
    ("banded", 4, 150, 14, {}),
    ("banded", 5, 200, 8, {}),
    ("banded", 6, 282, 8, {}),
    ("banded", 7, 300, 14, {}),
    ("bernoulli", 11, 40, 4, {"p": 0.06}),
    ("bernoulli", 12, 60, 3, {"p": 0.05}),
    ("bernoulli", 13, 80, 6, {"p": 0.03}),
    ("bernoulli", 14, 150, 8, {"p": 0.015}),
    ("bernoulli", 15, 300, 10, {"p": 0.008}),
    ("clustered", 21, 60, 4, {}),
    ("clustered", 22, 100, 8, {}),
    ("clustered", 23, 150, 10, {}),
    ("clustered", 24, 250, 12, {}),
    ("clustered", 25, 300, 14, {}),
]
QUICK = {("banded", 1), ("banded", 3), ("bernoulli", 11), ("bernoulli", 13), ("clustered", 21), ("clustered", 23)}


@dataclass
class Row:
    name: str
    ne: int
    mplus: int
    phi: int
    sets: int
    ours_s: float
    fdt_s: float | None  # None: not run
    fdt_done: bool
    same: bool | None
    note: str = ""

    @property
    def ratio(self) -> float | None:
        if self.fdt_s is None or self.ours_s <= 0:
            return None
        return self.fdt_s / self.ours_s

    @property
    def verdict(self) -> str:
        r = self.ratio
        if r is None:
            return "-"
        if self.same is False:
            return "MISS (sets differ)"
        return "PASS" if r >= GOAL else "MISS"


def timed(run: Callable[[], T], min_total_s: float = 0.3, repeats: int = 3) -> tuple[T, float]:
    """Result and the best wall time per call; calls under 50 ms are repeated in batches for 0.3 s and the
    best batch mean is kept (the same rule for both tools)."""
    t = time.perf_counter()
    res = run()
    once = time.perf_counter() - t
    if once >= 0.05:
        return res, once
    n = max(3, int(min_total_s / max(once, 1e-6) / repeats))
    best = once
    for _ in range(repeats):
        t = time.perf_counter()
        for _ in range(n):
            run()
        best = min(best, (time.perf_counter() - t) / n)
    return res, best


def _fdt_child(d: dict[str, Any], conn: Any) -> None:
    import faultdiagnosistoolbox as fdt

    with contextlib.redirect_stdout(io.StringIO()):
        model = fdt.DiagnosisModel(d)
    res, dt = timed(model.MSO)
    conn.send((dt, sorted(sum(1 << int(e) for e in m) for m in res)))
    conn.close()


def fdt_msos(st: Structure, timeout: float) -> tuple[float | None, set[int] | None]:
    """FDT's MSO() in a child process (only the call is timed); (time, sets), or (None, None) on timeout."""
    d = {"type": "MatrixStruc", "X": st.X.astype(int).tolist(), "F": st.F.astype(int).tolist(),
         "Z": st.Z.astype(int).tolist()}
    ctx = mp.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_fdt_child, args=(d, send), daemon=True)
    proc.start()
    send.close()
    try:
        if not recv.poll(timeout):
            return None, None
        dt, sets = recv.recv()
        return dt, set(sets)
    except EOFError:  # the child died (memory)
        return None, None
    finally:
        if proc.is_alive():
            proc.kill()
        proc.join()


def redundancy(st: Structure) -> tuple[int, int]:
    p = prepare(st)
    eqs = [e for e in range(st.ne) if p.root >> e & 1]
    nvars = int(st.incidence[eqs].any(axis=0).sum()) if eqs else 0
    return len(eqs), len(eqs) - nvars


def measure(name: str, st: Structure, fdt_timeout: float) -> Row:
    mp_, phi = redundancy(st)
    sets, t_ours = timed(lambda: list(iter_msos(st)))
    ours = set(sets)
    assert len(ours) == len(sets), f"{name}: duplicate MSO set"
    limit = max(fdt_timeout, (GOAL + 0.5) * t_ours)  # a timeout still decides the goal
    t_fdt, theirs = fdt_msos(st, limit)
    if t_fdt is None:
        return Row(name, st.ne, mp_, phi, len(ours), t_ours, limit, False, None, f"FDT > {limit:.0f} s")
    return Row(name, st.ne, mp_, phi, len(ours), t_ours, t_fdt, True, theirs == ours)


def counted(name: str, st: Structure, workers: int) -> tuple[Row, MsoSummary]:
    """Our count on `workers` processes (no per-set Python objects); FDT not run."""
    mp_, phi = redundancy(st)
    s = find_msos(st, workers=workers, progress=sys.stderr.isatty())
    row = Row(name, st.ne, mp_, phi, s.count, s.elapsed_s, None, False, None,
              f"{workers} workers, counted; FDT not run (its list of {s.count:,} sets does not fit in memory)")
    return row, s


def fmt_time(s: float | None) -> str:
    if s is None:
        return "-"
    return f"{s * 1e3:.3g} ms" if s < 1 else f"{s:.3g} s"


def print_row(r: Row) -> None:
    ratio = "-" if r.ratio is None else (f"{r.ratio:.1f}x" if r.fdt_done else f">={r.ratio:.0f}x")
    fdt = fmt_time(r.fdt_s) if r.fdt_done else ("not run" if r.fdt_s is None else f">{r.fdt_s:.0f} s")
    same = "-" if r.same is None else ("yes" if r.same else "NO")
    us = r.ours_s / r.sets * 1e6 if r.sets else float("nan")
    print(f"{r.name:<28} {r.ne:>4} {r.mplus:>4} {r.phi:>4} {r.sets:>13,} {same:>4} {fmt_time(r.ours_s):>10} "
          f"{fdt:>12} {ratio:>9} {us:>9.3g}  {r.verdict}", flush=True)
    if r.fdt_s is None and r.note:
        print(f"  ({r.note})")


def header(title: str) -> None:
    print(f"\n{title}")
    print(f"{'structure':<28} {'ne':>4} {'M+':>4} {'phi':>4} {'MSO sets':>13} {'same':>4} {'ours':>10} "
          f"{'FDT MSO()':>12} {'ratio':>9} {'us/set':>9}  goal >= {GOAL:.0f}x")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="CI size: a subset, FDT capped at 10 s")
    ap.add_argument("--fdt-timeout", type=float, default=None,
                    help="FDT time limit per structure [s] (default 30, quick 10; at least 10.5x ours)")
    ap.add_argument("--fdt-max-sets", type=int, default=2_000_000,
                    help="structures with more MSO sets are counted on workers, without FDT (default 2e6)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--stretch", action="store_true",
                    help="also count every MSO set of romo_full_vertical.toml (about 1.6e9) on the workers")
    args = ap.parse_args(argv)
    timeout = args.fdt_timeout if args.fdt_timeout is not None else (10.0 if args.quick else 30.0)
    try:
        import faultdiagnosistoolbox as fdt
    except ImportError:
        print("faultdiagnosistoolbox is not importable; the benchmark needs it as the anchor", file=sys.stderr)
        return 2
    print(f"FDT {fdt.__version__}; wall clock on this machine, both tools in this run (calls under 50 ms repeated, "
          f"best of 3 batches, for both); FDT limit max({timeout:.0f} s, 10.5x ours) per structure; load average "
          f"{os.getloadavg()[0]:.2f}")
    rows: list[Row] = []

    header("FDT example models (loaded through the FDT JSON path)")
    for label, model in fdt_examples.example_models():
        with contextlib.redirect_stderr(io.StringIO()):  # the repeated-name warnings of the sensor variants
            st = Structure.from_fdt_dict(fdt_examples.fdt_dict(model), source=label)
        rows.append(measure(label, st, timeout))
        print_row(rows[-1])

    header("random structures (generators not used for tuning)")
    for gen, seed, ne, phi, kw in RANDOM:
        if args.quick and (gen, seed) not in QUICK:
            continue
        st = getattr(generators, gen)(seed, ne, phi, **kw)
        rows.append(measure(f"{gen} s{seed} n{ne} r{phi}", st, timeout))
        print_row(rows[-1])

    header("ROMO models (analysis/models/)")
    romo = ["romo_grouped"] + ([] if args.quick else ["romo_quasistatic"])
    romo += ["romo_full_vertical"] if args.stretch else []
    for name in romo:
        st = load_model(MODELS / f"{name}.toml").structure()
        if name == "romo_grouped":
            rows.append(measure(name, st, max(timeout, 300.0)))  # FDT needs over a minute here
        else:
            row, summary = counted(name, st, args.workers)
            rows.append(row if row.sets > args.fdt_max_sets else measure(name, st, timeout))
            if name == "romo_full_vertical":
                hist = ", ".join(f"{k}:{v:,}" for k, v in sorted(summary.by_equations.items()))
                print(f"  {name}: MSO sets by number of equations: {hist}")
        print_row(rows[-1])

    compared = [r for r in rows if r.ratio is not None]
    passed = [r for r in compared if r.verdict == "PASS"]
    missed = ", ".join(r.name for r in compared if r not in passed)
    print(f"\ngoal >= {GOAL:.0f}x FDT MSO() per structure: {len(passed)} of {len(compared)} PASS"
          + (f"; MISS: {missed}" if missed else ""))
    if compared:
        lo = min(compared, key=lambda r: r.ratio or 0.0)
        gm = math.exp(sum(math.log(r.ratio or 1.0) for r in compared) / len(compared))
        print(f"smallest ratio {lo.ratio:.1f}x ({lo.name}), geometric mean {gm:.1f}x "
              "(lower bounds where FDT hit its limit)")
    print("same MSO sets as FDT on every structure FDT finished: "
          + ("yes" if all(r.same for r in rows if r.fdt_done) else "NO"))
    print("\nper-set cost vs model size (ours, us per MSO set, structures with >= 100 sets):")
    for lo_ne, hi_ne in ((1, 50), (51, 100), (101, 150), (151, 200), (201, 300)):
        sel = [r for r in rows if lo_ne <= r.ne <= hi_ne and r.sets >= 100]
        if sel:
            costs = sorted(r.ours_s / r.sets * 1e6 for r in sel)
            print(f"  {lo_ne:>3}-{hi_ne:<3} equations: {len(sel):>2} structures, "
                  f"median {costs[len(costs) // 2]:.3g} us, range {costs[0]:.3g}-{costs[-1]:.3g} us")
    return 0 if len(passed) == len(compared) else 1


if __name__ == "__main__":
    # the run's output becomes section bench_mso of docs/results.md (exit 1, a goal missed, is a result too)
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))
    import results_doc

    raise SystemExit(results_doc.tee_main("bench_mso", main, shlex.join(["python", "analysis/bench/bench_mso.py",
                                                                          *sys.argv[1:]]), ok_codes=(0, 1)))
