"""Exact minimum test selection as SAT (count) and incremental SAT (cost) on a symmetry-reduced code model.

The model is the code assignment of `selection.exact` (k selected tests; every item gets the k-bit code of
the tests sensitive to it; required pairs must be separated), written as CNF and given to CaDiCaL
(PyPI `python-sat`):

- *Column membership.* Every one of the k test columns must be a candidate. The candidate family is
  compiled once into a reduced ordered decision diagram (a few hundred nodes on the full vertical model,
  56,784 columns) and copied per test with one variable per node (node reached -> its child on the
  chosen branch is reached; the false terminal is never reached).
- *Interchangeable items.* Items i, j whose transposition maps the candidate family onto itself
  (`interchangeable_classes`) are never given individual code variables: a class C of m items is one set
  variable u[C, v] per code v ("some item of C has code v"), exactly m of them true. Since the family is
  closed under permuting C, membership of a column depends only on the other items and on how many items
  of C it holds, so the diagram branches on that count (a unary counter over the u variables of the codes
  holding the test). This removes the m! relabellings of each class from the search exactly. Only classes
  of at least `MIN_CLASS` items are treated so (and only for k <= `MAX_CLASS_K`); smaller classes keep
  item rows, adjacent in the row order, with a lex-leader constraint per adjacent transposition. Measured
  on the full vertical model, method A, k = 7 (unsatisfiable): count rows for the class of 5 items only
  10-15 s; for the classes of 3 as well, undecided after 60 s; no count rows, undecided after 200 s.
- *Remaining symmetry.* Lexicographic-leader constraints vec(M) <= vec(gM), all with respect to one order
  of the (derived) matrix M: rows = singleton items, then the per-test counts of each class; columns =
  tests. They hold for adjacent column swaps (tests sorted) and for every family automorphism that maps
  classes onto classes (e.g. wheel swaps). The lex-least member of every orbit satisfies all of them, so
  they only remove symmetric copies: unsatisfiable stays unsatisfiable, and a proof of "no selection with k
  tests" is a proof.
- *Cost.* Leaves of the diagram carry the column cost (a multi-terminal diagram); each test's cost is
  order-encoded and summed by a capped partial-sum ladder, and an incremental linear search asks for a
  selection cheaper than the best so far until the solver proves none exists (full vertical model, A:
  eight improving steps of 0.2-3.5 s from 706 to 602 unknowns, then 13-20 s for the final refutation).
  Costs usually break most symmetry, so classes and automorphisms are recomputed cost-preserving.
- *Processes.* Each solver call runs in a forked child (python-sat's CaDiCaL cannot be interrupted; a
  process can be killed at the deadline), which also lets `selection.optimal` run the cost search beside
  the last count refutation on the second core.

Every returned selection is verified against the problem (membership and every required pair) before it
is used; every "no selection with k tests" is only as strong as the solver's completeness, which
`tests/analysis/test_properties_selection_sat.py` checks against brute force on random small instances.
"""

from __future__ import annotations

import itertools
import multiprocessing
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import cast

import numpy as np
import numpy.typing as npt

from fdi_analysis.errors import ComputationError, FdiError
from fdi_analysis.selection.exact import Problem, automorphisms, search_order

try:  # optional: without python-sat the exact stages fall back to the code search (and may stay unproven)
    from pysat.solvers import Solver

    HAVE_SAT = True
except ImportError:  # pragma: no cover - exercised only without python-sat
    HAVE_SAT = False

SAT_SOLVER = "cadical195"
MIN_CLASS = 4  # classes of at least this many items become count rows (smaller ones: item rows + lex)
MAX_CLASS_K = 10  # count rows need one variable per code (2^k) and clauses per comparable code pair (3^k)


class SatUnavailableError(FdiError, RuntimeError):
    """python-sat is not installed."""


class SatTimeoutError(FdiError):
    """The solver ran past its deadline; nothing was proven by the interrupted call."""


