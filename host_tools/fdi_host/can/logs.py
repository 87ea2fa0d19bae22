"""CAN log files through python-can's readers and writers, by extension: ``.log`` (candump), ``.asc`` (Vector
ASCII), ``.blf`` (Vector binary). Reading keeps data frames only (error and remote frames are dropped); a file
that cannot be read is one `LogError` naming the file and what is wrong."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import can

from fdi_host.can.frame import Frame

LOG_SUFFIXES = (".log", ".asc", ".blf")


class LogError(ValueError):
    """A log file that cannot be written or read (format, missing file, corrupt content)."""


def check_suffix(path: str | Path) -> Path:
    """The path, or LogError when python-can has no reader/writer for its extension."""
    p = Path(path)
    if p.suffix not in LOG_SUFFIXES:
        raise LogError(f"{p}: unsupported log format {p.suffix!r}; use one of {', '.join(LOG_SUFFIXES)}")
    return p


def write_log(frames: Iterable[Frame], path: str | Path) -> int:
    """Write frames with python-can's writer for the file's extension. Returns the number written."""
    p = check_suffix(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    n = 0
    with can.Logger(str(p)) as writer:
        for f in frames:
            writer.on_message_received(f.to_can())
            n += 1
    return n


def read_log(path: str | Path) -> list[Frame]:
    """The data frames of a log, in file order."""
    p = check_suffix(path)
    if not p.is_file():
        raise LogError(f"{p}: no such file")
    try:
        return [Frame.from_can(m) for m in can.LogReader(str(p)) if not (m.is_error_frame or m.is_remote_frame)]
    except Exception as exc:  # python-can raises many kinds (struct.error, ValueError, BLFParseException, ...)
        raise LogError(f"{p}: not a readable {p.suffix} log ({type(exc).__name__}: {exc})") from exc
