"""A log's data frames as columns (times, identifiers, lengths, payloads): what the ECU bindings take in one C call
(`Ecu.process_arrays`), without one Python object per frame.

`read_log_columns` gives exactly the columns of `frame_columns(read_log(path))`. A candump log (``.log``) in the
plain form that python-can and ``candump -L`` write, classic data frames only, is parsed here with numpy, several
times faster than python-can's reader (`host_tools/bench/bench_can.py` prints both); any other log, and any
candump log with something else in it (a remote, error or CAN FD frame, a tab, a blank line, an unusual
timestamp, a malformed line), goes through `read_log`, so that the result, and the error for a bad file, are
always python-can's.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from operator import attrgetter
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from fdi_host.can.frame import Frame
from fdi_host.can.logs import check_suffix, read_log


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

    def select(self, keep: NDArray[np.bool_]) -> FrameColumns:
        """The frames where keep is true."""
        return FrameColumns(self.t[keep], self.frame_id[keep], self.dlc[keep], self.data[keep])


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


def read_log_columns(path: str | Path) -> FrameColumns:
    """The data frames of a log as columns, the same as `frame_columns(read_log(path))`; a LogError (from
    read_log) for a file that cannot be read."""
    p = check_suffix(path)
    if p.suffix == ".log" and p.is_file():
        columns = parse_candump(p.read_bytes())
        if columns is not None:
            return columns
    return frame_columns(read_log(p))


# the bytes a plain candump log may hold: printable ASCII, one space between tokens, a newline after each line
_PRINTABLE = bytes(range(0x20, 0x7F)) + b"\n"
_HEX = np.full(256, 0xFF, np.uint8)
_HEX[np.frombuffer(b"0123456789", np.uint8)] = np.arange(10, dtype=np.uint8)
_HEX[np.frombuffer(b"abcdef", np.uint8)] = np.arange(10, 16, dtype=np.uint8)
_HEX[np.frombuffer(b"ABCDEF", np.uint8)] = np.arange(10, 16, dtype=np.uint8)
_DIRECTIONS = np.frombuffer(b"RTrt", np.uint8)
_ID_MAX_DIGITS = 8
_DATA_MAX_DIGITS = 16  # 8 bytes: a classic frame
_EXACT_INT = 2**53  # a decimal N / 10^d with N below this is float(its text) after one float division
_POW10 = np.array([float(10**d) for d in range(17)])  # exact: 10^d < 2^53 for d <= 15, 10^16 = 2^16 5^16 exact too


def _gather(padded: NDArray[np.uint8], start: NDArray[np.int64], end: NDArray[np.int64],
            width: int) -> tuple[NDArray[np.uint8], NDArray[np.int64]] | None:
    """Each token padded[start:end] as a row of `width` bytes (0 past its end) and its length; None when a token is
    empty or longer than width. `padded` ends in at least `width` bytes past the last token."""
    length = end - start
    if length.size and (int(length.min()) < 1 or int(length.max()) > width):
        return None
    rows = np.lib.stride_tricks.sliding_window_view(padded, width)[start]  # a copy: row i = padded[start[i]:][:width]
    rows[np.arange(width)[None, :] >= length[:, None]] = 0
    return rows, length


def _timestamps(tok: NDArray[np.uint8], length: NDArray[np.int64]) -> NDArray[np.float64] | None:
    """"(digits.digits)" -> its value, exactly float() of the text: N / 10^d with N < 2^53 is one correctly rounded
    division of two exact floats. None for any other form (signs, exponents, more digits)."""
    n, width = tok.shape
    rows = np.arange(n)
    if not ((tok[:, 0] == ord("(")).all() and (tok[rows, length - 1] == ord(")")).all()):
        return None
    inner = np.zeros_like(tok)
    inner[:, : width - 1] = tok[:, 1:]
    inner[rows, length - 2] = 0  # the closing parenthesis
    dot = inner == ord(".")
    digit = (inner >= ord("0")) & (inner <= ord("9"))
    if not ((dot.sum(axis=1) == 1).all() and ((digit | dot) == (inner != 0)).all()):
        return None
    dot_at = np.argmax(dot, axis=1)
    n_digits = digit.sum(axis=1)
    if (dot_at < 1).any() or (dot_at >= length - 3).any() or (n_digits > 16).any():
        return None  # digits on both sides of the point, at most 16 of them
    value = np.zeros(n, np.int64)
    for k in range(width - 1):
        d = digit[:, k]
        value = np.where(d, value * 10 + (inner[:, k].astype(np.int64) - ord("0")), value)
    if (value >= _EXACT_INT).any():
        return None
    decimals = length - 3 - dot_at  # characters after the point, before ")"
    exact: NDArray[np.float64] = value.astype(np.float64) / _POW10[decimals]
    return exact


def _frames(tok: NDArray[np.uint8], length: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.int64],
                                                                          NDArray[np.uint8]] | None:
    """"ID#DATA" (1-8 hex digits, then 0-16 hex digits in pairs) -> identifier, length, payload. None for a
    remote, error or CAN FD frame or anything else."""
    n, width = tok.shape
    sharp = tok == ord("#")
    if not (sharp.sum(axis=1) == 1).all():
        return None
    at = np.argmax(sharp, axis=1)
    nib = _HEX[tok]
    used = tok != 0
    if ((nib == 0xFF) & used & ~sharp).any():
        return None  # not a hex digit (a remote frame's R, a second #, ...)
    n_data = length - at - 1
    if (at < 1).any() or (at > _ID_MAX_DIGITS).any() or (n_data % 2 != 0).any() or (n_data > _DATA_MAX_DIGITS).any():
        return None
    ids = np.zeros(n, np.int64)
    for k in range(_ID_MAX_DIGITS):
        ids = np.where(k < at, (ids << 4) | nib[:, k].astype(np.int64), ids)
    if (ids > 0x1FFFFFFF).any():
        return None  # error frames (CAN_ERR_FLAG) and flag bits: python-can's reader decides
    dlc = n_data // 2
    cols = np.minimum(at[:, None] + 1 + np.arange(_DATA_MAX_DIGITS)[None, :], width - 1)
    digits = np.take_along_axis(nib, cols, axis=1)  # uint8, as nib
    data = (digits[:, 0::2] << 4) | digits[:, 1::2]
    data[np.arange(8)[None, :] >= dlc[:, None]] = 0
    return ids, dlc, data.astype(np.uint8, copy=False)  # already uint8: no copy (the annotation for mypy)


def parse_candump(raw: bytes) -> FrameColumns | None:
    """A plain candump log -> its columns; None for anything this parser does not take (the caller then reads the
    file with python-can). Plain: printable ASCII lines, each ending in a newline, each "(time) channel frame"
    with an optional direction R or T, the tokens one space apart, every line with the same number of tokens."""
    if not raw or not raw.endswith(b"\n") or raw.translate(None, _PRINTABLE):
        return None
    if b"  " in raw or b" \n" in raw or b"\n " in raw or b"\n\n" in raw or raw.startswith(b" "):
        return None
    buf = np.frombuffer(raw, np.uint8)
    newline = np.flatnonzero(buf == ord("\n"))
    space = np.flatnonzero(buf == ord(" "))
    n = int(newline.size)
    per_line = np.bincount(np.searchsorted(newline, space), minlength=n)
    k = int(per_line[0]) + 1
    if k not in (3, 4) or not (per_line == k - 1).all():
        return None
    starts = np.concatenate(([0], newline[:-1] + 1)).astype(np.int64)
    sp = space.reshape(n, k - 1).astype(np.int64)
    if k == 4:
        if not (sp[:, 2] + 2 == newline).all() or not np.isin(buf[newline - 1], _DIRECTIONS).all():
            return None  # the direction: one character
        frame_end = sp[:, 2]
    else:
        frame_end = newline.astype(np.int64)
    ts_width, frame_width = 24, _ID_MAX_DIGITS + 1 + _DATA_MAX_DIGITS
    padded = np.concatenate((buf, np.zeros(max(ts_width, frame_width), np.uint8)))  # once, for both gathers
    ts = _gather(padded, starts, sp[:, 0], ts_width)
    fr = _gather(padded, sp[:, 1] + 1, frame_end, frame_width)
    if ts is None or fr is None:
        return None
    t = _timestamps(*ts)
    frames = _frames(*fr)
    if t is None or frames is None:
        return None
    ids, dlc, data = frames
    return FrameColumns(t, ids, dlc, data)