# ----------------------------------------------------------------------------------------------------
# Symmetry of the candidate family


def _mapped_columns_equal(sorted_cols: npt.NDArray[np.uint64], costs: npt.NDArray[np.int64] | None,
                          perm: Sequence[int]) -> bool:
    one = np.uint64(1)
    mapped = np.zeros_like(sorted_cols)
    for i, j in enumerate(perm):
        mapped |= ((sorted_cols >> np.uint64(i)) & one) << np.uint64(j)
    pos = np.searchsorted(sorted_cols, mapped)
    pos[pos >= len(sorted_cols)] = 0
    if not np.array_equal(sorted_cols[pos], mapped):
        return False
    return costs is None or bool(np.array_equal(costs[pos], costs))


def interchangeable_classes(problem: Problem, with_costs: bool) -> list[list[int]]:
    """Partition of items 1..n-1 into classes whose every transposition maps the column family onto itself
    (and preserves costs, if asked). Transpositions that are automorphisms generate the full symmetric
    group on each class, so membership of a column depends only on its count inside each class."""
    n = problem.n_items
    cols = np.array(problem.columns, dtype=np.uint64)
    order = np.argsort(cols)
    sorted_cols = cols[order]
    costs = np.array(problem.costs, dtype=np.int64)[order] if with_costs else None
    freq = [int(((cols >> np.uint64(i)) & np.uint64(1)).sum()) for i in range(n)]
    parent = list(range(n))

    def find(x: int) -> int:
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for i in range(1, n):
        for j in range(i + 1, n):
            if find(i) == find(j) or freq[i] != freq[j]:
                continue
            perm = list(range(n))
            perm[i], perm[j] = j, i
            if _mapped_columns_equal(sorted_cols, costs, perm):
                parent[find(j)] = find(i)
    groups: dict[int, list[int]] = {}
    for i in range(1, n):
        groups.setdefault(find(i), []).append(i)
    return sorted(groups.values(), key=lambda g: (len(g), g))


# ----------------------------------------------------------------------------------------------------
# Quotient rows and the multi-valued decision diagram of the family


@dataclass(frozen=True)
class Rows:
    """Rows of the derived code matrix: singleton items (0/1 per test) and classes (count per test)."""

    singles: tuple[int, ...]
    classes: tuple[tuple[int, ...], ...]

    @property
    def n_rows(self) -> int:
        return len(self.singles) + len(self.classes)

    def domain(self, r: int) -> int:
        """Number of values of row r (2 for a singleton item, m + 1 for a class of m items)."""
        return 2 if r < len(self.singles) else len(self.classes[r - len(self.singles)]) + 1

    def meta(self, column: int) -> tuple[int, ...]:
        out = [column >> i & 1 for i in self.singles]
        out += [sum(column >> i & 1 for i in c) for c in self.classes]
        return tuple(out)


def make_rows(problem: Problem, classes: Sequence[Sequence[int]], min_class: int) -> Rows:
    """Items of classes smaller than `min_class` are rows of their own (search order, members of a class
    adjacent); larger classes are count rows (largest first)."""
    rank = {item: r for r, item in enumerate(search_order(problem))}
    small = sorted((c for c in classes if len(c) < min_class), key=lambda c: min(rank[i] for i in c))
    singles = tuple(i for c in small for i in sorted(c, key=lambda i: rank[i]))
    multi = tuple(tuple(c) for c in sorted((c for c in classes if len(c) >= min_class), key=lambda c: (-len(c), c)))
    return Rows(singles=singles, classes=multi)


@dataclass
class Diagram:
    """Reduced ordered multi-valued diagram: node id -> (row, child per value); ids 0 = false terminal,
    1.. = leaves (one per leaf value), then inner nodes. `root` may be a terminal."""

    nodes: dict[int, tuple[int, tuple[int, ...]]]
    leaves: dict[int, int]  # leaf id -> value (cost, or 0 when costs are ignored)
    root: int


