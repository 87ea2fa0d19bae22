"""The errors the project raises on purpose, under one root: `FdiError`.

Every typed error of `fdi_analysis` derives from `FdiError`, and `fdi_host`'s from its own root
`fdi_host.errors.FdiHostError`, itself an `FdiError`. An `FdiError` says what is wrong with the input (a model
file, a thresholds file, a log, an option's value) or what could not be computed (a solver without an answer,
a search past its time limit); its message is meant for the user, one line, naming the file where there is one.
Anything else escaping from the library is a bug.

The command lines (`fdi_analysis.cli.common.run`) report an `FdiError` as one line and exit 1; argparse's usage
errors exit 2; any other exception keeps its traceback (exit `fdi_analysis.cli.common.EXIT_BUG`).

Many classes also derive from the built-in error they replaced (``class ModelError(FdiError, ValueError)``), so
that ``except ValueError`` in existing callers keeps working. Where a class carries data (`ModelError`'s file,
equation and symbol; `fdi_analysis.residuals.reasons.NotRealizableError`'s typed reason), that stays on it.

    from fdi_analysis.errors import FdiError
    try:
        model = load_model(path)
    except FdiError as exc:      # ModelError: the file, the equation and the symbol in the message
        print(exc)
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


class FdiError(Exception):
    """The root of the project's errors: a bad input, or a result that could not be computed (never a bug)."""


class InputError(FdiError, ValueError):
    """A bad input that no more specific class of its module describes (a value in a file, an option)."""


class ComputationError(FdiError, RuntimeError):
    """A result that could not be computed from good input: a solver without an answer, a proof not found within
    its time limit."""


@contextmanager
def fields_of(path: Path | str, error: type[FdiError]) -> Iterator[None]:
    """Inside, reading a parsed file's fields: a missing key or a value of the wrong type (KeyError, TypeError,
    ValueError, AttributeError) becomes `error` naming the file and the key; an `FdiError` passes as it is."""
    try:
        yield
    except FdiError:
        raise
    except KeyError as exc:
        raise error(f"{path}: no {exc.args[0]!r}") from exc
    except (TypeError, ValueError, AttributeError) as exc:
        raise error(f"{path}: a value of the wrong type: {exc}") from exc
