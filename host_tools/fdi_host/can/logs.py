"""CAN log files through python-can's readers and writers, in every format the installed python-can reads and
writes, chosen by the file's extension: ``.log`` (candump), ``.asc`` (Vector ASCII), ``.blf`` (Vector binary),
``.trc`` (PEAK), ``.csv``, ``.mf4`` (ASAM MDF, with the optional ``asammdf`` package) and ``.db`` (SQLite); the
text formats also gzip-compressed (``drive.log.gz``, ``drive.asc.gz``, ...).

Reading keeps data frames only (error and remote frames are dropped). A malformed line or frame is what the
ECU does with a bad frame: counted and skipped, never the end of the log (`LogIssues`: how many, the first few
line numbers and why); ``strict=True`` makes the first one a `MalformedLogError` naming the file and the line.

Malformed, in a text log: a line python-can's reader fails on (a garbage line, ``could not convert string to
float``), a frame whose payload is shorter or longer than its length code (an odd number of hex digits, a line
cut inside the payload), and a last line without its line end (a recording cut off; every writer ends its lines).
Lines python-can's reader skips as meta data (comments, events, statistics, blank lines) are not malformed. In a
binary log (``.blf``, ``.mf4``, ``.db``): a record python-can fails on ends the log there (the rest of the file
cannot be found again): one malformed record, the frames before it kept; a ``.blf`` shorter than its header says
(a copy or recording cut off) is one malformed record too. A file with no frame at all before such an error is a
`LogError` (not a log of that format).

How a text log is read past a bad line: python-can's reader gets the lines through a counter (the line number of
a frame or an error is the counter's), and when it raises on a line the same reader is iterated again from the
next line (its state, the header it read, is kept); a reader that re-reads a header when iterated again first
gets one filler line it consumes as such (`_RESUME_FILLER`).
"""

from __future__ import annotations

import gzip
import logging
import os
import threading
import time
import zlib
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import can
from can.io import MESSAGE_READERS, MESSAGE_WRITERS
from can.io.generic import MessageReader, TextIOMessageReader

from fdi_host.can.frame import Frame
from fdi_host.errors import FdiHostError

_PREFERRED = (".log", ".asc", ".blf", ".trc", ".csv", ".mf4", ".db")
# every format python-can both reads and writes (in the installed version), the common ones first
LOG_SUFFIXES: tuple[str, ...] = (*(s for s in _PREFERRED if s in MESSAGE_READERS and s in MESSAGE_WRITERS),
                                 *sorted(set(MESSAGE_READERS) & set(MESSAGE_WRITERS) - set(_PREFERRED)))
TEXT_SUFFIXES: tuple[str, ...] = tuple(s for s in LOG_SUFFIXES if issubclass(MESSAGE_READERS[s], TextIOMessageReader))
GZIP_SUFFIX = ".gz"  # a text log compressed: drive.log.gz (python-can writes and reads them)
OPTIONAL_PACKAGES = {".mf4": ("asammdf", "pip install 'python-can[mf4]'")}  # formats that need another package
TRUNCATED = "truncated: the last line has no line end"
MAX_REPORTED = 5  # malformed lines kept with their line number and reason (all are counted)

# What a reader that re-reads its header when iterated again consumes as that header, so that no line of the
# log is lost: ASCReader and CSVReader take one line (a blank one here), TRCReader reads ";" comment lines up to
# the first frame line. CanutilsLogReader reads no header (None: nothing to hand out).
_RESUME_FILLER: dict[type[MessageReader], str | None] = {
    can.CanutilsLogReader: None, can.ASCReader: "\n", can.CSVReader: "\n", can.TRCReader: ";\n"}


class LogError(FdiHostError, ValueError):
    """A log file that cannot be written or read (format, missing file, corrupt content)."""


class MalformedLogError(LogError):
    """A malformed line or frame in a log read with ``strict=True``; the message names the file and the line."""