def build_diagram(rows: Rows, columns: Sequence[int], values: Sequence[int]) -> Diagram:
    """Diagram of {meta(column)}, the leaf of a column holding its value. Every meta tuple must have one
    value (checked): the family is closed under the classes, and values are class-invariant."""
    leaf_value: dict[tuple[int, ...], int] = {}
    for col, val in zip(columns, values, strict=True):
        key = rows.meta(col)
        if leaf_value.setdefault(key, val) != val:
            raise ValueError("column values are not invariant under the interchangeable classes")
    leaves: dict[int, int] = {}
    leaf_id: dict[int, int] = {}
    for v in sorted(set(leaf_value.values())):
        leaf_id[v] = len(leaf_id) + 1
        leaves[leaf_id[v]] = v
    next_id = len(leaf_id) + 1
    current: dict[tuple[int, ...], int] = {key: leaf_id[v] for key, v in leaf_value.items()}
    nodes: dict[int, tuple[int, tuple[int, ...]]] = {}
    unique: dict[tuple[int, tuple[int, ...]], int] = {}
    for r in range(rows.n_rows - 1, -1, -1):
        children: dict[tuple[int, ...], list[int]] = {}
        dom = rows.domain(r)
        for key, nid in current.items():
            children.setdefault(key[:r], [0] * dom)[key[r]] = nid
        nxt: dict[tuple[int, ...], int] = {}
        for prefix, ch in children.items():
            kids = tuple(ch)
            if all(c == kids[0] for c in kids):
                nxt[prefix] = kids[0]
                continue
            known = unique.get((r, kids))
            if known is None:
                known = next_id
                next_id += 1
                unique[(r, kids)] = known
                nodes[known] = (r, kids)
            nxt[prefix] = known
        current = nxt
    root = current.get((), 0)
    return Diagram(nodes=nodes, leaves=leaves, root=root)


# ----------------------------------------------------------------------------------------------------
# CNF


@dataclass
class _Cnf:
    n_vars: int = 0
    clauses: list[list[int]] = field(default_factory=list)

    def var(self) -> int:
        self.n_vars += 1
        return self.n_vars

    def add(self, clause: list[int]) -> None:
        self.clauses.append(clause)

    def counter(self, inputs: Sequence[int], cap: int) -> list[int]:
        """Unary outputs o[s-1] <-> (at least s inputs true), s = 1..cap (both directions)."""
        prev: list[int] = []  # prev[s-1] = at least s of the inputs so far
        for x in inputs:
            cur = []
            for s in range(1, cap + 1):
                o = self.var()
                keep = prev[s - 1] if s - 1 < len(prev) else None  # at least s before
                carry = prev[s - 2] if s >= 2 and s - 2 < len(prev) else (None if s >= 2 else 0)
                # o <-> keep or (carry and x); carry 0 = true (s = 1), None = false
                if keep is not None:
                    self.add([-keep, o])
                if carry == 0:
                    self.add([-x, o])
                elif carry is not None:
                    self.add([-carry, -x, o])
                back = [-o] + ([keep] if keep is not None else [])
                if carry == 0:
                    self.add([*back, x])
                elif carry is not None:
                    self.add([*back, x])
                    self.add([*back, carry])
                else:
                    self.add(back)
                cur.append(o)
            prev = cur
        if not prev:
            prev = []
            for _ in range(cap):
                o = self.var()
                self.add([-o])
                prev.append(o)
        return prev

    def lex_leq(self, xs: Sequence[int], ys: Sequence[int]) -> None:
        """xs <= ys lexicographically (literal lists of equal length, false < true)."""
        prev: int | None = None
        for x, y in zip(xs, ys, strict=True):
            if x == y:
                continue
            base = [] if prev is None else [-prev]
            self.add([*base, -x, y])
            e = self.var()
            if prev is not None:
                self.add([-e, prev])
            self.add([-e, -x, y])
            self.add([-e, x, -y])
            self.add([*base, x, y, e])
            self.add([*base, -x, -y, e])
            prev = e


