"""Fleet replay (`fdi_host.fleet`, ``fdi-replay`` over many logs): the logs found, each scored as a single-log
replay scores it, the same table in one process, on local processes and on a local Dask cluster, and a bad
log as one row with its error."""

from __future__ import annotations

import json
import shutil
from dataclasses import replace
from functools import partial
from pathlib import Path

import pytest

from fdi_host import fleet
from fdi_host.can.logs import read_log
from fdi_host.cli import main as sim_main
from fdi_host.ecu.session import table_classes
from fdi_host.monitor.score import score_run, windows_from_truth
from fdi_host.replay import main as replay_main
from fdi_host.replay import replay_fleet, replay_log, replay_offline_fast

# name: fdi-sim arguments (8 s each; the faults from 5 s, after the ECU's warm-up and its estimators' start-up, 4.2 s)
DRIVES = {
    "a/f10": ["--scenario", "cornering", "--no-scenario-faults", "--fault", "f10@5s:-120", "--seed", "1"],
    "a/f4": ["--scenario", "cornering", "--no-scenario-faults", "--fault", "f4@5s:0.5", "--seed", "2"],
    "b/f22": ["--scenario", "slalom", "--no-scenario-faults", "--fault", "f22@5s:2", "--seed", "3"],
    "b/free": ["--scenario", "straight", "--no-scenario-faults", "--seed", "4"],
}


@pytest.fixture(scope="module")
def fleet_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("fleet")
    for name, args in DRIVES.items():
        assert sim_main([*args, "--duration", "8", "--out", str(root / f"{name}.blf"), "--quiet"]) == 0
    return root


def _without_wall(results: tuple[fleet.LogResult, ...]) -> list[fleet.LogResult]:
    return [replace(r, wall=0.0) for r in results]


def test_find_logs(fleet_dir: Path, tmp_path: Path) -> None:
    every = sorted(fleet_dir.rglob("*.blf"))
    assert fleet.find_logs([fleet_dir]) == every and len(every) == 4
    assert fleet.find_logs([str(fleet_dir / "**" / "f*.blf")]) == [p for p in every if p.stem.startswith("f")]
    assert fleet.find_logs([every[0], fleet_dir / "a", every[0]]) == [p for p in every if p.parent.name == "a"]
    with pytest.raises(fleet.FleetError, match=r"missing\.blf: no such file"):
        fleet.find_logs([tmp_path / "missing.blf"])
    with pytest.raises(fleet.FleetError, match=r"no \.log/\.asc/\.blf log"):
        fleet.find_logs([tmp_path])
    (tmp_path / "x.txt").write_text("x", encoding="utf-8")
    with pytest.raises(fleet.FleetError, match="unsupported"):
        fleet.find_logs([tmp_path / "x.txt"])
    assert fleet.is_fleet([fleet_dir]) and fleet.is_fleet(["a.blf", "b.blf"]) and fleet.is_fleet(["*.blf"])
    assert not fleet.is_fleet([every[0]])


def test_each_log_is_scored_as_one_log_replay_scores_it(fleet_dir: Path) -> None:
    report = replay_fleet([fleet_dir], "romo", 3.0, workers=1)
    assert report.executor == "one process" and not report.failed and len(report.logs) == 4
    for r in report.logs:
        frames = read_log(r.log)
        fast = replay_offline_fast(frames, "romo")
        truth = json.loads(Path(r.log).with_suffix(".truth.json").read_text(encoding="utf-8"))
        score = score_run(fast.records, windows_from_truth(truth), table_classes(fast.ecu), 3.0)
        assert r.truth is not None and r.frames == len(frames) and r.steps == len(fast.records)
        assert list(r.faults) == score.faults and r.false_alarms == len(score.false_alarms)
    by_fault = {f.fault: f for f in report.faults}
    assert set(by_fault) == {"f10", "f4", "f22"} and all(f.cases == 1 for f in report.faults)
    assert by_fault["f4"].detected == 1 and by_fault["f4"].delay_median is not None
    assert report.fault_free_hours == pytest.approx(8.0 / 3600, rel=0.01)
    assert report.drive_hours == pytest.approx(4 * 8.0 / 3600, rel=0.01)
    md = fleet.markdown(report)
    assert "| f4 |" in md and "## Per log" in md and md.count(".blf |") == 4


def test_local_processes_and_dask_give_the_one_process_table(fleet_dir: Path) -> None:
    distributed = pytest.importorskip("distributed")
    logs = fleet.find_logs([fleet_dir])
    task = partial(replay_log, table="romo", grace=3.0)
    one = fleet.run_fleet(task, logs, workers=1)
    local = fleet.run_fleet(task, logs, workers=2)
    assert local.executor == "2 local processes"
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster:
        seen: list[str] = []
        on_dask = fleet.run_fleet(task, logs, scheduler=cluster.scheduler_address,
                                  progress=lambda r: seen.append(r.log))
    assert on_dask.executor.startswith(f"Dask {cluster.scheduler_address}: 2 threads on 2 workers")
    assert sorted(seen) == [str(p) for p in logs]
    for other in (local, on_dask):
        assert _without_wall(other.logs) == _without_wall(one.logs)
        assert other.faults == one.faults


def test_cli_over_a_folder_reports_a_bad_log_as_a_row(fleet_dir: Path, tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    logs = tmp_path / "logs"
    shutil.copytree(fleet_dir, logs)
    (logs / "b" / "free.truth.json").unlink()  # a log without ground truth: replayed, not scored
    (logs / "bad.blf").write_bytes(b"LOGG" + bytes(range(256)) * 2)
    (logs / "a" / "f4.truth.json").write_text("{", encoding="utf-8")
    rc = replay_main([str(logs), "--workers", "2", "--out-dir", str(tmp_path / "out"), "--quiet"])
    out, err = capsys.readouterr()
    assert rc == 1
    assert err.strip().splitlines()[-1].startswith("fdi-replay: error: 2 of 5 logs could not be replayed")
    assert "bad.blf: holds no data frames" in err and "f4.truth.json: not a readable truth file" in err
    doc = json.loads((tmp_path / "out" / "fleet.json").read_text(encoding="utf-8"))
    assert doc["logs_total"] == 5 and doc["logs_failed"] == 2
    rows = {Path(r["log"]).name: r for r in doc["logs"]}
    assert rows["free.blf"]["truth"] is None and rows["free.blf"]["error"] is None and rows["free.blf"]["steps"] > 0
    assert rows["f10.blf"]["faults"][0]["fault"] == "f10"
    assert "logs without a truth file" in out and "| f22 |" in out


def test_cli_on_a_dask_cluster(fleet_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, dashboard_address=None) as cluster:
        rc = replay_main([str(fleet_dir / "**" / "*.blf"), "--scheduler", cluster.scheduler_address,
                          "--out-dir", str(tmp_path), "--quiet"])
    out = capsys.readouterr().out
    assert rc == 0, out
    assert f"on Dask {cluster.scheduler_address}: 2 threads on 1 workers" in out
    assert "4 of 4 logs" in out and (tmp_path / "fleet.md").is_file()


def _broken_task(path: str) -> fleet.LogResult:
    raise RuntimeError(f"cannot replay {Path(path).name}")


def test_a_task_that_raises_is_a_row_on_every_executor(fleet_dir: Path) -> None:
    logs = fleet.find_logs([fleet_dir])
    for workers in (1, 2):
        report = fleet.run_fleet(_broken_task, logs, workers=workers)
        assert [r.error for r in report.logs] == [f"RuntimeError: cannot replay {p.name}" for p in logs]
        assert report.replayed == [] and report.drive_hours == 0.0