@dataclass(frozen=True)
class Malformed:
    """One malformed line or record: its line number in a text log, or in a binary one the number of frames read
    before it; and why."""

    line: int | None
    after_frame: int | None
    reason: str

    def where(self) -> str:
        return f"line {self.line}" if self.line is not None else f"the record after frame {self.after_frame}"


@dataclass(frozen=True)
class LogIssues:
    """What was skipped while reading a log: `skipped` malformed lines or records, the first `MAX_REPORTED` of
    them with their line numbers (`first`). Empty (false) for a clean log."""

    path: str
    skipped: int = 0
    first: tuple[Malformed, ...] = ()

    def __bool__(self) -> bool:
        return self.skipped > 0

    @property
    def lines(self) -> tuple[int, ...]:
        """The line numbers of the first malformed lines (text logs)."""
        return tuple(m.line for m in self.first if m.line is not None)

    def summary(self) -> str:
        """One line: ``drive.log: 3 malformed lines skipped (lines 7, 12, 40; line 7: could not ...)``."""
        if not self:
            return f"{self.path}: no malformed line"
        first = self.first[0] if self.first else Malformed(None, None, "malformed")
        what = "line" if first.line is not None else "record"
        if self.skipped == 1:
            return f"{self.path}: 1 malformed {what} skipped ({first.where()}: {first.reason})"
        where = ", ".join(str(m.line) if m.line is not None else m.where() for m in self.first)
        more = ", ..." if self.skipped > len(self.first) else ""
        return (f"{self.path}: {self.skipped} malformed {what}s skipped ({what + 's ' if first.line else ''}"
                f"{where}{more}; {first.where()}: {first.reason})")

    def error(self) -> str:
        """The first malformed line as one line for ``--strict``: ``drive.log: line 7: malformed (...)``."""
        first = self.first[0] if self.first else Malformed(None, None, "malformed")
        return f"{self.path}: {first.where()}: malformed ({first.reason})"


@dataclass(frozen=True)
class LogRead:
    """A log's data frames in file order and what was skipped."""

    frames: list[Frame]
    issues: LogIssues


# ---------------------------------------------------------------------------------------------- formats
def log_format(path: str | Path) -> str | None:
    """The log format of a path by its extension (``.log``, ``.blf``, ``.asc.gz``, ...), None if it is not one
    (case-insensitive, as python-can)."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == GZIP_SUFFIX:
        inner = Path(p.stem).suffix.lower()
        return inner + GZIP_SUFFIX if inner in TEXT_SUFFIXES else None
    return suffix if suffix in LOG_SUFFIXES else None


def is_log(path: str | Path) -> bool:
    return log_format(path) is not None


CSV_HEADER = b"timestamp,arbitration_id,"  # the first line of python-can's .csv logs
SQLITE_HEADER = b"SQLite format 3\x00"


def looks_like_log(path: str | Path) -> bool:
    """Whether a file found in a folder is a CAN log: a log extension, and for the formats other files share
    (.csv, .db) python-can's header (a table of residuals or a database of something else is not a log)."""
    fmt = log_format(path)
    if fmt is None:
        return False
    head = {".csv": CSV_HEADER, ".csv.gz": CSV_HEADER, ".db": SQLITE_HEADER}.get(fmt)
    if head is None:
        return True
    try:
        opener = gzip.open if fmt.endswith(GZIP_SUFFIX) else open
        with opener(path, "rb") as f:
            return bool(f.read(len(head)) == head)
    except (OSError, EOFError):
        return False


def formats_text() -> str:
    """The formats for a message: ``.log, .asc, ... (text formats also as .gz)``."""
    return f"{', '.join(LOG_SUFFIXES)} (the text formats {'/'.join(TEXT_SUFFIXES)} also gzip-compressed, .log.gz)"