@dataclass
class CodeModel:
    """CNF of "a selection with at most k columns" (see the module docstring); `leaf_lits[t]` maps each leaf
    value of test t's diagram to the literal "test t reaches a leaf with that value"."""

    problem: Problem
    k: int
    rows: Rows
    cnf: _Cnf
    single_bits: list[list[int]]  # [test][singleton row] -> var
    class_codes: list[dict[int, int]]  # [class] -> code -> var
    leaf_lits: list[dict[int, int]]

    def decode(self, model: Sequence[int]) -> list[int]:
        """Selected columns (item bitmasks, one per test) from a satisfying assignment."""
        true = {lit for lit in model if lit > 0}
        cols = [0] * self.k
        for t in range(self.k):
            for r, item in enumerate(self.rows.singles):
                if self.single_bits[t][r] in true:
                    cols[t] |= 1 << item
        for c, cls in enumerate(self.rows.classes):
            codes = sorted(v for v, var in self.class_codes[c].items() if var in true)
            for item, code in zip(cls, codes, strict=True):
                for t in range(self.k):
                    if code >> t & 1:
                        cols[t] |= 1 << item
        return cols


def _code_literals(model_bits: list[int], code: int, k: int) -> list[int]:
    return [model_bits[t] if code >> t & 1 else -model_bits[t] for t in range(k)]


@dataclass(frozen=True)
class SatProblem:
    """A reduced problem with the part of its SAT encoding that does not depend on k: the interchangeable
    classes, the rows, the diagram and the row permutations of the family automorphisms used for lex-leader
    constraints (`build_model` adds the k test slots)."""

    problem: Problem
    with_costs: bool
    classes: tuple[tuple[int, ...], ...]
    rows: Rows
    diagram: Diagram
    row_perms: tuple[tuple[int, ...], ...]


def sat_problem(problem: Problem, with_costs: bool, min_class: int = MIN_CLASS) -> SatProblem:
    classes = tuple(tuple(c) for c in interchangeable_classes(problem, with_costs))
    rows = make_rows(problem, classes, min_class)
    values = problem.costs if with_costs else [0] * len(problem.columns)
    diagram = build_diagram(rows, problem.columns, values)
    return SatProblem(problem, with_costs, classes, rows, diagram, _row_permutations(problem, rows, classes,
                                                                                     with_costs))


def build_model(sp: SatProblem, k: int) -> CodeModel:
    """The CNF for "at most k tests" (exactly k test slots; a column may repeat). ValueError if k < 1."""
    if k < 1:
        raise ValueError("k must be at least 1")
    problem, rows = sp.problem, sp.rows
    cnf = _Cnf()
    ns = len(rows.singles)
    single_bits = [[cnf.var() for _ in range(ns)] for _ in range(k)]
    required = problem.required
    method_a = problem.method == "A"
    n_codes = 1 << k
    class_codes: list[dict[int, int]] = []
    for cls in rows.classes:
        rep = cls[0]
        allowed = [v for v in range(n_codes) if v or not (required[rep] & 1 or required[0] >> rep & 1)]
        class_codes.append({v: cnf.var() for v in allowed})
    # the row values per test: singleton bits, class counts (unary)
    row_lits: list[list[list[int]]] = []  # [test][row] -> literal list (1 literal, or m unary literals)
    for t in range(k):
        lits: list[list[int]] = [[b] for b in single_bits[t]]
        for c, cls in enumerate(rows.classes):
            lits.append(cnf.counter([var for v, var in class_codes[c].items() if v >> t & 1], len(cls)))
        row_lits.append(lits)
    for c, cls in enumerate(rows.classes):  # exactly m codes per class
        total = cnf.counter(list(class_codes[c].values()), len(cls) + 1)
        cnf.add([total[len(cls) - 1]])
        cnf.add([-total[len(cls)]])
    leaf_lits = [_diagram_clauses(cnf, sp.diagram, rows, row_lits[t]) for t in range(k)]
    _pair_clauses(cnf, problem, rows, k, single_bits, class_codes, method_a)
    _symmetry_clauses(cnf, rows, k, row_lits, sp.row_perms)
    return CodeModel(problem, k, rows, cnf, single_bits, class_codes, leaf_lits)


