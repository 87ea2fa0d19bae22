"""Where many independent tasks run: in this process, on local processes, or on a Dask cluster.

Shared by the fleet replay (`fdi_host.fleet`, one recorded log per task) and the fleet quality suite
(`fdi_host.quality.fleet`, one simulated vehicle x scenario per task). A task that raises is one failed item
(`on_error` turns it into a result), never the end of the run; Ctrl-C cancels what has not started.

* one process (``workers=1``): the tasks in a loop;
* local processes (default): `concurrent.futures.ProcessPoolExecutor`, one worker per core;
* a Dask cluster (``scheduler="tcp://host:8786"``, the ``fleet`` extra): `distributed.Client.map`. The workers
  need romo-fdi installed (and, for logs, the same paths); only the results come back.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import TypeVar

from fdi_host.errors import FdiHostError

T = TypeVar("T")
R = TypeVar("R")


class ExecutorError(FdiHostError, ValueError):
    """No Dask where a scheduler is asked for, or a scheduler that cannot be reached."""


def run_tasks(task: Callable[[T], R], items: Sequence[T], on_error: Callable[[T, BaseException], R], *,
              workers: int | None = None, scheduler: str | None = None) -> tuple[str, Iterator[R]]:
    """(a name of the executor, the results as they arrive, in any order)."""
    if scheduler is not None:
        return _on_dask(task, items, on_error, scheduler)
    n = max(1, workers or os.cpu_count() or 1)
    if n == 1 or len(items) <= 1:
        return "one process", _in_process(task, items, on_error)
    return f"{min(n, len(items))} local processes", _on_processes(task, items, on_error, n)


def _in_process(task: Callable[[T], R], items: Sequence[T], on_error: Callable[[T, BaseException], R]
                ) -> Iterator[R]:
    for item in items:
        try:
            yield task(item)
        except Exception as exc:  # as on processes and Dask: one failed task is one item
            yield on_error(item, exc)


def _on_processes(task: Callable[[T], R], items: Sequence[T], on_error: Callable[[T, BaseException], R],
                  n: int) -> Iterator[R]:
    with ProcessPoolExecutor(max_workers=min(n, len(items))) as pool:
        futures = {pool.submit(task, item): item for item in items}
        try:
            for fut in as_completed(futures):
                try:
                    yield fut.result()
                except Exception as exc:  # one failed task is one item, not the run's end
                    yield on_error(futures[fut], exc)
        except BaseException:  # Ctrl-C: the queued tasks are not started
            pool.shutdown(wait=False, cancel_futures=True)
            raise


def _on_dask(task: Callable[[T], R], items: Sequence[T], on_error: Callable[[T, BaseException], R],
             scheduler: str) -> tuple[str, Iterator[R]]:
    try:
        from distributed import Client
        from distributed import as_completed as dask_completed
    except ImportError as exc:
        raise ExecutorError("--scheduler needs Dask: pip install 'romo-fdi[fleet]'") from exc
    try:
        client = Client(scheduler, timeout="10s")  # type: ignore[no-untyped-call]
    except (OSError, TimeoutError) as exc:
        raise ExecutorError(f"cannot reach the Dask scheduler {scheduler}: {exc}") from exc
    workers = client.scheduler_info().get("workers", {})
    threads = sum(int(w.get("nthreads", 1)) for w in workers.values())

    def results() -> Iterator[R]:
        try:
            futures = client.map(task, list(items), pure=False)
            by_key = {f.key: item for f, item in zip(futures, items, strict=True)}
            for fut in dask_completed(futures):  # type: ignore[no-untyped-call]
                try:
                    yield fut.result()
                except Exception as exc:  # one failed task is one item, not the run's end
                    yield on_error(by_key[fut.key], exc)
        finally:
            client.close()  # type: ignore[no-untyped-call]

    return f"Dask {scheduler}: {threads} threads on {len(workers)} workers", results()
