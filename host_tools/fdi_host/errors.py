"""The root of the host tools' errors: `FdiHostError`, an `fdi_analysis.errors.FdiError`.

Every typed error of `fdi_host` (a scenario, a fault spec, a log, the ECU core's status, the quality suite's
configuration, ...) derives from `FdiHostError`, so ``except FdiError`` catches the analysis's and the host
tools' alike, and ``except FdiHostError`` the host tools' only. The command lines report them as one line and
exit 1 (`fdi_analysis.cli.common.run`); see `fdi_analysis.errors` for the rules.
"""

from __future__ import annotations

from fdi_analysis.errors import FdiError


class FdiHostError(FdiError):
    """The root of `fdi_host`'s errors: a bad input or a result that could not be computed (never a bug)."""