def _value_condition(lits: list[int], value: int, domain: int) -> list[int]:
    """Literals whose disjunction is "row value != value" (negated condition, for clause building)."""
    if domain == 2:
        return [-lits[0]] if value else [lits[0]]
    out = []
    if value >= 1:
        out.append(-lits[value - 1])  # at least value
    if value < domain - 1:
        out.append(lits[value])  # not at least value + 1
    return out


def _diagram_clauses(cnf: _Cnf, diagram: Diagram, rows: Rows, lits: list[list[int]]) -> dict[int, int]:
    node_var = {nid: cnf.var() for nid in diagram.nodes}
    leaf_var = {lid: cnf.var() for lid in diagram.leaves}
    if diagram.root == 0:
        cnf.add([])
        return {}
    root = node_var.get(diagram.root, leaf_var.get(diagram.root, 0))
    cnf.add([root])
    for nid, (r, kids) in diagram.nodes.items():
        x = node_var[nid]
        for value, child in enumerate(kids):
            cond = _value_condition(lits[r], value, rows.domain(r))
            if child == 0:
                cnf.add([-x, *cond])
            else:
                cnf.add([-x, *cond, node_var.get(child, leaf_var.get(child, 0))])
    out: dict[int, int] = {}
    for lid, var in leaf_var.items():
        out[diagram.leaves[lid]] = var
    return out


def _pair_clauses(cnf: _Cnf, problem: Problem, rows: Rows, k: int, single_bits: list[list[int]],
                  class_codes: list[dict[int, int]], method_a: bool) -> None:
    """Every required pair separated: (j, i) in A: code(j) not within code(i); in B: codes differ."""
    srow = {item: r for r, item in enumerate(rows.singles)}
    crow = {item: c for c, cls in enumerate(rows.classes) for item in cls}
    req = problem.required
    n = problem.n_items
    for j in range(n):
        for i in range(n):
            if not req[j] >> i & 1 or (not method_a and j > i) or j == i:
                continue
            if j in crow and i in crow and crow[j] == crow[i]:
                first_pair = j == rows.classes[crow[j]][0] and i == rows.classes[crow[j]][1]
                if method_a and first_pair:  # the class's codes form an antichain (once per class)
                    codes = class_codes[crow[j]]
                    for v, var in codes.items():
                        for w, wvar in codes.items():
                            if v != w and v & ~w == 0:
                                cnf.add([-var, -wvar])
                continue
            _pair(cnf, k, j, i, srow, crow, single_bits, class_codes, method_a, rows)


def _pair(cnf: _Cnf, k: int, j: int, i: int, srow: dict[int, int], crow: dict[int, int],
          single_bits: list[list[int]], class_codes: list[dict[int, int]], method_a: bool, rows: Rows) -> None:
    def code_bits(item: int) -> list[int] | None:
        return [single_bits[t][srow[item]] for t in range(k)] if item in srow else None

    bj, bi = code_bits(j), code_bits(i)
    if j in crow and i in crow:  # two classes: only the first items carry the constraint (uniform)
        if j != rows.classes[crow[j]][0] or i != rows.classes[crow[i]][0]:
            return
        for v, var in class_codes[crow[j]].items():
            for w, wvar in class_codes[crow[i]].items():
                if (method_a and v & ~w == 0) or (not method_a and v == w):
                    cnf.add([-var, -wvar])
        return
    if j in crow or i in crow:
        cls_item, single = (j, i) if j in crow else (i, j)
        if cls_item != rows.classes[crow[cls_item]][0]:
            return
        bs = code_bits(single) if single != 0 else None
        for v, var in class_codes[crow[cls_item]].items():
            if bs is None:  # against the no-fault item: code(j) != 0 (A and B alike)
                if v == 0:
                    cnf.add([-var])
                continue
            if not method_a:
                cnf.add([-var, *(-bs[t] if v >> t & 1 else bs[t] for t in range(k))])
            elif cls_item == j:  # v not within code(single)
                cnf.add([-var, *(-bs[t] for t in range(k) if v >> t & 1)])
            else:  # code(single) not within v
                cnf.add([-var, *(bs[t] for t in range(k) if not v >> t & 1)])
        return
    if i == 0 or j == 0:
        other = bj if i == 0 else bi
        assert other is not None
        cnf.add(list(other))  # non-empty code
        return
    assert bj is not None and bi is not None
    clause = []
    for t in range(k):
        y = cnf.var()
        clause.append(y)
        if method_a:
            cnf.add([-y, bj[t]])
            cnf.add([-y, -bi[t]])
        else:
            cnf.add([-y, bj[t], bi[t]])
            cnf.add([-y, -bj[t], -bi[t]])
    cnf.add(clause)


