"""MSO enumeration on the native engine: streaming iteration, aggregation, multi-process search.

The search tree of the Krysander-Aslund-Nyberg algorithm is split at its top levels into independent
subproblems (node S, removable set R). The no-repeated-removal rule makes the subtrees disjoint, so every
MSO set is found in exactly one of them. Workers aggregate in C (count, size histogram, signature table)
and send one table each at the end; memory does not grow with the number of MSO sets.

Size: no fixed limit. The engine picks the narrowest compiled bitset width that holds the equations
(1 word up to 64 equations, 5 words for 282, ... up to 16384, where its int16 indices end); a search node
costs O(edges x words). The engine keys fault signatures on 64 bits: a model with more faults is keyed on
its distinct fault rows (the equations' fault sets) and the keys are merged back into fault sets here;
with more than 64 distinct fault rows the engine only tells faulty equations apart and the signatures
are computed here from the yielded sets (one process, about a microsecond of Python per MSO set).
"""

from __future__ import annotations

import heapq
import multiprocessing as mp
import os
import queue
import signal
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from functools import cached_property
from types import FrameType
from typing import Any

import numpy as np
import numpy.typing as npt
from tqdm import tqdm

from ..errors import ComputationError
from ..structure import Structure
from . import _core
from .results import MsoSummary, SignatureEntry, lex_before

KEY_BITS = 64  # the engine's fault-signature key

# (equations, unknowns, key bits, incidence bytes ne x nv, key bytes ne x key bits): picklable, cheap to build
ModelArgs = tuple[int, int, int, bytes, bytes]


@dataclass(frozen=True)
class Prepared:
    """A structure in the engine's form: the native model, its dense source and the overdetermined part."""

    args: ModelArgs
    model: _core.Model
    root: int  # overdetermined part M+ of the whole model (bitset over equations)
    fault_masks: tuple[int, ...]  # fault bitmask of each equation (any number of faults)
    key_faults: tuple[int, ...] | None = None  # engine key bit k -> fault mask; None: bit j is fault j
    keyed: bool = True  # False: engine keys only mark faulty equations (over 64 distinct fault rows)

    @property
    def ne(self) -> int:
        return self.args[0]

    @cached_property
    def rows(self) -> list[list[int]]:
        """Unknown indices of each equation."""
        ne, nv, _, inc, _ = self.args
        return [[x for x in range(nv) if inc[e * nv + x]] for e in range(ne)]

    def signature(self, key: int) -> int:
        """The fault set of an engine signature key."""
        return key if self.key_faults is None else _key_to_faults(key, self.key_faults)

    def faults_of(self, eqs: int) -> int:
        f = 0
        masks = self.fault_masks
        while eqs:
            low = eqs & -eqs
            f |= masks[low.bit_length() - 1]
            eqs ^= low
        return f


def _key_to_faults(key: int, key_faults: tuple[int, ...]) -> int:
    f = 0
    while key:
        low = key & -key
        f |= key_faults[low.bit_length() - 1]
        key ^= low
    return f


def fault_keys(structure: Structure) -> tuple[bytes, int, tuple[int, ...] | None]:
    """Fault key bytes (ne x bits), key bits, and the fault mask of each key bit (None: bit j = fault j).
    Over 64 distinct fault rows: one key bit that marks the faulty equations, and an empty mask tuple."""
    if structure.nf <= KEY_BITS:
        return _nonzero_bytes(structure.F), structure.nf, None
    F = structure.F != 0
    rows = sorted({tuple(int(j) for j in r.nonzero()[0]) for r in F if r.any()})
    if len(rows) > KEY_BITS:
        return F.any(axis=1).astype(np.uint8).tobytes(), 1, ()
    index = {r: k for k, r in enumerate(rows)}
    keys = bytearray(structure.ne * len(rows))
    for e, r in enumerate(F):
        if r.any():
            keys[e * len(rows) + index[tuple(int(j) for j in r.nonzero()[0])]] = 1
    return bytes(keys), len(rows), tuple(sum(1 << j for j in r) for r in rows)


