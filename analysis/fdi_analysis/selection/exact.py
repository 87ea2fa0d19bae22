"""Exact minimum test selection: reduction, bounds, symmetry and a code-assignment search.

(`selection.sat` decides the same questions with a SAT solver on the same code model and is used when
python-sat is installed; the search here is the pure-Python fallback and the reference it is tested
against.)

The problem. Every candidate test is a column T (a set of faults). A set of k selected columns gives every
fault j a *code*: the k-bit vector of the selected tests sensitive to j (the no-fault row has code 0). The
selection reaches the fault matrix of all candidates iff every *required* pair is separated:

- method A: (j, i) is required when some candidate fires for j and not for i; the selection must then make
  code(j) not a subset of code(i);
- method B: {j, i} is required when some candidate fires for exactly one of them; the codes must differ.

Reduction (exact). Faults contained in exactly the same candidates can never be told apart, by any
selection, in either method: they merge into one *item*; faults in no candidate merge with the no-fault
item 0. Columns become bitmasks over items; one column per distinct mask is kept (the cheapest).

Lower bounds. B: k columns give at most 2^k distinct codes, so 2^k >= #items. A: items that are pairwise
required both ways must get pairwise incomparable non-empty codes, and by Sperner's theorem an antichain
in k bits has at most C(k, floor(k/2)) members; the largest such set is a maximum clique (found exactly).

The search (`CodeSearch`) decides "is there a selection with at most k columns" exactly. Instead of
picking columns (the candidate lists are huge) it assigns every item its full k-bit code, items in a fixed
order. The i-th bit of the codes assigned so far is the *trace* of the i-th selected column on the items
seen so far; it must be the trace of some candidate, which is looked up in the set of candidate prefixes
of that length (`_Trie`). Pair constraints are checked the moment the second item of a pair gets its code.
When all items have codes every trace is a whole candidate column, so a leaf is a genuine selection, and
since every selection corresponds to code assignments the search is complete. Fewer than k columns are
covered because a column may repeat. Symmetries are broken with lexicographic-leader constraints, all
with respect to one order of the code matrix (items in search order, bits 0..k-1 inside an item):
permuting the k columns never changes a solution (columns stay sorted), and item permutations that map
the candidate family onto itself (`automorphisms`, found exactly by a small backtracking search and checked
on every column) never change feasibility (or cost, if they preserve costs). Each constraint only removes
assignments that are not the lexicographically least of their orbit, so at least one optimal assignment of
each orbit survives: pruning is exact.

The cost stage runs the same search as branch and bound: the cost of a column is at least the cheapest
candidate that has its current trace as a prefix, so the sum over the k traces bounds every completion.

Incumbents come from greedy and a weighted tabu swap search (`local_search`) over k columns; they only
supply upper bounds. A result is reported as proven only when the lower bound meets the incumbent.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from math import comb

import numpy as np
import numpy.typing as npt
from scipy.sparse import csc_matrix

from fdi_analysis.errors import FdiError
from fdi_analysis.fault_matrix import Method

BoolMatrix = npt.NDArray[np.bool_]
IntArray = npt.NDArray[np.int64]


class SearchTimeoutError(FdiError):
    """The search ran past its deadline; nothing was proven by the interrupted call."""


@dataclass(frozen=True)
class Problem:
    """A reduced selection problem: items (merged faults; item 0 = no fault) and distinct columns."""

    method: Method
    n_items: int
    columns: tuple[int, ...]  # item bitmask per column
    costs: tuple[int, ...]
    item_of_fault: tuple[int, ...]  # fault k (0-based) -> item
    required: tuple[int, ...]  # required[j] = items i with (j, i) required (symmetric for B)

    @property
    def has_requirements(self) -> bool:
        return any(self.required)


def reduce_problem(fault_sets: Sequence[int], costs: Sequence[int], nf: int, method: Method) -> Problem:
    """Merge faults with identical candidate membership into items; keep the cheapest column per mask."""
    membership = [0] * nf
    for t, fs in enumerate(fault_sets):
        for k in range(nf):
            if fs >> k & 1:
                membership[k] |= 1 << t
    item_of_member: dict[int, int] = {0: 0}
    item_of_fault = []
    for k in range(nf):
        item_of_fault.append(item_of_member.setdefault(membership[k], len(item_of_member)))
    n_items = len(item_of_member)
    best: dict[int, int] = {}
    for fs, cost in zip(fault_sets, costs, strict=True):
        mask = 0
        for k in range(nf):
            if fs >> k & 1:
                mask |= 1 << item_of_fault[k]
        if mask and (mask not in best or cost < best[mask]):
            best[mask] = cost
    columns = tuple(sorted(best))
    return Problem(method=method, n_items=n_items, columns=columns, costs=tuple(best[c] for c in columns),
                   item_of_fault=tuple(item_of_fault), required=_required(columns, n_items, method))


def _required(columns: Sequence[int], n_items: int, method: Method) -> tuple[int, ...]:
    everything = (1 << n_items) - 1
    fires_without = [0] * n_items  # items i such that some column holds j and not i
    for col in columns:
        outside = everything & ~col
        for j in range(n_items):
            if col >> j & 1:
                fires_without[j] |= outside
    if method == "A":
        return tuple(fires_without)
    sym = [fires_without[j] for j in range(n_items)]
    for j in range(n_items):
        for i in range(n_items):
            if fires_without[j] >> i & 1:
                sym[i] |= 1 << j
    return tuple(sym)


def required_pairs(problem: Problem) -> list[tuple[int, int]]:
    """Required (j, i) item pairs (for B each unordered pair once, j < i)."""
    out = []
    for j in range(problem.n_items):
        for i in range(problem.n_items):
            if problem.required[j] >> i & 1 and (problem.method == "A" or j < i):
                out.append((j, i))
    return out


def cover_matrix(problem: Problem) -> BoolMatrix:
    """cover[c, e] = column c separates required pair e."""
    cols = np.array(problem.columns, dtype=np.uint64)
    pairs = required_pairs(problem)
    cover = np.zeros((len(cols), len(pairs)), dtype=bool)
    one = np.uint64(1)
    for e, (j, i) in enumerate(pairs):
        bj = (cols >> np.uint64(j)) & one
        bi = (cols >> np.uint64(i)) & one
        cover[:, e] = (bj & ~bi & one).astype(bool) if problem.method == "A" else (bj ^ bi).astype(bool)
    return cover


# ----------------------------------------------------------------------------------------------------
# Lower bound at the root


def _max_clique(adjacency: Sequence[int], candidates: int) -> int:
    """Size of a maximum clique inside `candidates` (bitmask); simple exact branch and bound."""
    best = 0

    def grow(size: int, pool: int) -> None:
        nonlocal best
        if size + pool.bit_count() <= best:
            return
        if not pool:
            best = size
            return
        v = (pool & -pool).bit_length() - 1
        grow(size + 1, pool & adjacency[v])
        grow(size, pool & ~(1 << v))

    grow(0, candidates)
    return best


def root_lower_bound(problem: Problem) -> int:
    """Information-theoretic (B) or Sperner (A) bound on the number of columns."""
    if not problem.has_requirements:
        return 0
    if problem.method == "B":
        return max(1, (problem.n_items - 1).bit_length())
    mutual = [sum(1 << i for i in range(problem.n_items)
                  if problem.required[j] >> i & 1 and problem.required[i] >> j & 1)
              for j in range(problem.n_items)]
    width = _max_clique(mutual, (1 << problem.n_items) - 2)  # item 0 has the empty code, never in an antichain
    k = 1
    while comb(k, k // 2) < width:
        k += 1
    return k


# ----------------------------------------------------------------------------------------------------
# Symmetry


def _map_columns(cols: npt.NDArray[np.uint64], perm: Sequence[int]) -> npt.NDArray[np.uint64]:
    out = np.zeros_like(cols)
    one = np.uint64(1)
    for i, j in enumerate(perm):
        out |= ((cols >> np.uint64(i)) & one) << np.uint64(j)
    return out


def automorphisms(problem: Problem, order: Sequence[int], with_costs: bool,
                  max_nodes: int = 200_000) -> list[list[int]]:
    """Item permutations mapping the column family onto itself (and costs, if asked): stabiliser-chain
    generators relative to `order` (each fixes the items before its base point). Every returned
    permutation is verified on all columns. Candidate images are pruned by co-occurrence counts (with
    costs: also cost-weighted co-occurrence, without which the search spends its budget on targets that
    only fail at the cost check). The backtracking shares a budget of `max_nodes`; stopping
    early only loses symmetry pruning, never exactness."""
    n = problem.n_items
    cols = np.array(problem.columns, dtype=np.uint64)
    sort_idx = np.argsort(cols)
    sorted_cols = cols[sort_idx]
    costs = np.array(problem.costs, dtype=np.int64)[sort_idx]
    freq = [int(((cols >> np.uint64(i)) & np.uint64(1)).sum()) for i in range(n)]
    co = np.zeros((n, n), dtype=np.int64)
    bits = np.array([((cols >> np.uint64(i)) & np.uint64(1)).astype(np.int64) for i in range(n)])
    co[:, :] = bits @ bits.T
    if with_costs:  # cost-weighted co-occurrence is invariant too: prunes targets that only fail on costs
        weighted = (bits * np.array(problem.costs, dtype=np.int64)) @ bits.T
        co = co * (int(weighted.max()) + 1) + weighted

    def verify(perm: list[int]) -> bool:
        mapped = _map_columns(sorted_cols, perm)
        pos = np.searchsorted(sorted_cols, mapped)
        pos[pos >= len(sorted_cols)] = 0
        if not np.array_equal(sorted_cols[pos], mapped):
            return False
        return not with_costs or bool(np.array_equal(costs[pos], costs))

    gens: list[list[int]] = []
    budget = [max_nodes]
    for depth, base in enumerate(order):
        fixed = list(order[:depth])
        for target in order[depth + 1:]:
            if freq[target] != freq[base] or co[base, base] != co[target, target]:
                continue
            if budget[0] <= 0:
                return gens
            perm = _extend(fixed, base, target, co, n, budget, verify)
            if perm is not None:
                gens.append(perm)
    return gens


def _extend(fixed: list[int], base: int, target: int, co: npt.NDArray[np.int64], n: int, budget: list[int],
            verify: Callable[[list[int]], bool]) -> list[int] | None:
    """Backtracking for a co-occurrence-preserving permutation fixing `fixed`, base -> target; every
    visited node and verified leaf is charged to the shared `budget`."""
    perm = [-1] * n
    used = [False] * n
    for f in fixed:
        perm[f] = f
        used[f] = True
    perm[base] = target
    used[target] = True
    rest = [i for i in range(n) if perm[i] < 0]

    def consistent(i: int, img: int) -> bool:
        return all(perm[x] < 0 or co[i, x] == co[img, perm[x]] for x in range(n)) and co[i, i] == co[img, img]

    def rec(idx: int) -> list[int] | None:
        budget[0] -= 1
        if budget[0] < 0:
            return None
        if idx == len(rest):
            budget[0] -= 100  # a verification maps every column
            return list(perm) if verify(perm) else None
        i = rest[idx]
        for img in range(n):
            if not used[img] and consistent(i, img):
                perm[i] = img
                used[img] = True
                found = rec(idx + 1)
                perm[i] = -1
                used[img] = False
                if found is not None:
                    return found
        return None

    if not consistent(base, target):
        return None
    return rec(0)


# ----------------------------------------------------------------------------------------------------
# Code-assignment search


def search_order(problem: Problem) -> list[int]:
    """Item 0 first (its code is forced to 0), then items in the most columns first (ties: index)."""
    freq = [sum(1 for c in problem.columns if c >> i & 1) for i in range(problem.n_items)]
    return sorted(range(problem.n_items), key=lambda i: (i != 0, -freq[i], i))


@dataclass
class _Trie:
    """Candidate prefixes per length, over item positions of the search order; cheapest cost per prefix."""

    prefixes: list[set[int]]
    min_cost: list[dict[int, int]]
    cost_of: dict[int, int]


def _build_trie(problem: Problem, order: Sequence[int]) -> tuple[_Trie, list[int]]:
    position = {item: p for p, item in enumerate(order)}
    n = len(order)
    cols = [sum(1 << position[i] for i in range(problem.n_items) if c >> i & 1) for c in problem.columns]
    prefixes: list[set[int]] = [set() for _ in range(n + 1)]
    min_cost: list[dict[int, int]] = [{} for _ in range(n + 1)]
    for col, cost in zip(cols, problem.costs, strict=True):
        for m in range(n + 1):
            t = col & ((1 << m) - 1)
            prefixes[m].add(t)
            if cost < min_cost[m].get(t, 1 << 62):
                min_cost[m][t] = cost
    cost_of = dict(zip(cols, problem.costs, strict=True))
    return _Trie(prefixes, min_cost, cost_of), cols


@dataclass
class CodeSearch:
    """Exact search over code assignments; see the module docstring. Positions are search-order slots."""

    problem: Problem
    deadline: float
    with_costs: bool = False
    order: list[int] = field(default_factory=list)
    nodes: int = 0

    def __post_init__(self) -> None:
        if not self.order:
            self.order = search_order(self.problem)
        self.trie, self.position_cols = _build_trie(self.problem, self.order)
        n = len(self.order)
        pos = {item: p for p, item in enumerate(self.order)}
        self.not_sub_earlier = [0] * n  # code(p) must not be within code(q), q < p  (A), or differ (B)
        self.not_sup_earlier = [0] * n  # code(q) must not be within code(p), q < p  (A)
        for j in range(self.problem.n_items):
            for i in range(self.problem.n_items):
                if self.problem.required[j] >> i & 1:
                    pj, pi = pos[j], pos[i]
                    if pj > pi:
                        self.not_sub_earlier[pj] |= 1 << pi
                    elif self.problem.method == "A":  # B is symmetric: (i, j) is listed as well
                        self.not_sup_earlier[pi] |= 1 << pj
        gens = automorphisms(self.problem, self.order, self.with_costs)
        self.gens_inv: list[list[int]] = []
        for g in gens:  # item permutation -> inverse permutation on positions
            inv = [0] * n
            for i, img in enumerate(g):
                inv[pos[img]] = pos[i]
            self.gens_inv.append(inv)
        self.best_cost = 1 << 62
        self.best: list[int] | None = None

    # public API -------------------------------------------------------------------------------------

    def feasible(self, k: int) -> list[int] | None:
        """Columns (indices into problem.columns) of a selection with at most k columns, or None."""
        self.k = k
        self._start()
        found = self._rec(0, [0] * k, (1 << max(k - 1, 0)) - 1, tuple(0 for _ in self.gens_inv))
        return None if found is None else self._to_indices(found)

    def cheapest(self, k: int, upper: int) -> list[int] | None:
        """Cheapest selection with at most k columns costing less than `upper`, or None if none is."""
        self.k = k
        self.best_cost, self.best = upper, None
        self._start()
        self._rec(0, [0] * k, (1 << max(k - 1, 0)) - 1, tuple(0 for _ in self.gens_inv))
        return None if self.best is None else self._to_indices(self.best)

    # internals --------------------------------------------------------------------------------------

    def _start(self) -> None:
        n = len(self.order)
        self.codes = [0] * n
        self.keys = [0] * n

    def _to_indices(self, traces: list[int]) -> list[int]:
        index = {c: i for i, c in enumerate(self.position_cols)}
        return sorted({index[t] for t in traces})

    def _bit_options(self, m: int, traces: list[int]) -> list[tuple[int, ...]] | None:
        allowed = self.trie.prefixes[m + 1]
        bit = 1 << m
        opts: list[tuple[int, ...]] = []
        for t in traces:
            o = tuple(v for v, tt in ((0, t), (1, t | bit)) if tt in allowed)
            if not o:
                return None
            opts.append(o)
        return opts

    def _pairs_ok(self, m: int, x: int) -> bool:
        codes = self.codes
        q = self.not_sub_earlier[m]
        method_a = self.problem.method == "A"
        while q:
            low = q & -q
            p = low.bit_length() - 1
            q ^= low
            if (x & ~codes[p] == 0) if method_a else codes[p] == x:
                return False
        q = self.not_sup_earlier[m]
        while q:
            low = q & -q
            p = low.bit_length() - 1
            q ^= low
            if codes[p] & ~x == 0:
                return False
        return True

    def _lex_ok(self, m: int, state: tuple[int, ...]) -> tuple[int, ...] | None:
        """Lex-leader M <= gM for every generator g, compared as far as assigned; -1 = settled."""
        out = []
        for inv, p in zip(self.gens_inv, state, strict=True):
            while 0 <= p <= m:
                q = inv[p]
                if q == p:
                    p += 1
                    continue
                if q > m:
                    break
                a, b = self.keys[p], self.keys[q]
                if a > b:
                    return None
                p = -1 if a < b else p + 1
            out.append(p)
        return tuple(out)

    def _rec(self, m: int, traces: list[int], tied: int, state: tuple[int, ...]) -> list[int] | None:
        self.nodes += 1
        if self.nodes & 0x3FF == 0 and time.monotonic() > self.deadline:
            raise SearchTimeoutError
        n, k = len(self.order), self.k
        if m == n:
            return self._leaf(traces)
        opts = self._bit_options(m, traces)
        if opts is None:
            return None
        bit = 1 << m
        min_cost = self.trie.min_cost[m + 1]
        for combo in itertools.product(*opts):
            if any(tied >> b & 1 and combo[b] > combo[b + 1] for b in range(k - 1)):
                continue  # columns stay lexicographically sorted
            new_traces = [t | bit if v else t for t, v in zip(traces, combo, strict=True)]
            if self.with_costs and sum(min_cost[t] for t in set(new_traces)) >= self.best_cost:
                continue
            x = sum(1 << b for b in range(k) if combo[b])
            if not self._pairs_ok(m, x):
                continue
            self.codes[m] = x
            self.keys[m] = sum(1 << (k - 1 - b) for b in range(k) if combo[b])
            new_state = self._lex_ok(m, state)
            if new_state is None:
                continue
            new_tied = tied
            for b in range(k - 1):
                if combo[b] != combo[b + 1]:
                    new_tied &= ~(1 << b)
            found = self._rec(m + 1, new_traces, new_tied, new_state)
            if found is not None:
                return found
        return None

    def _leaf(self, traces: list[int]) -> list[int] | None:
        if not self.with_costs:
            return list(traces)
        cost = sum(self.trie.cost_of[t] for t in set(traces))
        if cost < self.best_cost:
            self.best_cost, self.best = cost, list(traces)
        return None  # keep searching: branch and bound


# ----------------------------------------------------------------------------------------------------
# Incumbents


def cover_greedy(cover: BoolMatrix) -> list[int]:
    """Classic set-cover greedy: repeatedly the column covering most uncovered elements (an incumbent for
    the count; the paper's greedy orders by size instead and can need several times more columns)."""
    mat = csc_matrix(cover, dtype=np.float32)
    uncovered = np.asarray(cover.any(axis=0), dtype=bool)
    sel: list[int] = []
    while uncovered.any():
        gain = mat @ uncovered.astype(np.float32)
        c = int(np.argmax(gain))
        if gain[c] <= 0:
            break
        sel.append(c)
        uncovered &= ~cover[c]
    return sorted(sel)


def local_search(cover: BoolMatrix, k: int, iterations: int, seed: int,
                 deadline: float = float("inf")) -> list[int] | None:
    """Weighted tabu swap search for k columns covering every element (a heuristic: only finds, never
    proves). Uncovered elements gain weight each step, which steers the search out of local minima. Gives
    up (None) after `iterations` steps or at `deadline` (time.monotonic())."""
    n, m = cover.shape
    if k <= 0 or n < k or m == 0:
        return None
    rng = np.random.default_rng(seed)
    mat = csc_matrix(cover, dtype=np.float32)
    weight = np.ones(m, dtype=np.float32)
    sel = [int(c) for c in rng.choice(n, k, replace=False)]
    count = cover[sel].sum(axis=0).astype(np.int64)
    tabu = np.zeros(n, dtype=np.int64)
    for it in range(iterations):
        uncovered = count == 0
        if not uncovered.any():
            return sel
        if time.monotonic() > deadline:
            return None
        gain_new = mat @ (weight * uncovered)
        best: tuple[float, int, int] | None = None
        for p in range(k):
            only = (count == 1) & cover[sel[p]]
            gain = gain_new + mat @ (weight * only) - float(weight[only].sum())
            gain[sel] = -np.inf
            gain[tabu > it] = -np.inf
            c = int(np.argmax(gain + rng.random(n) * 1e-3))
            if np.isfinite(gain[c]) and (best is None or gain[c] > best[0]):
                best = (float(gain[c]), p, c)
        if best is None:
            return None
        _, p, c = best
        count += cover[c].astype(np.int64) - cover[sel[p]].astype(np.int64)
        tabu[sel[p]] = it + 5
        sel[p] = c
        weight[count == 0] += 1.0
    return None


def cheaper_swaps(cover: BoolMatrix, costs: IntArray, sel: list[int],
                  deadline: float = float("inf")) -> list[int]:
    """Replace columns by cheaper ones while the selection still covers every element (until `deadline`)."""
    sel = list(sel)
    improved = True
    while improved and time.monotonic() < deadline:
        improved = False
        for p in range(len(sel)):
            others = [sel[q] for q in range(len(sel)) if q != p]
            needed: BoolMatrix = cover[others].sum(axis=0) == 0
            ok: BoolMatrix = np.asarray(cover[:, needed].all(axis=1), dtype=bool)
            ok[others] = False
            cand = np.flatnonzero(ok)
            c = int(cand[np.argmin(costs[cand])])
            if costs[c] < costs[sel[p]]:
                sel[p] = c
                improved = True
    return sel