def _row_permutations(problem: Problem, rows: Rows, classes: Sequence[Sequence[int]],
                      with_costs: bool) -> tuple[tuple[int, ...], ...]:
    """Row permutations (src row per row) of the transpositions of adjacent item rows of one class and of
    the family automorphisms (`automorphisms`) that map classes onto classes; identities dropped."""
    n_rows = rows.n_rows
    row_of: dict[int, int] = {item: r for r, item in enumerate(rows.singles)}
    for c, cls in enumerate(rows.classes):
        for item in cls:
            row_of[item] = len(rows.singles) + c
    perms: list[list[int]] = []
    for r in range(len(rows.singles) - 1):
        a, b = rows.singles[r], rows.singles[r + 1]
        if any(a in c and b in c for c in classes):
            swap = list(range(problem.n_items))
            swap[a], swap[b] = b, a
            perms.append(swap)
    perms += automorphisms(problem, search_order(problem), with_costs)
    out: list[tuple[int, ...]] = []
    for g in perms:
        src = [-1] * n_rows  # (gM)[row of g(i)] = M[row of i]
        ok = True
        for item in range(1, problem.n_items):
            r, s = row_of[item], row_of[g[item]]
            if src[s] not in (-1, r):
                ok = False
                break
            src[s] = r
        if not ok or -1 in src or src == list(range(n_rows)):
            continue
        if any(rows.domain(src[s]) != rows.domain(s) for s in range(n_rows)) or tuple(src) in out:
            continue
        out.append(tuple(src))
    return tuple(out)


def _symmetry_clauses(cnf: _Cnf, rows: Rows, k: int, row_lits: list[list[list[int]]],
                      row_perms: Sequence[Sequence[int]]) -> None:
    """Lex-leader constraints on vec(M) = row-major over rows (singletons, class counts), tests inside."""

    def vec(row_perm: Sequence[int] | None, col_perm: Sequence[int] | None) -> list[int]:
        out: list[int] = []
        for r in range(rows.n_rows):
            src_r = r if row_perm is None else row_perm[r]
            for t in range(k):
                out.extend(row_lits[t if col_perm is None else col_perm[t]][src_r])
        return out

    base = vec(None, None)
    for t in range(k - 1):  # adjacent test swaps: tests sorted
        swap = list(range(k))
        swap[t], swap[t + 1] = t + 1, t
        cnf.lex_leq(base, vec(None, swap))
    for perm in row_perms:
        cnf.lex_leq(base, vec(perm, None))


# ----------------------------------------------------------------------------------------------------
# Verification and solving


def separates(problem: Problem, cols: Sequence[int]) -> bool:
    """True when `cols` (item bitmasks) are all candidates and separate every required pair."""
    family = set(problem.columns)
    if any(c not in family for c in cols):
        return False
    n = problem.n_items
    code = [sum(1 << t for t, c in enumerate(cols) if c >> i & 1) for i in range(n)]
    for j in range(n):
        for i in range(n):
            if problem.required[j] >> i & 1:
                if problem.method == "A" and code[j] & ~code[i] == 0:
                    return False
                if problem.method == "B" and code[j] == code[i]:
                    return False
    return True