def _nonzero_bytes(a: npt.NDArray[Any]) -> bytes:
    """Row-major bytes, nonzero where `a` is (the engine reads any nonzero byte as an incidence)."""
    return a.tobytes() if a.dtype.itemsize == 1 else (a != 0).tobytes()


def model_args(structure: Structure) -> ModelArgs:
    # dense bytes: per-row Python or numpy work costs more than the whole search on small models
    inc = _nonzero_bytes(structure.X)
    keys, nk, _ = fault_keys(structure)
    return structure.ne, structure.nx, nk, inc, keys


def _model(args: ModelArgs) -> _core.Model:
    return _core.model_dense(*args)


def prepare(structure: Structure) -> Prepared:
    inc = _nonzero_bytes(structure.X)
    keys, nk, key_faults = fault_keys(structure)
    args = (structure.ne, structure.nx, nk, inc, keys)
    model = _model(args)
    root = _core.mplus(model, (1 << structure.ne) - 1)
    masks = tuple(sum(1 << int(j) for j in row.nonzero()[0]) for row in structure.F)
    keyed = key_faults is None or len(key_faults) > 0
    return Prepared(args=args, model=model, root=root, fault_masks=masks, key_faults=key_faults, keyed=keyed)


def mplus(structure: Structure | Prepared, eqs: int) -> int:
    """Overdetermined part (DM M+) of an equation set given as a bitset."""
    p = structure if isinstance(structure, Prepared) else prepare(structure)
    return _core.mplus(p.model, eqs)


def iter_msos(structure: Structure | Prepared, *, batch: int = 8192) -> Iterator[int]:
    """Every MSO set of the structure once, as an int bitset over equations (streaming, constant memory)."""
    if isinstance(structure, Prepared):
        model, root = structure.model, structure.root
    else:  # the short path: on small models the Python around the search costs more than the search
        model = _model(model_args(structure))
        root = _core.mplus(model, (1 << structure.ne) - 1)
    if root == 0:
        return
    it = _core.iter_new(model, root, root)
    size = 64  # small first batches: a large result buffer costs more than a small model's whole search
    while True:
        chunk = _core.iter_next(it, size)
        yield from chunk
        if len(chunk) < size:
            return
        size = min(batch, size * 4)


def split_tasks(p: Prepared, target: int) -> list[tuple[int, int]]:
    """Disjoint subproblems (S, R) covering the whole search tree, at least `target` when possible."""
    if p.root == 0:
        return []
    heap: list[tuple[int, int, int, int, int]] = []  # (-phi, -|R|, seq, S, R)
    done: list[tuple[int, int]] = []
    seq = 0

    def push(s: int, r: int) -> None:
        nonlocal seq
        phi = s.bit_count() - _n_unknowns(p, s)
        if phi <= 2:
            done.append((s, r))
        else:
            heapq.heappush(heap, (-phi, -r.bit_count(), seq, s, r))
        seq += 1

    push(p.root, p.root)
    while heap and len(heap) + len(done) < target:
        _, _, _, s, r = heapq.heappop(heap)
        _, children = _core.split(p.model, s, r)
        for cs, cr in children:
            push(cs, cr)
    tasks = [(s, r) for _, _, _, s, r in sorted(heap)] + done
    return tasks


def _n_unknowns(p: Prepared, eqs: int) -> int:
    rows = p.rows
    vs: set[int] = set()
    while eqs:
        low = eqs & -eqs
        vs.update(rows[low.bit_length() - 1])
        eqs ^= low
    return len(vs)


