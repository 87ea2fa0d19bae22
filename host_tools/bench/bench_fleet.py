"""Throughput of fleet replay (`fdi-replay` over many logs, `fdi_host.fleet`): the same fleet of simulated drives
through the ECU in one process, on local processes (one per core) and on a local Dask cluster (one worker
process per core), with the same quality table from each.

Printed numbers, measured in this run: logs per minute and drive-hours per minute of each executor (wall time
from the first task sent to the last result; the Dask cluster's start is not counted, its workers' first
imports are), and the speed-up against one process.

    python host_tools/bench/bench_fleet.py [--drives 24] [--duration 60] [--logs out/bench_fleet/logs]

The drives are made once (five scenarios, one Table I fault each in three of four drives, at a size the table
detects, on its own noise seed) and reused while --logs holds them; --fresh makes them again.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from functools import partial
from pathlib import Path

from fdi_host import fleet
from fdi_host.can import traffic
from fdi_host.can.logs import write_log
from fdi_host.replay import replay_log
from fdi_host.sim.drive import write_truth
from fdi_host.sim.faults import FaultSpec
from fdi_host.sim.scenario import SCENARIOS, load_scenario
from fdi_host.sim.vehicle_sim import default_plant, simulate
from fdi_host.vehicle import add_vehicle_argument

FAULTS = (("f1", 0.3), ("f4", 0.5), ("f5", 0.5), ("f10", 150.0), ("f19", 300.0), ("f22", 1.0), ("f24", 0.5))


def make_drive(k: int, duration: float, out: Path) -> Path:
    """Drive k of the fleet: scenario k mod 5, a fault in three of four drives, written as .blf + truth."""
    rng = random.Random(k)
    scenario = replace(load_scenario(SCENARIOS[k % len(SCENARIOS)]), duration=duration, faults=())
    faults = []
    if k % 4 != 3:
        fault, size = rng.choice(FAULTS)
        faults.append(FaultSpec(fault, round(rng.uniform(5.0, max(6.0, duration - 15.0)), 1), size))
    plant = default_plant()
    res = simulate(scenario, faults, seed=1000 + k, plant=plant, duration=duration)
    path = out / f"drive{k:04d}.blf"
    write_log(traffic.build_frames(res), path)
    write_truth(res, plant, duration, 0.0, True, path.with_suffix(".truth.json"))
    return path


def make_fleet(n: int, duration: float, out: Path, workers: int) -> list[Path]:
    have = sorted(out.glob("drive*.blf"))
    if len(have) >= n:
        return have[:n]
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=workers) as pool:
        paths = sorted(pool.map(partial(make_drive, duration=duration, out=out), range(n)))
    print(f"made {n} drives of {duration:g} s in {out} ({time.perf_counter() - t0:.0f} s)", flush=True)
    return paths


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    ap.add_argument("--drives", type=int, default=24, help="logs in the fleet (default 24)")
    ap.add_argument("--duration", type=float, default=60.0, help="seconds per drive (default 60)")
    ap.add_argument("--logs", type=Path, default=Path("out/bench_fleet/logs"), help="folder of the fleet's logs")
    ap.add_argument("--fresh", action="store_true", help="make the drives again")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="processes, Dask workers (default: cores)")
    add_vehicle_argument(ap)
    ap.add_argument("--out", type=Path, default=Path("out/bench_fleet/bench.json"))
    args = ap.parse_args(argv)
    if args.fresh and args.logs.exists():
        shutil.rmtree(args.logs)
    logs = make_fleet(args.drives, args.duration, args.logs, args.workers)
    task = partial(replay_log, table=args.vehicle, grace=3.0)
    runs: list[fleet.FleetReport] = [fleet.run_fleet(task, logs, workers=1, table=args.vehicle),
                                     fleet.run_fleet(task, logs, workers=args.workers, table=args.vehicle)]
    try:
        from distributed import LocalCluster
    except ImportError:
        print("no dask.distributed (pip install 'romo-fdi[fleet]'): the Dask row is left out", file=sys.stderr)
    else:
        with LocalCluster(n_workers=args.workers, threads_per_worker=1, dashboard_address=None) as cluster:
            runs.append(fleet.run_fleet(task, logs, scheduler=cluster.scheduler_address, table=args.vehicle))
    base = runs[0]
    same = all([replace(r, wall=0.0) for r in run.logs] == [replace(r, wall=0.0) for r in base.logs]
               for run in runs[1:])
    print(f"fleet: {len(logs)} logs, {base.drive_hours:.2f} drive-hours, table {args.vehicle}; "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} before the last run")
    print("| executor | wall [s] | logs/min | drive-hours/min | vs one process |")
    print("|---|---|---|---|---|")
    for run in runs:
        print(f"| {run.executor} | {run.wall:.1f} | {run.logs_per_minute:.0f} | {run.drive_hours_per_minute:.2f} | "
              f"{base.wall / run.wall:.2f}x |")
    print(f"same quality table from every executor: {'yes' if same else 'NO'}; failed logs: {len(base.failed)}")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({
        "logs": len(logs), "drive_hours": base.drive_hours, "cores": os.cpu_count(), "same_table": same,
        "runs": [{"executor": r.executor, "wall_s": r.wall, "logs_per_minute": r.logs_per_minute,
                  "drive_hours_per_minute": r.drive_hours_per_minute} for r in runs],
    }, indent=2) + "\n", encoding="utf-8")
    print(f"wrote {args.out}")
    return 0 if same and not base.failed else 1


if __name__ == "__main__":
    # the run's output becomes section bench_fleet of docs/results.md (a run with failed logs (exit 1) is not written)
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))
    import results_doc

    rerun = results_doc.run_script("bench_fleet", __file__, sys.argv[1:], ok_codes=(0,))
    raise SystemExit(main() if rerun is None else rerun)