def check_suffix(path: str | Path) -> Path:
    """The path, or LogError when python-can has no reader/writer for its extension."""
    p = Path(path)
    if log_format(p) is None:
        raise LogError(f"{p}: unsupported log format {''.join(p.suffixes[-2:]) or p.name!r}; use one of "
                       f"{formats_text()}")
    return p


def _missing_package(p: Path, fmt: str, exc: BaseException) -> LogError | None:
    """A LogError saying which optional package a format needs, when `exc` says it is missing."""
    need = OPTIONAL_PACKAGES.get(fmt.removesuffix(GZIP_SUFFIX))
    if need is None or not isinstance(exc, (ImportError, NotImplementedError)):
        return None
    package, install = need
    return LogError(f"{p}: {fmt} logs need the optional package {package}, which is not installed ({install})")


# ---------------------------------------------------------------------------------------------- writing
def write_log(frames: Iterable[Frame], path: str | Path) -> int:
    """Write frames with python-can's writer for the file's extension. Returns the number written."""
    p = check_suffix(path)
    fmt = log_format(p) or ""
    p.parent.mkdir(parents=True, exist_ok=True)
    if fmt == ".db":
        p.unlink(missing_ok=True)  # python-can's SqliteWriter appends to an existing table
    n = 0
    try:
        writer = can.Logger(str(p))
    except Exception as exc:  # python-can raises ValueError, NotImplementedError (a missing package), OSError
        raise _missing_package(p, fmt, exc) or LogError(f"{p}: cannot write a {fmt} log ({type(exc).__name__}: "
                                                     f"{exc})") from exc
    with writer:
        for f in frames:
            writer.on_message_received(f.to_can())
            n += 1
        if isinstance(writer, can.SqliteWriter):
            _drain_sqlite(writer)
    if isinstance(writer, can.SqliteWriter) and writer.num_frames != n:
        raise LogError(f"{p}: python-can's SqliteWriter wrote {writer.num_frames} of {n} frames")
    return n


def _drain_sqlite(writer: can.SqliteWriter, timeout: float = 60.0) -> None:
    """Wait until python-can's SqliteWriter thread has taken every queued frame: its ``stop`` writes the batch
    in hand and drops what is still queued (python-can 4.6: only the first ~500 frames of a burst were written)."""
    deadline = time.monotonic() + timeout
    while not writer.buffer.empty() and time.monotonic() < deadline:
        time.sleep(0.005)


# ---------------------------------------------------------------------------------------------- reading
def read_log(path: str | Path, strict: bool = False) -> list[Frame]:
    """The data frames of a log, in file order; malformed lines skipped (`read_log_checked` tells which)."""
    return read_log_checked(path, strict).frames


def read_log_checked(path: str | Path, strict: bool = False) -> LogRead:
    """The data frames of a log in file order and the malformed lines or records skipped; with `strict` the first
    one is a `MalformedLogError`. LogError for a file that is missing or not a log of its format."""
    p = check_suffix(path)
    if not p.is_file():
        raise LogError(f"{p}: no such file")
    fmt = log_format(p) or ""
    reader_type = MESSAGE_READERS[fmt.removesuffix(GZIP_SUFFIX)]
    tally = Tally(str(p), strict)
    if issubclass(reader_type, TextIOMessageReader):
        raw, cut = read_bytes(p)
        frames = [f for _, f in read_text_lines(reader_type, numbered_lines(raw), tally)]
        if cut is not None and (raw.endswith(b"\n") or not raw):  # else its cut last line was counted already
            tally.add(raw.count(b"\n") + 1, None, cut)
    else:
        frames = _read_binary(p, fmt, tally)
    return LogRead(frames, tally.issues())


