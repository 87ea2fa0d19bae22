"""A vehicle's DBC as the project reads it: the one place that parses the signal attributes mapping DBC signals to
the model's measured signals.

A DBC signal carries a model signal when it has the signal attribute ``ModelSignal`` (the model's name of the
signal); ``ModelFactor`` (default 1) states its scaling, DBC value = model value * factor. The CAN codec of the
firmware (`can_codec`, `fdi-analyze export-can`) and the host tools' encoder and decoder (`fdi_host.can.dbc`) both
take the mapping from here, so the DBC is its one source.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cantools
from cantools.database.errors import UnsupportedDatabaseFormatError

from fdi_analysis.errors import FdiError

MODEL_SIGNAL = "ModelSignal"
MODEL_FACTOR = "ModelFactor"


class DbcError(FdiError, ValueError):
    """A DBC that cannot be read, or whose model-signal attributes are wrong (the message names the signal)."""


@dataclass(frozen=True)
class DbcSignal:
    """Signal `signal` of message `message` carries the model's signal `model`: DBC value = model value * factor."""

    message: str
    signal: str
    model: str
    factor: float = 1.0


def load_dbc(path: Path) -> cantools.database.can.Database:
    """The DBC at `path` (a `DbcError` naming the file when it is missing or not a DBC CAN database)."""
    try:
        db = cantools.database.load_file(str(path))
    except (OSError, UnsupportedDatabaseFormatError) as exc:
        raise DbcError(f"{path}: cannot read the DBC: {exc}") from exc
    if not isinstance(db, cantools.database.can.Database) or db.dbc is None:
        raise DbcError(f"{path} is not a DBC CAN database")
    return db


def model_signals(path: Path) -> tuple[DbcSignal, ...]:
    """The DBC signals that carry a model signal, in DBC order (messages, then their signals)."""
    db = load_dbc(path)
    out = []
    seen: dict[str, str] = {}
    for msg in db.messages:
        for sig in msg.signals:
            attrs = sig.dbc.attributes if sig.dbc is not None else {}
            if MODEL_SIGNAL not in attrs or not attrs[MODEL_SIGNAL].value:
                continue
            model = str(attrs[MODEL_SIGNAL].value)
            where = f"{path.name}: {msg.name}.{sig.name}"
            if model in seen:
                raise DbcError(f"{where}: {MODEL_SIGNAL} {model!r} is already carried by {seen[model]}")
            seen[model] = f"{msg.name}.{sig.name}"
            try:
                factor = float(attrs[MODEL_FACTOR].value) if MODEL_FACTOR in attrs else 1.0
            except (TypeError, ValueError) as exc:
                raise DbcError(f"{where}: {MODEL_FACTOR} {attrs[MODEL_FACTOR].value!r} is not a number") from exc
            if not factor > 0.0 or factor == float("inf"):
                raise DbcError(f"{where}: {MODEL_FACTOR} {factor} must be a positive finite number")
            out.append(DbcSignal(msg.name, sig.name, model, factor))
    return tuple(out)
