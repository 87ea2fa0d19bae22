"""A vehicle's CAN database (``dbc/romo.dbc`` by default, or a vehicle folder's DBC) seen from the simulator:
which model signal goes where.

The DBC is the single source of truth for frame layout, scaling, cycle times and E2E data IDs. This module
only adds the mapping between simulator signals (the model's knowns such as ``vx_m`` in SI units, and the
motion demand) and DBC signals, with the unit factor (simulator -> DBC; Pa -> bar for pressures), and
encodes/decodes frames with the E2E profile 11 header of `fdi_host.can.e2e`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cantools

from fdi_analysis.export.dbc_signals import model_signals
from fdi_host.can import e2e
from fdi_host.errors import FdiHostError
from fdi_host.resources import DBC

DEFAULT_DBC = DBC.path() / "romo.dbc"  # dbc/romo.dbc in a checkout, the package's copy in a wheel


@dataclass(frozen=True)
class SignalMap:
    """Simulator signal `sim` (SI) is carried by `signal` of `message`; DBC value = sim value * factor."""

    sim: str
    message: str
    signal: str
    factor: float = 1.0


def signal_map(path: Path) -> tuple[SignalMap, ...]:
    """The DBC signals that carry a simulator (model) signal, in DBC order: the signal attributes "ModelSignal"
    and "ModelFactor" as `fdi_analysis.export.dbc_signals` reads them, for the firmware's codec too (`fdi-analyze
    export-can`): the DBC is the one source of the mapping, read in one place."""
    return tuple(SignalMap(s.model, s.message, s.signal, s.factor) for s in model_signals(path))


SIGNAL_MAP: tuple[SignalMap, ...] = signal_map(DEFAULT_DBC)

# Messages the simulator transmits (the diagnosis message is produced by the FDI unit, not simulated).
SIMULATED_MESSAGES: tuple[str, ...] = tuple(dict.fromkeys(m.message for m in SIGNAL_MAP))

DIAG_NODE = "FDI"  # the diagnosis unit: the one message it sends is the diagnosis frame


def diag_id_of(path: Path) -> int:
    """The ID of the diagnosis frame of a DBC: the one message node FDI sends."""
    db = cantools.database.load_file(str(path))
    if not isinstance(db, cantools.database.can.Database):
        raise ValueError(f"{path} is not a DBC CAN database")
    sent = [m.frame_id for m in db.messages if DIAG_NODE in m.senders]
    if len(sent) != 1:
        raise ValueError(f"{path}: node {DIAG_NODE} sends {len(sent)} messages, expected the diagnosis frame only")
    return int(sent[0])


DIAG_ID: int = diag_id_of(DEFAULT_DBC)  # ID of FDI_Diagnosis, from the DBC (the one definition on the host side)


class E2EError(FdiHostError, ValueError):
    """A received frame failed its E2E CRC check."""


@dataclass(frozen=True)
class Decoded:
    message: str
    signals: dict[str, float]
    counter: int


class CanDatabase:
    """The loaded DBC plus simulator mapping (its ModelSignal attributes) and E2E handling."""

    def __init__(self, path: str | Path = DEFAULT_DBC) -> None:
        self.path = Path(path)
        db = cantools.database.load_file(str(self.path))
        if not isinstance(db, cantools.database.can.Database) or db.dbc is None:
            raise ValueError(f"{self.path} is not a DBC CAN database")
        self.db = db
        self._dbc = db.dbc
        self._by_name = {m.name: m for m in self.db.messages}
        self._by_id = {m.frame_id: m for m in self.db.messages}
        self.signal_map = SIGNAL_MAP if self.path == DEFAULT_DBC else signal_map(self.path)
        self.simulated_messages: tuple[str, ...] = tuple(dict.fromkeys(m.message for m in self.signal_map))
        self.diag_id = DIAG_ID if self.path == DEFAULT_DBC else diag_id_of(self.path)
        self.maps_by_message: dict[str, list[SignalMap]] = {}
        for sm in self.signal_map:
            self.maps_by_message.setdefault(sm.message, []).append(sm)
            self.message(sm.message).get_signal_by_name(sm.signal)  # KeyError if the DBC lacks it

    # ---------------------------------------------------------------------------------------- attributes
    def message(self, name: str) -> Any:
        return self._by_name[name]

    def message_by_id(self, frame_id: int) -> Any:
        return self._by_id[frame_id]

    def _attr(self, name: str, attr: str) -> Any:
        attrs = self.message(name).dbc.attributes
        if attr in attrs:
            return attrs[attr].value
        return self._dbc.attribute_definitions[attr].default_value

    def cycle_time_ms(self, name: str) -> int:
        ct = self.message(name).cycle_time
        return int(ct if ct is not None else self._attr(name, "GenMsgCycleTime"))

    def start_delay_ms(self, name: str) -> int:
        return int(self._attr(name, "GenMsgStartDelayTime"))

    def data_id(self, name: str) -> int | None:
        if self._attr(name, "E2EProfile") != "P11":
            return None
        return int(self._attr(name, "E2EDataID"))

    def prefix(self, name: str) -> str:
        """Signal prefix of a message (``IMU`` for IMU_Motion: its CRC is ``IMU_CRC``)."""
        (crc,) = [s.name for s in self.message(name).signals if s.name.endswith("_CRC")]
        return str(crc[: -len("_CRC")])

    def baudrate(self) -> int:
        return int(self._dbc.attributes["Baudrate"].value)

    # ---------------------------------------------------------------------------------------- encode
    def encode(self, name: str, values: Mapping[str, float], counter: int, status: int = 0) -> bytes:
        """Encode `values` (DBC signal names, physical DBC units) with E2E counter/CRC.

        Values outside a signal's [minimum, maximum] are clipped to it (a sensor saturates); signals not
        given are 0.
        """
        msg = self.message(name)
        pre = self.prefix(name)
        data: dict[str, float] = {}
        for sig in msg.signals:
            v = float(values.get(sig.name, 0.0))
            if sig.minimum is not None and v < sig.minimum:
                v = float(sig.minimum)
            if sig.maximum is not None and v > sig.maximum:
                v = float(sig.maximum)
            data[sig.name] = v
        data[f"{pre}_Counter"] = counter
        data[f"{pre}_Status"] = status
        data[f"{pre}_CRC"] = 0
        raw = msg.encode(data, scaling=True, padding=False, strict=False)
        did = self.data_id(name)
        return e2e.protect(raw, did, counter) if did is not None else bytes(raw)

    def encode_sim(self, name: str, sim_values: Mapping[str, float], counter: int) -> bytes:
        """Encode simulator signals (SI, keyed by `SignalMap.sim`) into message `name`."""
        vals = {sm.signal: sim_values[sm.sim] * sm.factor for sm in self.maps_by_message[name]}
        return self.encode(name, vals, counter)

    # ---------------------------------------------------------------------------------------- decode
    def decode(self, frame_id: int, data: bytes, check_e2e: bool = True) -> Decoded:
        msg = self.message_by_id(frame_id)
        did = self.data_id(msg.name)
        if check_e2e and did is not None and e2e.p11_crc(data, did) != data[0]:
            raise E2EError(f"{msg.name}: E2E CRC mismatch (got 0x{data[0]:02X})")
        sig = msg.decode(data, decode_choices=False, scaling=True)
        return Decoded(msg.name, {k: float(v) for k, v in sig.items()}, e2e.counter_of(data))

    def decode_sim(self, frame_id: int, data: bytes, check_e2e: bool = True) -> dict[str, float]:
        """Decode a frame back into simulator signals (SI)."""
        d = self.decode(frame_id, data, check_e2e)
        return {sm.sim: d.signals[sm.signal] / sm.factor for sm in self.maps_by_message.get(d.message, [])}
