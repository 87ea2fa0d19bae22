"""A log's data frames as columns (times, identifiers, lengths, payloads): what the ECU bindings take in one C call
(`Ecu.process_arrays`), without one Python object per frame.

`read_log_columns` gives exactly the columns of `frame_columns(read_log(path))`, and `read_columns_checked` the
same malformed lines as `read_log_checked`. A candump log (``.log``, ``.log.gz``) is parsed here with numpy,
several times faster than python-can's reader (`host_tools/bench/bench_can.py` prints both), line by line: every
line in the plain form that python-can and ``candump -L`` write (a classic data frame) is parsed here; every
other line (a remote, error or CAN FD frame, a tab, a blank line, an unusual timestamp, a garbage line, a last
line cut off) goes through python-can's reader (`fdi_host.can.logs.read_text_lines`), so that its frame, or its
count as malformed, is always python-can's; the frames are merged back in line order. Any other format goes
through `read_log`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from operator import attrgetter
from pathlib import Path

import can
import numpy as np
from numpy.typing import NDArray

from fdi_host.can.frame import Frame
from fdi_host.can.logs import (
    LogIssues,
    Tally,
    check_suffix,
    log_format,
    read_bytes,
    read_log_checked,
    read_text_lines,
)


@dataclass(frozen=True)
class FrameColumns:
    """Data frames in file order: times [s] on the log's clock, identifiers, payload lengths (bytes, as in the
    file) and payloads (n x 8 bytes, zero padded; a payload's bytes past the 8th are not kept)."""

    t: NDArray[np.float64]
    frame_id: NDArray[np.int64]
    dlc: NDArray[np.int64]
    data: NDArray[np.uint8]

    def __len__(self) -> int:
        return int(self.t.size)

    def select(self, keep: NDArray[np.bool_] | NDArray[np.intp]) -> FrameColumns:
        """The frames where keep is true (or at the indices in keep, in their order)."""
        return FrameColumns(self.t[keep], self.frame_id[keep], self.dlc[keep], self.data[keep])

    def concat(self, other: FrameColumns) -> FrameColumns:
        """These frames, then `other`'s."""
        return FrameColumns(np.concatenate((self.t, other.t)), np.concatenate((self.frame_id, other.frame_id)),
                            np.concatenate((self.dlc, other.dlc)), np.concatenate((self.data, other.data)))


@dataclass(frozen=True)
class ColumnsRead:
    """A log's data frames as columns and what was skipped (`fdi_host.can.logs.LogIssues`)."""

    columns: FrameColumns
    issues: LogIssues


def frame_columns(frames: Sequence[Frame]) -> FrameColumns:
    """The columns of `frames`: a few passes of map/numpy over the objects, no Python code per frame."""
    n = len(frames)
    t = np.fromiter(map(attrgetter("timestamp"), frames), np.float64, n)
    ids = np.fromiter(map(attrgetter("frame_id"), frames), np.int64, n)
    datas = list(map(attrgetter("data"), frames))
    dlc = np.fromiter(map(len, datas), np.int64, n)
    if not (dlc == 8).all():
        datas = [d if len(d) == 8 else d[:8].ljust(8, b"\0") for d in datas]
    data = np.frombuffer(b"".join(datas), np.uint8).reshape(n, 8)
    return FrameColumns(t, ids, dlc, data)


def read_log_columns(path: str | Path, strict: bool = False) -> FrameColumns:
    """The data frames of a log as columns, the same as `frame_columns(read_log(path))`; a LogError (from
    read_log) for a file that cannot be read."""
    return read_columns_checked(path, strict).columns


def read_columns_checked(path: str | Path, strict: bool = False) -> ColumnsRead:
    """The data frames of a log as columns and the malformed lines skipped, the same as `read_log_checked` (with
    `strict` the first malformed line is a `MalformedLogError`)."""
    p = check_suffix(path)
    if log_format(p) in (".log", ".log.gz") and p.is_file():
        return _read_candump(p, strict)
    read = read_log_checked(p, strict)
    return ColumnsRead(frame_columns(read.frames), read.issues)


def _read_candump(p: Path, strict: bool) -> ColumnsRead:
    """A candump log: its plain lines parsed here, the others by python-can, merged in line order."""
    raw, cut = read_bytes(p)
    tally = Tally(str(p), strict)
    fast = candump_lines(raw)
    others = list(read_text_lines(can.CanutilsLogReader, fast.other, tally))
    if cut is not None and (raw.endswith(b"\n") or not raw):  # as read_log_checked
        tally.add(raw.count(b"\n") + 1, None, cut)
    columns = fast.columns
    if others:
        lines = np.concatenate((fast.line, np.array([n for n, _ in others], np.int64)))
        merged = columns.concat(frame_columns([f for _, f in others]))
        columns = merged.select(np.argsort(lines, kind="stable"))
    return ColumnsRead(columns, tally.issues())


# the bytes a plain candump line may hold: printable ASCII (the newline ends it)
_PRINTABLE = bytes(range(0x20, 0x7F)) + b"\n"
_NOT_PRINTABLE = np.ones(256, np.bool_)
_NOT_PRINTABLE[0x20:0x7F] = False
_HEX = np.full(256, 0xFF, np.uint8)
_HEX[np.frombuffer(b"0123456789", np.uint8)] = np.arange(10, dtype=np.uint8)
_HEX[np.frombuffer(b"abcdef", np.uint8)] = np.arange(10, 16, dtype=np.uint8)
_HEX[np.frombuffer(b"ABCDEF", np.uint8)] = np.arange(10, 16, dtype=np.uint8)
_DIRECTIONS = np.frombuffer(b"RTrt", np.uint8)
_ID_MAX_DIGITS = 8
_DATA_MAX_DIGITS = 16  # 8 bytes: a classic frame
_TS_WIDTH = 24
_FRAME_WIDTH = _ID_MAX_DIGITS + 1 + _DATA_MAX_DIGITS
_EXACT_INT = 2**53  # a decimal N / 10^d with N below this is float(its text) after one float division
_POW10 = np.array([float(10**d) for d in range(17)])  # exact: 10^d < 2^53 for d <= 15, 10^16 = 2^16 5^16 exact too

Mask = NDArray[np.bool_]
Ints = NDArray[np.int64]


@dataclass(frozen=True)
class CandumpLines:
    """A candump log split by `candump_lines`: the frames of its plain lines (`columns`, their 1-based line
    numbers in `line`), every other line for python-can (`other`: number and text with its line end), and whether
    the whole file is plain (`uniform`: every line plain, with the same number of tokens, ending in a newline)."""

    columns: FrameColumns
    line: Ints
    other: list[tuple[int, str]]
    uniform: bool


def _lines_with(positions: Ints, newline: Ints) -> Ints:
    """How many of the byte `positions` each line holds (a line ends at its newline)."""
    counts: Ints = np.bincount(np.searchsorted(newline, positions), minlength=newline.size).astype(np.int64)
    return counts


def _gather(padded: NDArray[np.uint8], start: Ints, end: Ints, width: int) -> tuple[NDArray[np.uint8], Ints, Mask]:
    """Each token padded[start:end] as a row of `width` bytes (0 past its end), its length, and whether it is one
    (not empty, not longer than width; the row of one that is not is garbage). `padded` ends in at least `width`
    bytes past the last token."""
    length = end - start
    ok = (length >= 1) & (length <= width)
    length = np.where(ok, length, 1)
    rows = np.lib.stride_tricks.sliding_window_view(padded, width)[start]  # a copy: row i = padded[start[i]:][:width]
    rows[np.arange(width)[None, :] >= length[:, None]] = 0
    return rows, length, ok


def _timestamps(tok: NDArray[np.uint8], length: Ints) -> tuple[NDArray[np.float64], Mask]:
    """"(digits.digits)" -> its value, exactly float() of the text: N / 10^d with N < 2^53 is one correctly rounded
    division of two exact floats; and which rows have that form (not: signs, exponents, more digits)."""
    n, width = tok.shape
    rows = np.arange(n)
    ok = (tok[:, 0] == ord("(")) & (tok[rows, length - 1] == ord(")")) & (length >= 4)
    inner = np.zeros_like(tok)
    inner[:, : width - 1] = tok[:, 1:]
    inner[rows, np.maximum(length - 2, 0)] = 0  # the closing parenthesis
    dot = inner == ord(".")
    digit = (inner >= ord("0")) & (inner <= ord("9"))
    ok &= (dot.sum(axis=1) == 1) & ((digit | dot) == (inner != 0)).all(axis=1)
    dot_at = np.argmax(dot, axis=1)
    ok &= (dot_at >= 1) & (dot_at < length - 3) & (digit.sum(axis=1) <= 16)  # digits on both sides, at most 16
    value = np.zeros(n, np.int64)
    for k in range(width - 1):
        d = digit[:, k] & ok
        value = np.where(d, value * 10 + (inner[:, k].astype(np.int64) - ord("0")), value)
    ok &= value < _EXACT_INT
    decimals = np.clip(length - 3 - dot_at, 0, 16)  # characters after the point, before ")"
    exact: NDArray[np.float64] = value.astype(np.float64) / _POW10[decimals]
    return exact, ok


def _frames(tok: NDArray[np.uint8], length: Ints) -> tuple[Ints, Ints, NDArray[np.uint8], Mask]:
    """"ID#DATA" (1-8 hex digits, then 0-16 hex digits in pairs) -> identifier, length, payload, and which rows
    have that form (not: a remote, error or CAN FD frame, or anything else)."""
    n, width = tok.shape
    sharp = tok == ord("#")
    ok = sharp.sum(axis=1) == 1
    at = np.argmax(sharp, axis=1)
    nib = _HEX[tok]
    used = tok != 0
    ok &= ~((nib == 0xFF) & used & ~sharp).any(axis=1)  # hex digits only (not a remote frame's R, a second #, ...)
    n_data = length - at - 1
    ok &= (at >= 1) & (at <= _ID_MAX_DIGITS) & (n_data % 2 == 0) & (n_data <= _DATA_MAX_DIGITS)
    ids = np.zeros(n, np.int64)
    for k in range(_ID_MAX_DIGITS):
        ids = np.where(k < at, (ids << 4) | nib[:, k].astype(np.int64), ids)
    ok &= ids <= 0x1FFFFFFF  # error frames (CAN_ERR_FLAG) and flag bits: python-can's reader decides
    dlc = np.clip(n_data // 2, 0, 8)
    cols = np.minimum(at[:, None] + 1 + np.arange(_DATA_MAX_DIGITS)[None, :], width - 1)
    digits = np.take_along_axis(nib, cols, axis=1)  # uint8, as nib
    data = (digits[:, 0::2] << 4) | digits[:, 1::2]
    data[np.arange(8)[None, :] >= dlc[:, None]] = 0
    return ids, dlc, data.astype(np.uint8, copy=False), ok  # already uint8: no copy (the annotation for mypy)


def _empty_columns() -> FrameColumns:
    return FrameColumns(np.zeros(0, np.float64), np.zeros(0, np.int64), np.zeros(0, np.int64),
                        np.zeros((0, 8), np.uint8))


def candump_lines(raw: bytes) -> CandumpLines:
    """A candump log's lines: the plain ones parsed to columns, the rest handed out as text for python-can.
    Plain: printable ASCII, "(time) channel frame" with an optional direction R or T, the tokens one space apart,
    ended by a newline (a last line without one may be cut off: python-can's reader and the malformed count
    decide)."""
    if not raw:
        return CandumpLines(_empty_columns(), np.zeros(0, np.int64), [], False)
    terminated = raw.endswith(b"\n")
    buf = np.frombuffer(raw if terminated else raw + b"\n", np.uint8)
    newline = np.flatnonzero(buf == ord("\n")).astype(np.int64)
    starts = np.concatenate(([0], newline[:-1] + 1)).astype(np.int64)
    space_at = np.flatnonzero(buf == ord(" ")).astype(np.int64)
    n_space = _lines_with(space_at, newline)
    cand = (n_space == 2) | (n_space == 3)
    if raw.translate(None, _PRINTABLE):  # a byte other than printable ASCII and newlines: its line is not plain
        odd = np.flatnonzero(_NOT_PRINTABLE[buf] & (buf != ord("\n"))).astype(np.int64)
        cand &= _lines_with(odd, newline) == 0
    if not terminated:
        cand[-1] = False
    idx = np.flatnonzero(cand)
    spaces_before = np.concatenate(([0], np.cumsum(n_space)[:-1])).astype(np.int64)
    columns, ok = _parse_lines(buf, starts[idx], newline[idx], spaces_before[idx], n_space[idx] == 3, space_at)
    plain = np.zeros(newline.size, np.bool_)
    plain[idx[ok]] = True
    other = [(int(i) + 1, raw[starts[i]: newline[i] + 1].decode("utf-8", errors="replace")) for i in
             np.flatnonzero(~plain)]
    uniform = terminated and bool(plain.all()) and bool((n_space == n_space[0]).all())
    return CandumpLines(columns.select(ok), idx[ok].astype(np.int64) + 1, other, uniform)


def _parse_lines(buf: NDArray[np.uint8], starts: Ints, newline: Ints, spaces_before: Ints, four: Mask,
                 space_at: Ints) -> tuple[FrameColumns, Mask]:
    """The candidate lines (two or three spaces, printable) parsed: their columns and which of them are plain."""
    if not starts.size:
        return _empty_columns(), np.zeros(0, np.bool_)
    sp0 = space_at[spaces_before]
    sp1 = space_at[spaces_before + 1]
    sp2 = np.where(four, space_at[np.minimum(spaces_before + 2, space_at.size - 1)], newline)
    ok = sp1 > sp0 + 1  # a channel
    ok &= ~four | ((sp2 + 2 == newline) & np.isin(buf[newline - 1], _DIRECTIONS))  # the direction: one character
    padded = np.concatenate((buf, np.zeros(max(_TS_WIDTH, _FRAME_WIDTH), np.uint8)))  # once, for both gathers
    ts_tok, ts_len, ts_ok = _gather(padded, starts, sp0, _TS_WIDTH)
    fr_tok, fr_len, fr_ok = _gather(padded, sp1 + 1, sp2, _FRAME_WIDTH)
    t, t_ok = _timestamps(ts_tok, ts_len)
    ids, dlc, data, f_ok = _frames(fr_tok, fr_len)
    return FrameColumns(t, ids, dlc, data), ok & ts_ok & fr_ok & t_ok & f_ok


def parse_candump(raw: bytes) -> FrameColumns | None:
    """A plain candump log -> its columns; None for anything else (`read_log_columns` then reads the lines this
    parser does not take with python-can). Plain: printable ASCII lines, each ending in a newline, each "(time)
    channel frame" with an optional direction R or T, the tokens one space apart, every line with the same number
    of tokens."""
    lines = candump_lines(raw)
    return lines.columns if lines.uniform else None