def read_bytes(path: Path) -> tuple[bytes, str | None]:
    """A text log's bytes, decompressed when it ends in .gz, and why it ends early (a gzip stream cut off: the
    bytes before the cut are kept) or None."""
    if path.suffix.lower() != GZIP_SUFFIX:
        return path.read_bytes(), None
    out = zlib.decompressobj(16 + zlib.MAX_WBITS)  # the gzip container
    try:
        raw = out.decompress(path.read_bytes())
    except zlib.error as exc:
        raise LogError(f"{path}: not a readable gzip file ({exc})") from exc
    return raw, None if out.eof else "truncated: the gzip stream ends early"


def numbered_lines(raw: bytes, first: int = 1) -> Iterator[tuple[int, str]]:
    """The lines of a text log as python-can reads them, numbered, each with its line end: split at newlines
    only (a stray carriage return stays inside its line), bytes that are not UTF-8 replaced (such a line is then
    malformed, not the end of the log)."""
    text = raw.decode("utf-8", errors="replace")
    start = 0
    number = first
    while start < len(text):
        end = text.find("\n", start)
        stop = len(text) if end < 0 else end + 1
        yield number, text[start:stop]
        number += 1
        start = stop


class Tally:
    """Malformed lines as they are found: counted, the first few kept, or with `strict` the first one raised."""

    def __init__(self, path: str, strict: bool = False) -> None:
        self.path = path
        self.strict = strict
        self.count = 0
        self.first: list[Malformed] = []

    def add(self, line: int | None, after_frame: int | None, reason: str) -> None:
        bad = Malformed(line, after_frame, " ".join(reason.split()))
        self.count += 1
        if len(self.first) < MAX_REPORTED:
            self.first.append(bad)
        if self.strict:
            raise MalformedLogError(LogIssues(self.path, 1, (bad,)).error())

    def issues(self) -> LogIssues:
        return LogIssues(self.path, self.count, tuple(self.first))


def bad_frame(msg: can.Message) -> str | None:
    """Why a data frame python-can read is malformed (its payload does not match its length code), or None."""
    if msg.is_error_frame or msg.is_remote_frame:
        return None
    n = len(msg.data)
    if n == msg.dlc or (not msg.is_fd and msg.dlc > 8 and n == 8):  # a classic DLC 9-15 means 8 bytes
        return None
    return f"{n} payload bytes for length code {msg.dlc}"


class _Lines:
    """Numbered lines as a text file for a python-can reader: `number` is the line last handed out, `filler`
    a line handed out before the next one without counting (see `_RESUME_FILLER`)."""

    def __init__(self, lines: Iterable[tuple[int, str]]) -> None:
        self._lines = iter(lines)
        self.number = 0
        self.text = ""
        self.filler: str | None = None

    def __iter__(self) -> Iterator[str]:
        return self

    def __next__(self) -> str:
        if self.filler is not None:
            line, self.filler = self.filler, None
            return line
        self.number, self.text = next(self._lines)
        return self.text

    def close(self) -> None:
        """python-can's readers close their file at the end: the caller owns the real one."""


class _TrcWarnings(logging.Handler):
    """python-can's TRCReader logs a line it cannot split into its columns (``Failed to parse message``) and
    drops it: counted as malformed here, with the line number of the line being read; only the warnings of the
    thread reading (another thread may read another log at the same time: a fleet on Dask threads)."""

    def __init__(self, on_line: Callable[[str], None]) -> None:
        super().__init__(logging.WARNING)
        self._on_line = on_line
        self._thread = threading.get_ident()

    def emit(self, record: logging.LogRecord) -> None:
        args = record.args if isinstance(record.args, tuple) else ()
        if record.thread == self._thread and "Failed to parse" in str(record.msg) and args and str(args[0]).strip():
            self._on_line(f"TRCReader: cannot split {str(args[0])[:60]!r} into its columns")


