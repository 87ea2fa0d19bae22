"""What every command line of the project shares (``fdi-analyze`` and the ``fdi_host`` programs): ``--version``,
the exit codes, and one line on stderr for an error instead of a traceback.

Exit codes: 0 done; 1 a runtime error (a bad input file, something that could not be computed), reported as
one line ``PROG: error: FILE: what is wrong``; 2 a usage error (argparse); 130 interrupted (Ctrl-C). A
program's own checks after parsing return `EXIT_ERROR`; everything it raises of `INPUT_ERRORS`, or of the
errors it names, ends as that one line.

    def main(argv=None) -> int:
        args = add_version(build_parser()).parse_args(argv)
        return run("fdi-x", lambda: body(args), errors=(EcuError,))
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

from fdi_analysis.resources import model_file
from fdi_analysis.version import __version__

EXIT_OK = 0
EXIT_ERROR = 1
EXIT_USAGE = 2  # argparse's own
EXIT_INTERRUPTED = 130

# Bad input anywhere below a command line: a file that is missing or unreadable (OSError), malformed content
# (ValueError: UnicodeDecodeError, JSON and TOML decode errors and every typed error of the project, ModelError,
# StructureError, LogError, ScenarioError, ...), a truncated binary file (EOFError).
INPUT_ERRORS: tuple[type[BaseException], ...] = (OSError, ValueError, EOFError)


def add_version(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """``--version``: prints ``PROG VERSION`` and exits 0."""
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    return parser


def one_line(exc: BaseException) -> str:
    """The error as one line: an OSError as ``FILE: reason``, any other message with its line breaks folded."""
    if isinstance(exc, OSError) and exc.filename is not None and exc.strerror:
        text = f"{exc.filename}: {exc.strerror}"
    else:
        text = str(exc) or type(exc).__name__
    return " ".join(text.split())


def fail(prog: str, message: str | BaseException) -> int:
    """Print ``PROG: error: MESSAGE`` (one line) on stderr; returns `EXIT_ERROR`."""
    text = one_line(message) if isinstance(message, BaseException) else " ".join(message.split())
    print(f"{prog}: error: {text}", file=sys.stderr)
    return EXIT_ERROR


def run(prog: str, body: Callable[[], int], errors: tuple[type[BaseException], ...] = ()) -> int:
    """`body`'s exit code; an exception of `INPUT_ERRORS` or `errors` becomes one line and `EXIT_ERROR`, Ctrl-C
    `EXIT_INTERRUPTED`. Anything else is a bug and keeps its traceback."""
    try:
        return body()
    except BrokenPipeError:  # the reader went away (`| head`): no message, as Python's documentation advises
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return EXIT_ERROR
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except (*INPUT_ERRORS, *errors) as exc:
        return fail(prog, exc)


def use_file_backend() -> None:
    """A command line writes its plots to files: the non-interactive Agg backend. Called from a program's main,
    never at import (a notebook keeps its own backend)."""
    import matplotlib

    matplotlib.use("Agg")


def run_subcommand(prog: str, parser: argparse.ArgumentParser, argv: Sequence[str] | None = None) -> int:
    """The main of a command line with subcommands (`fdi-analyze`, `fdi-tune`): parse `argv`, take a bare MODEL
    name for the shipped model of that name, plot to files, and `run` the chosen subcommand's ``func`` (every
    typed error of the project is a ValueError, so one of `INPUT_ERRORS`)."""
    args = parser.parse_args(argv)
    if isinstance(getattr(args, "model", None), Path):
        args.model = model_file(args.model)
    use_file_backend()
    return run(prog, lambda: int(args.func(args)))
