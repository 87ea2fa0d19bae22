"""What every command line of the project shares (``fdi-analyze`` and the ``fdi_host`` programs): ``--version``,
the exit codes, and one line on stderr for an error instead of a traceback.

Exit codes: 0 done; 1 a runtime error (a bad input file, something that could not be computed), reported as
one line ``PROG: error: FILE: what is wrong``; 2 a usage error (argparse: a bad option, with the usage text);
70 a bug (`EXIT_BUG`, sysexits' EX_SOFTWARE: any other exception, printed with its traceback); 130 interrupted
(Ctrl-C). A program's own checks after parsing return `EXIT_ERROR`; everything it raises of `INPUT_ERRORS`
(`fdi_analysis.errors.FdiError`: every typed error of both packages; a missing or unreadable file), or of the
errors it names, ends as that one line.

    def main(argv=None) -> int:
        args = add_version(build_parser()).parse_args(argv)
        return run("fdi-x", lambda: body(args))
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tomllib
import traceback
from collections.abc import Callable, Sequence
from pathlib import Path

from fdi_analysis.errors import FdiError, InputError
from fdi_analysis.resources import model_file, shipped_models, shipped_thresholds, thresholds_file
from fdi_analysis.version import __version__

EXIT_OK = 0
EXIT_ERROR = 1
EXIT_USAGE = 2  # argparse's own
EXIT_BUG = 70  # EX_SOFTWARE of sysexits.h: an internal error, reported with its traceback
EXIT_INTERRUPTED = 130

# Bad input anywhere below a command line, or a result that could not be computed: the project's typed errors
# (FdiError: ModelError, StructureError, ScenarioError, EcuError, QualityError, ...), a file that is missing or
# unreadable (OSError, which names it), and content the standard library's readers reject where a reader of the
# project does not wrap it in a typed error naming the file yet (TOML, JSON, UTF-8, a truncated binary file).
# A bare ValueError, KeyError, ... is not among them: raised from the library, it is a bug.
INPUT_ERRORS: tuple[type[BaseException], ...] = (
    FdiError, OSError, tomllib.TOMLDecodeError, json.JSONDecodeError, UnicodeDecodeError, EOFError)


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
    `EXIT_INTERRUPTED`. Anything else is a bug: its traceback, a line saying so, and `EXIT_BUG`. (argparse's
    SystemExit passes through: exit 2 with the usage text.)"""
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
    except Exception as exc:
        traceback.print_exc()
        print(f"{prog}: internal error ({type(exc).__name__}): a bug; please report it with the traceback above",
              file=sys.stderr)
        return EXIT_BUG


def use_file_backend() -> None:
    """A command line writes its plots to files: the non-interactive Agg backend. Called from a program's main,
    never at import (a notebook keeps its own backend)."""
    import matplotlib

    matplotlib.use("Agg")


def shipped_file(path: Path, kind: str, names: Sequence[str], other_kind: str = "",
                 other_names: Sequence[str] = ()) -> Path:
    """`path` unless it is a bare name (no folder, no suffix) of no file and of no shipped `kind`: then an
    `InputError` listing the shipped `names` (and saying so when the name is a shipped `other_kind`)."""
    if path.exists() or path.suffix or len(path.parts) != 1:
        return path
    other = f"; {path.name} is a {other_kind}, not a {kind}" if path.name in other_names else ""
    raise InputError(f"{path}: no such file, nor a {kind} shipped with the package ({', '.join(names)}){other}")


def run_subcommand(prog: str, parser: argparse.ArgumentParser, argv: Sequence[str] | None = None) -> int:
    """The main of a command line with subcommands (`fdi-analyze`, `fdi-tune`): parse `argv`, take a bare MODEL
    or ``--thresholds`` name for the shipped file of that name (``romo_grouped``, ``romo_thresholds``), plot to
    files, and `run` the chosen subcommand's ``func``."""
    args = parser.parse_args(argv)
    use_file_backend()

    def body() -> int:
        if isinstance(getattr(args, "model", None), Path):
            args.model = shipped_file(model_file(args.model), "model", shipped_models(), "thresholds file",
                                      shipped_thresholds())
        if isinstance(getattr(args, "thresholds", None), Path):
            args.thresholds = shipped_file(thresholds_file(args.thresholds), "thresholds file", shipped_thresholds(),
                                           "model", shipped_models())
        return int(args.func(args))

    return run(prog, body)