def read_text_lines(reader_type: type[MessageReader], lines: Iterable[tuple[int, str]],
                    tally: Tally) -> Iterator[tuple[int, Frame]]:
    """The data frames python-can's `reader_type` finds in numbered `lines` (text with its line end), each with
    its line number; a line it fails on, a frame whose payload disagrees with its length code, and an unterminated
    last line go to `tally` and are skipped."""
    src = _Lines(lines)
    reader = reader_type(src)  # type: ignore[arg-type]  # every text reader takes a file-like object first
    cut_counted = False

    def bad(reason: str = "") -> None:
        nonlocal cut_counted
        cut = not src.text.endswith("\n")
        cut_counted = cut_counted or cut
        text = "; ".join(r for r in (TRUNCATED if cut else "", reason) if r)
        tally.add(src.number, None, text)

    trc = _TrcWarnings(bad)
    log = logging.getLogger("can.io.trc")
    log.addHandler(trc)  # (a handler here also keeps logging's last resort from printing the warning)
    try:
        last_error_at = -1
        while True:
            try:
                for msg in reader:
                    why = bad_frame(msg)
                    if why is not None or not src.text.endswith("\n"):
                        bad(why or "")
                    elif not (msg.is_error_frame or msg.is_remote_frame):
                        yield src.number, Frame.from_can(msg)
                break
            except MalformedLogError:
                raise
            except Exception as exc:  # python-can raises ValueError, IndexError, binascii.Error, ... on a bad line
                if src.number == last_error_at:  # no line consumed since the last error: the reader is stuck
                    raise LogError(f"{tally.path}: line {src.number}: python-can's reader cannot go on "
                                   f"({type(exc).__name__}: {exc})") from exc
                last_error_at = src.number
                bad(_reason(exc, src.text))
                src.filler = _RESUME_FILLER.get(reader_type)
        if not cut_counted and src.text.strip() and not src.text.endswith("\n"):
            bad()  # a line python-can took for meta data: a frame line cut early, likely
    finally:
        log.removeHandler(trc)


def _reason(exc: BaseException, text: str) -> str:
    shown = text.strip()
    shown = shown if len(shown) <= 60 else shown[:57] + "..."
    return f"{type(exc).__name__}: {exc}; the line reads {shown!r}"


def _read_binary(p: Path, fmt: str, tally: Tally) -> list[Frame]:
    """The data frames of a binary log (.blf, .mf4, .db, ...): a record python-can fails on ends the log (one
    malformed record; LogError when no frame came before it); a .blf shorter than its header says is one too."""
    frames: list[Frame] = []
    try:
        reader = can.LogReader(str(p))
    except Exception as exc:  # python-can raises many kinds (struct.error, ValueError, BLFParseException, ...)
        raise _missing_package(p, fmt, exc) or LogError(f"{p}: not a readable {fmt} log ({type(exc).__name__}: "
                                                     f"{exc})") from exc
    with reader:
        try:
            for msg in reader:
                why = bad_frame(msg)
                if why is not None:
                    tally.add(None, len(frames), why)
                elif not (msg.is_error_frame or msg.is_remote_frame):
                    frames.append(Frame.from_can(msg))
        except MalformedLogError:
            raise
        except Exception as exc:
            if not frames:
                raise LogError(f"{p}: not a readable {fmt} log ({type(exc).__name__}: {exc})") from exc
            tally.add(None, len(frames), f"{type(exc).__name__}: {exc}; the rest of the file is not read")
        if frames:  # a file of garbage holds no data frames; the size of a real one that was cut says so
            _check_blf_size(p, reader, len(frames), tally)
    return frames


def _check_blf_size(p: Path, reader: Any, frames: int, tally: Tally) -> None:
    """A .blf whose header announces more bytes than the file has was cut off: its last objects are lost."""
    if not isinstance(reader, can.BLFReader):
        return
    announced, size = int(reader.file_size), os.path.getsize(p)
    if announced > size:
        lost = max(0, int(reader.object_count) - frames)
        tally.add(None, frames, f"truncated: {size} of the {announced} bytes its header announces "
                  f"(up to {lost} objects lost)")