@dataclass
class ChildResult:
    """What a solver process reported: its progress messages and, if it finished, its answer."""

    progress: list[object]
    finished: bool
    answer: object = None


class _Child:
    """`work(report)` running in a forked child process; `report(x)` streams progress to the parent.
    python-sat's solvers cannot all be interrupted, a process always can: `collect` kills the child at its
    deadline, `cancel` at once; Ctrl-C in the parent kills it as well (the process is a daemon)."""

    def __init__(self, work: Callable[[Callable[[object], None]], object]) -> None:
        ctx = multiprocessing.get_context("fork")
        self.receiver, sender = ctx.Pipe(duplex=False)

        def child() -> None:
            try:
                answer = work(lambda x: sender.send(("progress", x)))
                sender.send(("done", answer))
            except Exception as exc:  # reported to the parent, which raises it
                sender.send(("error", repr(exc)))

        self.proc = ctx.Process(target=child, daemon=True)
        self.proc.start()
        sender.close()
        self.result = ChildResult(progress=[], finished=False)

    def collect(self, deadline: float) -> ChildResult:
        out = self.result
        try:
            while not out.finished and self.receiver.poll(max(0.0, deadline - time.monotonic())):
                kind, value = self.receiver.recv()
                if kind == "progress":
                    out.progress.append(value)
                elif kind == "error":
                    raise RuntimeError(f"SAT solver failed: {value}")
                else:
                    out.finished, out.answer = True, value
        except EOFError as exc:
            raise ComputationError(f"SAT solver process ended without an answer (exit code "
                                   f"{self.proc.exitcode})") from exc
        finally:
            self.cancel()
        return out

    def cancel(self) -> None:
        if self.proc.is_alive():
            self.proc.kill()
        self.proc.join()
        self.receiver.close()


def _in_child(work: Callable[[Callable[[object], None]], object], deadline: float) -> ChildResult:
    if deadline - time.monotonic() <= 0:
        return ChildResult(progress=[], finished=False)
    return _Child(work).collect(deadline)


def _solve_cnf(clauses: list[list[int]]) -> list[int] | None:
    with Solver(name=SAT_SOLVER, bootstrap_with=clauses) as solver:
        return list(solver.get_model() or []) if solver.solve() else None


@dataclass
class _CostBound:
    """Order-encoded sum of the k leaf costs: `reach[b]` is true whenever the sum is at least b (sums at
    or above `cap` share the threshold `cap`); assuming -reach[b] bounds the sum below b."""

    reach: dict[int, int]

    def assumption(self, bound: int) -> list[int]:
        """Assumptions for "sum <= bound" (none needed when no threshold lies above the bound)."""
        above = [b for b in self.reach if b > bound]
        return [-self.reach[min(above)]] if above else []


def _cost_bound(model: CodeModel, cap: int) -> _CostBound:
    cnf = model.cnf
    values = sorted({v for lits in model.leaf_lits for v in lits if v > 0})
    prev: dict[int, int | None] = {0: None}  # threshold -> literal (None = true)
    for t in range(model.k):
        at_least = {v: cnf.var() for v in values}  # the test's cost is at least v
        for value, leaf in model.leaf_lits[t].items():
            for v in values:
                if v <= value:
                    cnf.add([-leaf, at_least[v]])
        cur: dict[int, int | None] = {}
        for b, lit in prev.items():
            for v in [0, *values]:
                target = min(b + v, cap)
                if target not in cur:
                    cur[target] = cnf.var()
                tvar = cur[target]
                assert tvar is not None
                cnf.add([*([] if lit is None else [-lit]), *([] if v == 0 else [-at_least[v]]), tvar])
        thresholds = sorted(cur)
        for lo, hi in itertools.pairwise(thresholds):  # at least hi -> at least lo
            hv, lv = cur[hi], cur[lo]
            assert hv is not None and lv is not None
            cnf.add([-hv, lv])
        prev = cur
    return _CostBound({b: lit for b, lit in prev.items() if lit is not None})