class _Acc:
    """Merges aggregates coming from tasks or workers (engine keys translated to fault sets)."""

    def __init__(self, ne: int, signature: Callable[[int], int]) -> None:
        self.count = 0
        self.hist = [0] * (ne + 1)
        self.sigs: dict[int, list[int]] = {}
        self.signature = signature

    def add(self, res: tuple[int, list[int], list[tuple[int, int, int, int]]]) -> None:
        count, hist, sigs = res
        self.count += count
        for i, h in enumerate(hist):
            self.hist[i] += h
        for k, c, size, best in sigs:
            key = self.signature(k)
            cur = self.sigs.get(key)
            if cur is None:
                self.sigs[key] = [c, size, best]
            else:
                cur[0] += c
                if size < cur[1] or (size == cur[1] and lex_before(best, cur[2])):
                    cur[1] = size
                    cur[2] = best

    def summary(self, complete: bool, elapsed: float, workers: int, tasks: int) -> MsoSummary:
        sigs = tuple(
            sorted(
                (SignatureEntry(faults=k, count=v[0], smallest=v[2], smallest_size=v[1]) for k, v in self.sigs.items()),
                key=lambda s: (s.smallest_size, s.faults),
            )
        )
        return MsoSummary(
            count=self.count,
            by_equations={i: h for i, h in enumerate(self.hist) if h},
            signatures=sigs,
            complete=complete,
            elapsed_s=elapsed,
            workers=workers,
            tasks=tasks,
        )


class _WorkerStop:
    stopping = False


def _worker_sigint(signum: int, frame: FrameType | None) -> None:
    # first Ctrl-C stops the C loop (it sees KeyboardInterrupt and returns a partial aggregate); later ones
    # (the terminal's and the parent's) are ignored so the partial result can still be sent
    if not _WorkerStop.stopping:
        _WorkerStop.stopping = True
        raise KeyboardInterrupt


def _worker(args: ModelArgs, tasks: Any, results: Any) -> None:
    signal.signal(signal.SIGINT, _worker_sigint)
    model = _model(args)
    agg = _core.agg_new(model)
    interrupted = False
    try:
        while not interrupted:
            item = tasks.get()
            if item is None:
                break
            idx, s, r = item
            interrupted = _core.agg_run(model, agg, s, r, 1)
            if not interrupted:
                results.put(("done", idx))
    except KeyboardInterrupt:
        interrupted = True
    _WorkerStop.stopping = True
    results.put(("result", _core.agg_result(agg), interrupted))


def find_msos(
    structure: Structure | Prepared,
    *,
    workers: int = 2,
    progress: bool = True,
    tasks_per_worker: int = 64,
) -> MsoSummary:
    """Count all MSO sets with their size histogram and fault-signature table, without storing them.

    ``workers`` > 1 splits the search over processes. Ctrl-C stops the search; the summary then has
    ``complete=False`` and covers what was finished.
    """
    t0 = time.perf_counter()
    p = structure if isinstance(structure, Prepared) else prepare(structure)
    workers = max(1, int(workers))
    acc = _Acc(p.ne, p.signature)
    if p.root == 0:
        return acc.summary(True, time.perf_counter() - t0, workers, 0)
    if not p.keyed:
        return _aggregate_here(p, acc, t0)
    tasks = split_tasks(p, 1 if (workers == 1 and not progress) else workers * tasks_per_worker)
    bar = tqdm(total=len(tasks), unit="task", disable=not progress, desc="MSO search", leave=False)
    try:
        run = _run_serial if workers == 1 else _run_parallel
        complete = run(p, tasks, acc, bar, workers)
    finally:
        bar.close()
    return acc.summary(complete, time.perf_counter() - t0, workers, len(tasks))


