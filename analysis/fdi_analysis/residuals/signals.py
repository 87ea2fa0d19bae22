"""Filtered signals: the quantities a generator reads, and the filter bank that produces them.

Every measured signal s enters through chains of the firmware's state-variable filters (fdi_svf: output y =
low-passed input, dy = its derivative). A node (s, level, order) is s passed through `level` filters and
differentiated `order` times (order <= level):

    (s, 0, 0)            the raw sample
    (s, L, 0)            y  of the filter fed with (s, L-1, 0)
    (s, L, k), k >= 1    dy of the filter fed with (s, L-1, k-1)

so a filter is identified by its input node and yields (s, L, k) and (s, L, k+1). A residual uses every
signal at one common level (all terms delayed alike, as in the hand-written ARR3/ARR4 of fw/). Node symbols
are real (as the signals are): derivatives of Abs and Max are sign and Heaviside, with no re/im terms.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import sympy

_NAME = re.compile(r"^(?P<s>.+)__L(?P<l>\d+)d(?P<k>\d+)$")


@dataclass(frozen=True, order=True)
class Node:
    signal: str
    level: int
    order: int

    @property
    def symbol(self) -> sympy.Symbol:
        return sympy.Symbol(f"{self.signal}__L{self.level}d{self.order}", real=True)

    def source(self) -> Node | None:
        """The filter input node this node is an output of (None for a raw sample)."""
        if self.level == 0:
            return None
        return Node(self.signal, self.level - 1, max(self.order - 1, 0))

    def derivative(self) -> Node:
        return Node(self.signal, self.level + 1, self.order + 1)

    def at_level(self, level: int) -> Node:
        return Node(self.signal, level, self.order)

    def text(self) -> str:
        if self.level == 0:
            return self.signal
        d = "" if self.order == 0 else ("d/dt " if self.order == 1 else f"d^{self.order}/dt^{self.order} ")
        return f"{d}{self.signal} (filtered x{self.level})"


def node_of(sym: sympy.Basic) -> Node:
    m = _NAME.match(str(sym))
    if m is None:
        raise ValueError(f"{sym} is not a filtered-signal symbol")
    return Node(m["s"], int(m["l"]), int(m["k"]))


def nodes_in(expr: sympy.Expr) -> set[Node]:
    """The filtered-signal nodes of `expr` (other symbols, such as an observer state, are not nodes)."""
    return {node_of(s) for s in expr.free_symbols if _NAME.match(str(s))}


def raw(signal: str) -> sympy.Symbol:
    return Node(signal, 0, 0).symbol


def derivative(expr: sympy.Expr, inverses: dict[sympy.Symbol, sympy.Expr],
               constants: frozenset[sympy.Symbol] = frozenset(),
               rates: dict[sympy.Symbol, sympy.Symbol] | None = None) -> sympy.Expr:
    """d/dt of an expression of nodes by the chain rule; each node's derivative is a filter output.
    `inverses` maps placeholders v = 1/c (divisions by signals) to c: d/dt v = -v^2 d/dt c; `constants` are
    symbols with no derivative (the faults, steps of constant size), except those `rates` maps to a symbol of
    their rate (a fault's drift: what the residual sees of a fault it reaches only through a derivative)."""
    total: sympy.Expr = sympy.Integer(0)
    for sym in sorted(expr.free_symbols, key=str):
        if sym in constants:
            if rates is not None and sym in rates:
                total += sympy.diff(expr, sym) * rates[sym]
            continue
        if sym in inverses:
            total += sympy.diff(expr, sym) * (-(sym**2) * derivative(inverses[sym], inverses, constants, rates))
        else:
            total += sympy.diff(expr, sym) * node_of(sym).derivative().symbol
    return total


def align(expr: sympy.Expr) -> tuple[sympy.Expr, int]:
    """Lift every node to the highest level present (extra filters), so all terms carry the same delay."""
    nodes = nodes_in(expr)
    level = max((n.level for n in nodes), default=0)
    return expr.xreplace({n.symbol: n.at_level(level).symbol for n in nodes}), level


def filter_bank(nodes: set[Node], signal_order: list[str]) -> list[Node]:
    """The filters (by input node) that produce `nodes`, inputs before the filters fed by them."""
    need: set[Node] = set()
    todo = [n for n in nodes if n.level > 0]
    while todo:
        src = todo.pop().source()
        if src is not None and src not in need:
            need.add(src)
            if src.level > 0:
                todo.append(src)
    return sorted(need, key=lambda n: (n.level, signal_order.index(n.signal), n.order))


def readable(expr: sympy.Expr) -> str:
    """An expression over filtered-signal nodes with the signals' names (psidot_m__L1d0 -> psidot_m)."""
    names = {n.symbol: sympy.Symbol(n.signal if n.order == 0 else f"d{n.order}_{n.signal}") for n in nodes_in(expr)}
    return str(sympy.sstr(expr.xreplace(names)))