@dataclass
class PendingCost:
    """A cost search running in a child process."""

    selector: SatSelector
    k: int
    child: _Child

    def collect(self, deadline: float) -> tuple[list[int] | None, bool]:
        """(cheapest selection found or None, proven); waits until the search ends or the deadline."""
        result = self.child.collect(deadline)
        if not result.progress:
            return None, result.finished
        return self.selector._checked(cast(list[int], result.progress[-1])), result.finished

    def cancel(self) -> None:
        self.child.cancel()


class SatSelector:
    """Exact decisions on one reduced problem; its k-independent `SatProblem`s are cached."""

    def __init__(self, problem: Problem, min_class: int = MIN_CLASS) -> None:
        if not HAVE_SAT:
            raise SatUnavailableError("python-sat is not installed")
        self.problem = problem
        self.min_class = min_class
        self._sat_problems: dict[tuple[bool, bool], SatProblem] = {}
        self._cost_of = dict(zip(problem.columns, problem.costs, strict=True))

    def _sat_problem(self, with_costs: bool, k: int) -> SatProblem:
        """The encoding's k-independent part for k tests: count rows only while 2^k codes per class stay
        small."""
        key = (with_costs, k <= MAX_CLASS_K)
        if key not in self._sat_problems:
            min_class = self.min_class if key[1] else self.problem.n_items + 1
            self._sat_problems[key] = sat_problem(self.problem, with_costs, min_class)
        return self._sat_problems[key]

    def feasible(self, k: int, deadline: float) -> list[int] | None:
        """Indices of distinct columns of a selection with at most k columns, or None when none exists.
        SatTimeoutError at the deadline."""
        model = build_model(self._sat_problem(False, k), k)
        clauses = model.cnf.clauses
        result = _in_child(lambda _report: _solve_cnf(clauses), deadline)
        if not result.finished:
            raise SatTimeoutError
        found = cast(list[int] | None, result.answer)
        return None if found is None else self._checked(model.decode(found))

    def cheapest(self, k: int, upper: int, deadline: float) -> tuple[list[int] | None, bool]:
        """The cheapest selection with k test slots costing less than `upper` (each slot pays its column's
        cost), as (column indices or None when none is cheaper, proven). Linear search from above: every
        model found tightens the bound, the final unsatisfiable call proves the last one optimal. At the
        deadline: (best found or None, False). Meant for the minimum k, where the k columns are
        distinct and the slot costs are the selection's cost."""
        return self.cheapest_start(k, upper).collect(deadline)

    def cheapest_start(self, k: int, upper: int) -> PendingCost:
        """`cheapest` started in the background (model built in the child); `collect` or `cancel` it."""
        cached = self._sat_problems.get((True, k <= MAX_CLASS_K))
        cost_of = self._cost_of
        problem = self.problem
        min_class = self.min_class if k <= MAX_CLASS_K else problem.n_items + 1

        def work(report: Callable[[object], None]) -> object:
            model = build_model(cached or sat_problem(problem, True, min_class), k)
            bound = _cost_bound(model, upper)
            limit = upper - 1
            with Solver(name=SAT_SOLVER, bootstrap_with=model.cnf.clauses) as solver:
                while solver.solve(assumptions=bound.assumption(limit)):
                    cols = model.decode(list(solver.get_model() or []))
                    report(cols)
                    limit = sum(cost_of[c] for c in cols) - 1
            return None

        return PendingCost(self, k, _Child(work))

    def _checked(self, cols: list[int]) -> list[int]:
        if not separates(self.problem, cols):
            raise AssertionError("SAT model decoded to an invalid selection (encoding bug)")
        index = {c: i for i, c in enumerate(self.problem.columns)}
        return sorted({index[c] for c in cols})
