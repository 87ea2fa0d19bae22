"""The order of the generated step function's constant definitions: each one just before its first use.

The generators' step is straight-line float code: `const float t12 = ...;` definitions (common subexpressions,
observer terms, sensitivities) between statements that use them. In the order the common-subexpression pass
writes them, a block's definitions come first and are read much later, so the compiler keeps hundreds of values
alive at once, more than the FPU's registers, and moves them to and from the stack (`scripts/profile_m4.sh --ops
romo_gen_step`). Defined just before its first use (its own operands first, recursively), a value lives shorter.
Only the order changes: every statement is kept as it is, each definition still comes after its operands and
before its uses, and no float operation gets other operands, so the values are the same bit for bit.

The text is the generator's own format (generators.py): one statement per line, `{` and `}` alone on their lines
(a line before `{` that starts with if or else is its header), `#if` ... `#endif` around whole statements. A
definition moves only within its own block (it never enters a nested block or `#if` region, where it would
leave its scope or its condition); statements other than definitions keep their order. A definition never
moves past a statement that assigns a variable it reads (`xh = ...` after `float xh = xp;`), and one that reads
memory through a pointer other than the step's input frame (`in->`, read only) is not moved at all: a statement
it passes might write there.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass

_DEFINITION = re.compile(r"^\s*const float ([A-Za-z_]\w*) = (.*);\s*(?:/\*.*\*/)?$")
_IDENTIFIER = re.compile(r"\b[A-Za-z_]\w*\b")
_COMMENT = re.compile(r"/\*.*?\*/", re.S)
_HEADER = re.compile(r"^\s*(?:if|else)\b")
_ASSIGNED = re.compile(r"^\s*(?:float\s+)?([A-Za-z_]\w*)\s*(?:[-+*/|&^]|<<|>>)?=(?!=)", re.M)


@dataclass(frozen=True)
class _Definition:
    name: str
    line: str

    @property
    def value(self) -> str:
        """Its right-hand side, comments removed."""
        return _COMMENT.sub(" ", self.line.split("=", 1)[1])


@dataclass(frozen=True)
class _Line:
    line: str


@dataclass(frozen=True)
class _Block:
    head: tuple[str, ...]  # its header lines ("if (...)", "{" or "#if ...")
    items: tuple[_Item, ...]
    tail: str  # "}" or "#endif"


_Item = _Definition | _Line | _Block


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def _parse(lines: Sequence[str], i: int, ends: Callable[[str], bool]) -> tuple[list[_Item], int]:
    """The items from line i up to the first line `ends` accepts (its index returned; len(lines) if none)."""
    items: list[_Item] = []
    while i < len(lines) and not ends(lines[i]):
        line = lines[i]
        text = line.strip()
        if text.startswith("#if"):
            inner, j = _parse(lines, i + 1, lambda s: s.strip().startswith("#endif"))
            items.append(_Block((line,), tuple(inner), _closing(lines, j, "#endif")))
            i = j + 1
        elif text == "{":
            inner, j = _parse(lines, i + 1, _closes_at(_indent(line)))
            head: tuple[str, ...] = (line,)
            last = items[-1] if items else None
            if isinstance(last, _Line) and _HEADER.match(last.line):
                items.pop()
                head = (last.line, line)
            items.append(_Block(head, tuple(inner), _closing(lines, j, "}")))
            i = j + 1
        else:
            m = _DEFINITION.match(line)
            movable = m is not None and "->" not in m.group(2).replace("in->", "")
            items.append(_Definition(m.group(1), line) if m and movable else _Line(line))
            i += 1
    return items, i


def _closes_at(depth: int) -> Callable[[str], bool]:
    """The test for the `}` that closes a block opened at indentation `depth`."""
    return lambda s: s.strip() == "}" and _indent(s) == depth


def _closing(lines: Sequence[str], j: int, what: str) -> str:
    if j >= len(lines):
        raise ValueError(f"generated C: a block is not closed by {what!r}")
    return lines[j]


def _text(item: _Item) -> str:
    if isinstance(item, _Block):
        return "\n".join([*item.head, *(_text(x) for x in item.items), item.tail])
    return item.line


def _names_read(text: str, names: dict[str, _Definition]) -> list[str]:
    """The definitions of `names` that `text` reads, in order of first appearance (comments and preprocessor
    lines do not read anything)."""
    code = re.sub(r"^\s*#.*$", " ", _COMMENT.sub(" ", text), flags=re.M)
    return list(dict.fromkeys(n for n in _IDENTIFIER.findall(code) if n in names))


def _ordered(items: Sequence[_Item]) -> list[_Item]:
    """`items` with each definition of this block just before the first item that reads it (nested blocks
    ordered the same way, each on its own)."""
    items = [_Block(x.head, tuple(_ordered(x.items)), x.tail) if isinstance(x, _Block) else x for x in items]
    defs = {x.name: x for x in items if isinstance(x, _Definition)}
    out: list[_Item] = []
    placed: set[str] = set()

    def place(name: str) -> None:
        if name in placed:
            return
        placed.add(name)
        d = defs[name]
        for operand in _names_read(d.value, defs):
            place(operand)
        out.append(d)

    for i, x in enumerate(items):
        if isinstance(x, _Definition):
            continue
        text = _text(x)
        assigned = set(_ASSIGNED.findall(_COMMENT.sub(" ", text)))
        if assigned:  # a definition before it that reads a variable it assigns stays before it
            for d in items[:i]:
                if isinstance(d, _Definition) and d.name not in placed and assigned & set(_IDENTIFIER.findall(d.value)):
                    place(d.name)
        for name in _names_read(text, defs):
            place(name)
        out.append(x)
    for x in items:  # read by nothing after them in this block: where they were, relative to each other
        if isinstance(x, _Definition):
            place(x.name)
    return out


def _lines(items: Sequence[_Item]) -> list[str]:
    out: list[str] = []
    for x in items:
        if isinstance(x, _Block):
            out += [*x.head, *_lines(x.items), x.tail]
        else:
            out.append(x.line)
    return out


def defined_before_use(body: str) -> str:
    """The statements of a generated function body (the text between its braces) with every `const float`
    definition moved to just before its first use in its block."""
    lines = body.split("\n")
    items, end = _parse(lines, 0, lambda s: False)
    assert end == len(lines)
    out = _lines(_ordered(items))
    if sorted(out) != sorted(lines):  # a permutation, nothing lost or repeated
        raise AssertionError("generated C: reordering lost a line")
    return "\n".join(out)