def _aggregate_here(p: Prepared, acc: _Acc, t0: float) -> MsoSummary:
    """find_msos for models with over 64 distinct fault rows: signatures from the yielded sets, in Python."""
    count = 0
    hist = [0] * (p.ne + 1)
    sigs: dict[int, list[int]] = {}
    complete = True
    try:
        for eqs in iter_msos(p):
            count += 1
            size = eqs.bit_count()
            hist[size] += 1
            f = p.faults_of(eqs)
            cur = sigs.get(f)
            if cur is None:
                sigs[f] = [1, size, eqs]
            else:
                cur[0] += 1
                if size < cur[1] or (size == cur[1] and lex_before(eqs, cur[2])):
                    cur[1], cur[2] = size, eqs
    except KeyboardInterrupt:
        complete = False
    acc.signature = lambda k: k
    acc.add((count, hist, [(f, c, size, best) for f, (c, size, best) in sigs.items()]))
    return acc.summary(complete, time.perf_counter() - t0, 1, 1)


def _run_serial(p: Prepared, tasks: list[tuple[int, int]], acc: _Acc, bar: tqdm[Any], workers: int) -> bool:
    agg = _core.agg_new(p.model)
    complete = True
    try:
        for s, r in tasks:
            if _core.agg_run(p.model, agg, s, r, 1):
                complete = False
                break
            bar.update(1)
    except KeyboardInterrupt:
        complete = False
    acc.add(_core.agg_result(agg))
    return complete


class _ParentStop:
    """The parent's Ctrl-C during a parallel search: the first one is a request, passed on to the workers, which
    send what they finished; the parent keeps collecting (a KeyboardInterrupt in the middle of merging a
    worker's table would lose or double it). A second Ctrl-C stops at once (KeyboardInterrupt)."""

    GRACE_S = 10.0  # how long the parent waits for the workers' partial tables after a request

    def __init__(self, procs: list[Any]) -> None:
        self.procs = procs
        self.requested_at: float | None = None
        self.previous: Any = None
        self.installed = False

    def __enter__(self) -> _ParentStop:
        try:
            self.previous = signal.signal(signal.SIGINT, self._handle)
            self.installed = True
        except ValueError:  # not the main thread: Python delivers no SIGINT here anyway
            pass
        return self

    def __exit__(self, *exc: object) -> None:
        if self.installed:
            signal.signal(signal.SIGINT, self.previous)

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        if self.requested_at is not None:
            raise KeyboardInterrupt
        self.requested_at = time.monotonic()
        for proc in self.procs:
            if proc.is_alive() and proc.pid is not None:
                os.kill(proc.pid, signal.SIGINT)

    def expired(self) -> bool:
        return self.requested_at is not None and time.monotonic() - self.requested_at > self.GRACE_S


def _run_parallel(p: Prepared, tasks: list[tuple[int, int]], acc: _Acc, bar: tqdm[Any], workers: int) -> bool:
    ctx = mp.get_context("fork") if "fork" in mp.get_all_start_methods() else mp.get_context("spawn")
    task_q = ctx.Queue()
    result_q = ctx.Queue()
    for i, (s, r) in enumerate(tasks):
        task_q.put((i, s, r))
    for _ in range(workers):
        task_q.put(None)
    procs = [ctx.Process(target=_worker, args=(p.args, task_q, result_q), daemon=True) for _ in range(workers)]
    for proc in procs:
        proc.start()
    interrupted = False
    finished = 0
    pending = workers
    try:
        with _ParentStop(procs) as stop:
            while pending and not stop.expired():
                try:
                    msg = result_q.get(timeout=0.1)
                except queue.Empty:
                    if not any(proc.is_alive() for proc in procs):
                        raise ComputationError(
                            f"{pending} of {workers} search processes ended without their result "
                            f"(exit codes {[proc.exitcode for proc in procs]})"
                        ) from None
                    continue
                if msg[0] == "done":
                    finished += 1
                    bar.update(1)
                else:
                    acc.add(msg[1])
                    interrupted = interrupted or bool(msg[2])
                    pending -= 1
    finally:
        for proc in procs:
            proc.join(timeout=1.0)
            if proc.is_alive():
                proc.terminate()
                proc.join()
    # a Ctrl-C that came after every task finished loses nothing: the result is then complete
    return not (interrupted or pending > 0 or finished < len(tasks))
