"""Python bindings (ctypes) of the C ECU core `fw/ecu` and the fw/ diagnoser: an ECU process on any CAN interface,
and the diagnoser alone on frames of signals.

The shared library is a vehicle's plugin (fdi_host.vehicle, fdi_py_plugin.h): the generic core (fw/src,
fw/ecu/src), the seam (fdi_py_seam.c) and the vehicle's diagnosis in one library per vehicle, the shipped ones
(romo, kin, three_tank) built by ``pip install -e .`` (setup.py), a user's folder by ``fdi-vehicle build``. This
module loads it with `ctypes.CDLL` and wraps the C API
of ``fw/ecu/include/fdi_ecu.h`` and ``fw/include/fdi_diag.h``::

    ecu = Ecu("kin")                       # or Ecu("romo", warmup_steps=400, timeout_s={"IMU_Motion": 0.02})
    for t, can_id, data in frames:         # t in seconds (monotonic)
        ecu.rx(can_id, data, t)
        for fid, payload in ecu.poll(t):   # FDI_Diagnosis frames (DIAG_ID, from the DBC) to send
            bus.send(...)
    ecu.result().candidates, ecu.counters().rejected

    diag = Diagnoser("three_tank", sensitivities=True)   # no bus: frames of the table's signals
    runs = diag.run({"u": u, "y1": y1, "y2": y2, "y3": y3})   # residuals, sensitivities, results per step

Semantics (frame checks, timeouts, fixed steps at the table's dt, the diagnosis frame) are those of the C core:
a step at T_k sees exactly the frames with t <= T_k, whatever the poll pattern. Times are converted to wrapping
uint32 microseconds. The message layout is the C bus description generated from the DBC (`bus_info`), read from
the library, not kept here.
"""

from __future__ import annotations

import ctypes
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fdi_analysis.export.seam import BusInt, SizeOf, TableInt, TableReal, TableStr
from fdi_host.can.dbc import DIAG_ID
from fdi_host.errors import FdiHostError
from fdi_host.vehicle import resolve

__all__ = ["DIAG_ID", "REASONS", "BusInfo", "DiagRun", "Diagnoser", "Ecu", "EcuCounters",
           "EcuError", "EcuResult", "Evidence", "MessageCounters", "TableInfo", "bus_info", "table_info"]

REASONS: tuple[str, ...] = (
    "unknown_id", "own_frame", "bad_dlc", "bad_crc", "out_of_range", "repeated_counter", "counter_jump",
    "sensor_status",
)
STATUS_NAMES: dict[int, str] = {
    0: "INIT", 1: "NO_FAULT", 2: "FAULT_DETECTED", 3: "FAULT_ISOLATED", 4: "INPUT_INVALID", 15: "INVALID",
}
TEST_STATUS_NAMES: tuple[str, ...] = ("ok", "alarm", "not_evaluable")
_N_REASONS = len(REASONS)
_MODES = {"no_exoneration": 0, "exoneration": 1}


class EcuError(FdiHostError, RuntimeError):
    """A call of the C core returned an error status."""


_STATUS = {0: "OK", 1: "BAD_ARG", 2: "NOT_FINITE", 3: "BAD_TABLE", 4: "BAD_LAYOUT"}


def _check(st: int, what: str) -> None:
    if st != 0:
        raise EcuError(f"{what} failed: {_STATUS.get(st, str(st))}")


# ------------------------------------------------------------------------------------------ ctypes mirrors
@dataclass(frozen=True)
class _Caps:
    max_tests: int
    max_msgs: int
    max_sens: int
    n_params: int
    max_signals: int
    kept_frames: int  # FDI_ECU_HISTORY: frames the ECU keeps per message for the time alignment
    max_faults: int  # FDI_TABLE_MAX_FAULTS
    max_est: int  # FDI_EST_MAX_PARAMS: quantities one test's estimator follows


def _struct_types(c: _Caps) -> dict[str, type[ctypes.Structure]]:
    class DiagConfig(ctypes.Structure):
        _fields_ = [
            ("table", ctypes.c_void_p), ("gen_param", ctypes.c_float * c.n_params),
            ("cusum_k", ctypes.c_float), ("cusum_h", ctypes.c_float), ("set_count", ctypes.c_uint16),
            ("clear_count", ctypes.c_uint16), ("warmup_steps", ctypes.c_uint16), ("reentry_steps", ctypes.c_uint16),
            ("mode", ctypes.c_int),
            ("episode_clear_steps", ctypes.c_uint16), ("noise_allowance", ctypes.c_float),
            ("sensitivities", ctypes.c_bool), ("sens_every", ctypes.c_uint16), ("adaptive", ctypes.c_bool),
            ("estimate", ctypes.c_uint32), ("estimate_kappa", ctypes.c_float),
            ("estimate_decorrelation", ctypes.c_float), ("estimate_startup", ctypes.c_uint16),
        ]

    class Config(ctypes.Structure):
        _fields_ = [
            ("bus", ctypes.c_void_p), ("diag", DiagConfig), ("timeout_us", ctypes.c_uint32 * c.max_msgs),
            ("max_delta_counter", ctypes.c_uint8), ("max_catchup_steps", ctypes.c_uint16),
            ("align_us", ctypes.c_uint32),
        ]

    class MsgCounters(ctypes.Structure):
        _fields_ = [
            ("can_id", ctypes.c_uint32), ("received", ctypes.c_uint32), ("accepted", ctypes.c_uint32),
            ("timeouts", ctypes.c_uint32), ("rejected", ctypes.c_uint32 * _N_REASONS),
        ]

    class Counters(ctypes.Structure):
        _fields_ = [
            ("frames", ctypes.c_uint32), ("rejected", ctypes.c_uint32 * _N_REASONS), ("steps", ctypes.c_uint32),
            ("steps_skipped", ctypes.c_uint32), ("tx_frames", ctypes.c_uint32),
            ("msg", MsgCounters * c.max_msgs),
        ]

    class IsoResult(ctypes.Structure):
        _fields_ = [
            ("candidates", ctypes.c_uint32), ("class_mask", ctypes.c_uint32), ("n_classes", ctypes.c_uint8),
            ("detected", ctypes.c_bool), ("isolated", ctypes.c_bool),
        ]

    class DiagResult(ctypes.Structure):
        _fields_ = [
            ("n_tests", ctypes.c_uint8), ("alarm_mask", ctypes.c_uint32), ("evaluable_mask", ctypes.c_uint32),
            ("status", ctypes.c_int * c.max_tests), ("residual", ctypes.c_float * c.max_tests),
            ("ratio", ctypes.c_float * c.max_tests), ("spread", ctypes.c_float * c.max_tests),
            ("offset", ctypes.c_float * c.max_tests), ("estimate", (ctypes.c_float * c.max_est) * c.max_tests),
            ("accused_mask", ctypes.c_uint32), ("iso", IsoResult),
            ("in_envelope", ctypes.c_bool), ("sens_offset", ctypes.c_uint8 * (c.max_tests + 1)),
            ("sens", ctypes.c_float * c.max_sens),
        ]

    class Result(ctypes.Structure):
        _fields_ = [
            ("step", ctypes.c_uint32), ("t_us", ctypes.c_uint32), ("validity", ctypes.c_uint32),
            ("status", ctypes.c_uint8), ("iso_class", ctypes.c_uint8), ("diag", DiagResult),
        ]

    class Frame(ctypes.Structure):
        _fields_ = [
            ("can_id", ctypes.c_uint32), ("dlc", ctypes.c_uint8), ("data", ctypes.c_uint8 * 8),
        ]

    class Tx(ctypes.Structure):
        _fields_ = [("n_frames", ctypes.c_uint8), ("frame", Frame * 1)]

    class Evidence(ctypes.Structure):
        _fields_ = [
            ("episode_age", ctypes.c_uint16), ("undecided", ctypes.c_uint32), ("latched", ctypes.c_uint32),
            ("implied", ctypes.c_float * c.max_faults), ("cleared_run", ctypes.c_uint16 * c.max_faults),
            ("cleared", ctypes.c_uint32), ("clears", ctypes.c_uint32 * c.max_tests),
        ]

    class SignalFrame(ctypes.Structure):
        _fields_ = [("value", ctypes.c_float * c.max_signals)]

    return {"Config": Config, "Counters": Counters, "Result": Result, "Tx": Tx, "DiagResult": DiagResult,
            "DiagConfig": DiagConfig, "SignalFrame": SignalFrame, "Evidence": Evidence}


@dataclass(frozen=True)
class _Lib:
    dll: ctypes.CDLL
    types: dict[str, type[ctypes.Structure]]
    caps: _Caps
    ecu_size: int
    diag_size: int
    table: int  # the vehicle's fdi_table_t
    bus: int  # its fdi_ecu_bus_t; 0 without a bus


def _lib(vehicle: str | Path = "romo") -> _Lib:
    """The plugin of a vehicle (``--vehicle NAME|PATH``, fdi_host.vehicle), loaded once per shared library."""
    return _load(resolve(vehicle).library)


@cache
def _load(library: Path) -> _Lib:
    try:
        dll = ctypes.CDLL(str(library))
    except OSError as exc:
        raise EcuError(f"cannot load the vehicle plugin {library}: {exc}") from None
    dll.fdi_py_sizeof.restype = ctypes.c_size_t
    dll.fdi_py_sizeof.argtypes = [ctypes.c_int]

    def size(what: SizeOf) -> int:
        return int(dll.fdi_py_sizeof(what))

    caps = _Caps(max_tests=size(SizeOf.MAX_TESTS), max_msgs=size(SizeOf.MAX_MSGS), max_sens=size(SizeOf.MAX_SENS),
                 n_params=size(SizeOf.GEN_N_PARAMS), max_signals=size(SizeOf.FRAME_MAX_SIGNALS),
                 kept_frames=size(SizeOf.ECU_HISTORY), max_faults=size(SizeOf.TABLE_MAX_FAULTS),
                 max_est=size(SizeOf.EST_MAX_PARAMS))
    types = _struct_types(caps)
    for what, name in ((SizeOf.ECU_CONFIG, "Config"), (SizeOf.ECU_COUNTERS, "Counters"),
                       (SizeOf.ECU_RESULT, "Result"), (SizeOf.ECU_TX, "Tx"), (SizeOf.DIAG_RESULT, "DiagResult"),
                       (SizeOf.DIAG_CONFIG, "DiagConfig"), (SizeOf.DIAG_EVIDENCE, "Evidence")):
        c_size, py_size = size(what), ctypes.sizeof(types[name])
        if c_size != py_size:
            raise ImportError(f"fdi_host.ecu.bindings: ctypes mirror of {name} has {py_size} bytes, C has {c_size}")
    for what, (struct, field) in ((SizeOf.ECU_RESULT_DIAG, ("Result", "diag")),
                                  (SizeOf.DIAG_RESULT_ISO, ("DiagResult", "iso")),
                                  (SizeOf.DIAG_RESULT_SENS_OFFSET, ("DiagResult", "sens_offset"))):
        if size(what) != getattr(types[struct], field).offset:
            raise ImportError(f"fdi_host.ecu.bindings: layout of {struct}.{field} differs from its ctypes mirror")
    vp, st = ctypes.c_void_p, ctypes.c_int
    sigs: dict[str, tuple[Any, list[Any]]] = {
        "fdi_plugin_name": (ctypes.c_char_p, []),
        "fdi_plugin_table": (vp, []),
        "fdi_plugin_bus": (vp, []),
        "fdi_plugin_param_index": (ctypes.c_int, [ctypes.c_char_p]),
        "fdi_plugin_ecu_config_default": (st, [vp]),
        "fdi_py_table_int": (ctypes.c_longlong, [vp, ctypes.c_int, ctypes.c_int]),
        "fdi_py_table_str": (ctypes.c_char_p, [vp, ctypes.c_int, ctypes.c_int]),
        "fdi_py_table_real": (ctypes.c_double, [vp, ctypes.c_int, ctypes.c_int]),
        "fdi_py_bus_int": (ctypes.c_longlong, [vp, ctypes.c_int, ctypes.c_int]),
        "fdi_py_bus_str": (ctypes.c_char_p, [vp, ctypes.c_int]),
        "fdi_ecu_init": (st, [vp, vp]),
        "fdi_ecu_rx": (st, [vp, ctypes.c_uint32, ctypes.c_uint8, ctypes.c_char_p, ctypes.c_uint32]),
        "fdi_ecu_poll": (st, [vp, ctypes.c_uint32, vp]),
        "fdi_ecu_counters": (st, [vp, vp]),
        "fdi_ecu_result": (st, [vp, vp]),
        "fdi_ecu_align_us": (ctypes.c_uint32, [vp]),
        "fdi_py_ecu_explain": (st, [vp, vp]),
        "fdi_py_process": (ctypes.c_long, [vp, ctypes.c_long, vp, vp, vp, vp, vp, vp, ctypes.c_long]),
        "fdi_diag_config_default": (st, [vp, vp]),
        "fdi_py_diag_init": (st, [vp, vp]),
        "fdi_diag_step": (st, [vp, vp, ctypes.c_uint32]),
        "fdi_diag_result": (st, [vp, vp]),
        "fdi_py_diag_run": (ctypes.c_long, [vp, ctypes.c_long, ctypes.c_int, vp, vp, vp, vp]),
    }
    for name, (res, args) in sigs.items():
        try:
            fn = getattr(dll, name)
        except AttributeError:
            raise EcuError(f"{library} is not a vehicle plugin: it has no {name} (fdi_py_plugin.h)") from None
        fn.restype = res
        fn.argtypes = args
    table = dll.fdi_plugin_table()
    if not table:
        raise EcuError(f"the vehicle plugin {library} has no table")
    return _Lib(dll, types, caps, size(SizeOf.ECU), size(SizeOf.DIAG), int(table), int(dll.fdi_plugin_bus() or 0))


# ------------------------------------------------------------------------------------------ tables
@dataclass(frozen=True)
class TableInfo:
    """What the Python side needs to know about a built-in diagnosis table."""

    name: str
    n_faults: int
    fault_names: tuple[str, ...]
    test_names: tuple[str, ...]  # "MSO<id>: <interpretation>"
    mso_ids: tuple[int, ...]
    test_fault_masks: tuple[int, ...]
    test_input_masks: tuple[int, ...]
    has_generator: tuple[bool, ...]
    iso_class: tuple[int, ...]  # per fault: the faults structurally not isolable from it (bitmask)
    dt: float  # design sample time = diagnosis step [s]
    signal_names: tuple[str, ...] = ()  # the frame's signals by index
    sens_masks: tuple[int, ...] = ()  # per test: faults whose sensitivity its generator outputs (ascending)
    sensitivity_margin: float = 1.0  # the on-line rule's margin (fdi_table_t.sensitivity_margin)
    gates: tuple[float, ...] = ()  # per test: its gate in standard deviations
    sigmas: tuple[float, ...] = ()  # per test: its fault-free residual's standard deviation
    n_est: tuple[int, ...] = ()  # per test: the quantities its generator declares estimable on line (fdi_est.h)

    @property
    def n_tests(self) -> int:
        return len(self.mso_ids)

    @property
    def faults(self) -> tuple[str, ...]:
        """The faults' names, in the table's order (bit j of a fault mask is faults[j])."""
        return tuple(n.split()[0] for n in self.fault_names)

    def fault_labels(self, mask: int) -> list[str]:
        """The names of the faults in a bitmask, in the table's order."""
        return [f for j, f in enumerate(self.faults) if mask >> j & 1]

    def sens_faults(self, test: int) -> list[int]:
        """Fault indices of test `test`'s sensitivities, in the order the diagnoser lists them."""
        return [j for j in range(32) if self.sens_masks[test] >> j & 1]


@cache
def table_info(name: str | Path) -> TableInfo:
    """The diagnosis table of vehicle `name` (a shipped vehicle's name or a vehicle folder)."""
    lib = _lib(name)
    dll, t = lib.dll, lib.table
    nf, nt = int(dll.fdi_py_table_int(t, TableInt.N_FAULTS, 0)), int(dll.fdi_py_table_int(t, TableInt.N_TESTS, 0))
    ns = int(dll.fdi_py_table_int(t, TableInt.N_SIGNALS, 0))

    def ints(what: TableInt, n: int) -> tuple[int, ...]:
        return tuple(int(dll.fdi_py_table_int(t, what, i)) for i in range(n))

    def strs(what: TableStr, n: int) -> tuple[str, ...]:
        return tuple((dll.fdi_py_table_str(t, what, i) or b"").decode() for i in range(n))

    mso = ints(TableInt.MSO_ID, nt)
    interp = strs(TableStr.INTERPRETATION, nt)
    return TableInfo(
        name=str(name), n_faults=nf, fault_names=strs(TableStr.FAULT_NAME, nf),
        test_names=tuple(f"MSO{m}: {s}" for m, s in zip(mso, interp, strict=True)), mso_ids=mso,
        test_fault_masks=ints(TableInt.FAULT_MASK, nt), test_input_masks=ints(TableInt.INPUT_MASK, nt),
        has_generator=tuple(k != 0 for k in ints(TableInt.HAS_GENERATOR, nt)),
        iso_class=ints(TableInt.ISO_CLASS, nf),
        dt=int(dll.fdi_py_table_int(t, TableInt.DT_US, 0)) * 1e-6, signal_names=strs(TableStr.SIGNAL_NAME, ns),
        sens_masks=ints(TableInt.SENS_MASK, nt),
        sensitivity_margin=float(dll.fdi_py_table_real(t, TableReal.SENSITIVITY_MARGIN, 0)),
        gates=tuple(float(dll.fdi_py_table_real(t, TableReal.GATE, i)) for i in range(nt)),
        sigmas=tuple(math.sqrt(float(dll.fdi_py_table_real(t, TableReal.VARIANCE, i))) for i in range(nt)),
        n_est=ints(TableInt.N_EST, nt),
    )


@dataclass(frozen=True)
class BusInfo:
    """A built-in bus (generated from its DBC): the input messages in the order of the ECU's counters."""

    name: str
    messages: tuple[tuple[str, int], ...]  # (DBC message name, CAN ID)
    cycle_ms: tuple[int, ...]
    signals: tuple[int, ...]  # frame signal mask per message
    data_ids: tuple[int, ...]
    diag_id: int
    diag_data_id: int

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(n for n, _ in self.messages)


def _bus_lib(vehicle: str | Path) -> _Lib:
    lib = _lib(vehicle)
    if not lib.bus:
        raise EcuError(f"vehicle {str(vehicle)!r} has no bus (no DBC): use Diagnoser({str(vehicle)!r}) with frames "
                       "of its signals")
    return lib


def kept_frames(vehicle: str | Path = "romo") -> int:
    """Frames the ECU core keeps per message for the time alignment (FDI_ECU_HISTORY of the built library)."""
    return _lib(vehicle).caps.kept_frames


def bus_align(vehicle: str | Path = "romo") -> float:
    """Seconds of the alignment that takes every message's signals of the vehicle's bus at one instant
    (fdi_ecu_align_us; use as ``Ecu(..., align_s=...)``)."""
    lib = _bus_lib(vehicle)
    return int(lib.dll.fdi_ecu_align_us(lib.bus)) * 1e-6


@cache
def bus_info(vehicle: str | Path = "romo") -> BusInfo:
    """The bus of a vehicle (generated from its DBC), as its plugin holds it."""
    lib = _bus_lib(vehicle)
    dll, b = lib.dll, lib.bus
    n = int(dll.fdi_py_bus_int(b, BusInt.N_MSGS, 0))

    def ints(what: BusInt) -> tuple[int, ...]:
        return tuple(int(dll.fdi_py_bus_int(b, what, i)) for i in range(n))

    names = tuple((dll.fdi_py_bus_str(b, i) or b"").decode() for i in range(n))
    return BusInfo(str(vehicle), tuple(zip(names, ints(BusInt.CAN_ID), strict=True)), ints(BusInt.CYCLE_MS),
                   ints(BusInt.SIGNALS), ints(BusInt.DATA_ID), int(dll.fdi_py_bus_int(b, BusInt.DIAG_ID, 0)),
                   int(dll.fdi_py_bus_int(b, BusInt.DIAG_DATA_ID, 0)))


def _estimate_mask(value: Any, mso_ids: Sequence[int], n_est: Sequence[int] = ()) -> int:
    """``estimate``: a bitmask of tests, or tests by MSO id (``1``, ``"MSO1"``), as a sequence or a comma-separated
    string (``"MSO1,MSO39"``), or ``"all"``: every test whose generator declares estimable quantities."""
    if isinstance(value, str) and value.strip().lower() == "all":
        return sum(1 << i for i, n in enumerate(n_est) if n > 0)
    if isinstance(value, bool):
        raise ValueError(f"estimate = {value!r}: give a test mask or the tests' MSO ids, e.g. estimate='MSO1,MSO39'")
    if isinstance(value, int):
        if not 0 <= value < 1 << len(mso_ids):
            raise ValueError(f"estimate = {value:#x} names tests beyond the table's {len(mso_ids)}")
        return value
    items = [x.strip() for x in value.split(",")] if isinstance(value, str) else list(value)
    mask = 0
    for item in items:
        text = str(item).strip()
        mso = int(text[3:]) if text.upper().startswith("MSO") and text[3:].isdigit() else None
        if mso is None and text.isdigit():
            mso = int(text)
        if mso is None or mso not in mso_ids:
            raise ValueError(f"estimate: {item!r} is not a test of the table; its tests are "
                             f"{', '.join(f'MSO{m}' for m in mso_ids)}")
        mask |= 1 << list(mso_ids).index(mso)
    return mask


def _apply_diag(dll: ctypes.CDLL, d: Any, ov: dict[str, Any], mso_ids: Sequence[int],
                n_est: Sequence[int] = ()) -> None:
    """Overrides of the diagnoser settings (fdi_diag_config_t), consumed from `ov`; a run-time generator parameter
    of the vehicle (ROMO's ``d_x``, ``d_y``) by its name, as the plugin knows it."""
    for key in [k for k in ov if int(dll.fdi_plugin_param_index(k.encode())) >= 0]:
        d.gen_param[int(dll.fdi_plugin_param_index(key.encode()))] = float(ov.pop(key))
    for key in ("cusum_k", "cusum_h", "noise_allowance", "estimate_kappa", "estimate_decorrelation"):
        if key in ov:
            setattr(d, key, float(ov.pop(key)))
    for key in ("set_count", "clear_count", "warmup_steps", "reentry_steps", "episode_clear_steps", "sens_every",
                "estimate_startup"):
        if key in ov:
            v = int(ov.pop(key))
            if not 0 <= v <= 0xFFFF:
                raise ValueError(f"{key} = {v} is outside 0..65535")
            setattr(d, key, v)
    if "mode" in ov:
        mode = ov.pop("mode")
        if mode not in _MODES:
            raise ValueError(f"mode {mode!r}: use one of {tuple(_MODES)}")
        d.mode = _MODES[mode]
    for key in ("sensitivities", "adaptive"):
        if key in ov:
            setattr(d, key, bool(ov.pop(key)))
    if "estimate" in ov:
        d.estimate = _estimate_mask(ov.pop("estimate"), mso_ids, n_est)


def _estimates(d: Any, table: TableInfo) -> tuple[tuple[float, ...], ...]:
    """Per test: the estimated deviations of its estimable quantities (fdi_diag_result_t.estimate)."""
    return tuple(tuple(float(d.estimate[i][e]) for e in range(table.n_est[i])) for i in range(table.n_tests))


def _sensitivities(d: Any, n_tests: int) -> tuple[tuple[float, ...], ...]:
    off = [int(d.sens_offset[i]) for i in range(n_tests + 1)]
    return tuple(tuple(float(d.sens[k]) for k in range(off[i], off[i + 1])) for i in range(n_tests))


# ------------------------------------------------------------------------------------------ results
@dataclass(frozen=True)
class MessageCounters:
    name: str
    can_id: int
    received: int
    accepted: int
    timeouts: int
    rejected: dict[str, int]


@dataclass(frozen=True)
class EcuCounters:
    frames: int
    rejected: dict[str, int]  # all IDs, by reason (REASONS)
    steps: int
    steps_skipped: int
    tx_frames: int
    messages: dict[str, MessageCounters]  # by message name

    @property
    def rejected_total(self) -> int:
        return sum(self.rejected.values())


@dataclass(frozen=True)
class EcuResult:
    step: int  # steps run so far (0: none)
    t_us: int  # time of the last step (wrapping uint32 microseconds)
    status: int  # FDI_Status of the diagnosis frame
    validity: int  # frame signal mask (the table's signals by bit) used by the last step
    alarm_mask: int
    evaluable_mask: int
    accused_mask: int  # tests accused in the current isolation episode (latched alarms)
    candidates: int  # fault bitmask (bit j = the table's fault j, TableInfo.faults)
    class_mask: int
    n_classes: int
    detected: bool
    isolated: bool
    iso_class: int  # FDI_IsolationClass as sent: 0 none, 1 + the class's lowest fault index, 255 not isolated
    test_status: tuple[str, ...]  # per test: ok / alarm / not_evaluable
    residuals: tuple[float, ...]
    ratios: tuple[float, ...]
    test_names: tuple[str, ...]
    sensitivities: tuple[tuple[float, ...], ...] = ()  # per test: d r / d f of its sens faults (with sensitivities)
    in_envelope: bool = True  # inside the table's calibrated envelope (outside, the isolation holds: fdi_diag.h)
    # per test: the adaptive threshold's term, the residual's worst-case spread over the model's uncertainty at the
    # step (units of r; the test alarms beyond gate * sigma + spread; 0 with the fixed gate)
    spreads: tuple[float, ...] = ()
    # per test: its on-line estimate's share of the residual, h . theta, removed before the evaluation (0: not
    # estimated; fdi_diag.h "On-line estimation")
    offsets: tuple[float, ...] = ()
    # per test: the estimated deviations of its estimable quantities, in its generator's order (the thresholds file's
    # [estimation]); () for a test without estimation
    estimates: tuple[tuple[float, ...], ...] = ()

    @property
    def status_name(self) -> str:
        return STATUS_NAMES.get(self.status, str(self.status))

    def candidate_labels(self, table: TableInfo) -> list[str]:
        """The names of the candidate faults (`table`: the table that made this result)."""
        return table.fault_labels(self.candidates)


@dataclass(frozen=True)
class Evidence:
    """The on-line exoneration's evidence after a step (fdi_diag_explain): why a fault is still a candidate.
    Entries of faults outside `undecided` are 0; outside an episode everything is."""

    episode_age: int  # steps since the episode's first alarm (0: no episode)
    undecided: int  # fault bitmask: the faults the exoneration can still change
    latched: int  # the class isolated first in the episode (0xFFFFFFFF: contradicted; 0: none yet)
    implied: tuple[float, ...]  # per fault: the size the alarms imply (0: no bound yet)
    cleared_run: tuple[int, ...]  # per fault: steps in a row the rule has cleared it
    cleared: int  # fault bitmask: exonerated at the step (on-line rule confirmed, or reaction sizes)
    clears: tuple[int, ...]  # per test: fault bitmask it clears alone at the implied sizes (its last decision)


# ------------------------------------------------------------------------------------------ the ECU
def _t_us(t: float) -> int:
    return round(t * 1e6) & 0xFFFFFFFF


class Ecu:
    """One ECU core instance (C struct in a ctypes buffer) of a vehicle with a bus (``--vehicle NAME|PATH``:
    ``"romo"``, its generated table, or ``"kin"``, on the ROMO bus generated from dbc/romo.dbc; or a vehicle folder
    whose plugin is built), listening to the vehicle's bus.

    Overrides: the vehicle's run-time generator parameters by name (ROMO: ``d_x``, ``d_y`` of the kinematic
    generators), ``cusum_k``, ``cusum_h``,
    ``set_count``, ``clear_count``, ``warmup_steps``, ``reentry_steps``, ``mode`` ("exoneration" | "no_exoneration"),
    ``episode_clear_steps``, ``noise_allowance``, ``sensitivities``, ``sens_every``, ``adaptive``, ``estimate`` (a
    test mask, MSO ids: "MSO1,MSO39", or "all": every test whose generator declares estimable quantities),
    ``estimate_kappa``, ``estimate_decorrelation``, ``estimate_startup`` (fdi_diag.h), ``timeout_s``
    (one value for all messages or a mapping message name -> seconds), ``max_delta_counter``,
    ``max_catchup_steps``, ``align_s`` (a step's signals are those of the instant ``align_s`` before it, fdi_ecu.h;
    0: sample-and-hold).
    """

    def __init__(self, table: str | Path = "romo", **overrides: Any) -> None:
        lib = _bus_lib(table)
        self._dll = lib.dll
        self._types = lib.types
        self.table = table_info(table)
        self.bus = bus_info(table)
        cfg = lib.types["Config"]()
        _check(self._dll.fdi_plugin_ecu_config_default(ctypes.byref(cfg)), "fdi_ecu_config_default")
        self._apply(self._dll, cfg, dict(overrides), self.bus.names, self.table.mso_ids, self.table.n_est)
        self.config = cfg
        self._buf = ctypes.create_string_buffer(lib.ecu_size)
        self._self = ctypes.cast(self._buf, ctypes.c_void_p)
        _check(self._dll.fdi_ecu_init(self._self, ctypes.byref(cfg)), "fdi_ecu_init")
        self._tx = lib.types["Tx"]()

    @staticmethod
    def _apply(dll: ctypes.CDLL, cfg: Any, ov: dict[str, Any], names: Sequence[str], mso_ids: Sequence[int],
               n_est: Sequence[int] = ()) -> None:
        _apply_diag(dll, cfg.diag, ov, mso_ids, n_est)
        if "timeout_s" in ov:
            to = ov.pop("timeout_s")
            items: Iterable[tuple[str, float]] = (
                to.items() if isinstance(to, Mapping) else ((n, float(to)) for n in names)
            )
            for name, sec in items:
                if name not in names:
                    raise ValueError(f"timeout_s: unknown message {name!r}; messages are {list(names)}")
                us = round(float(sec) * 1e6)
                if not 0 < us <= 0xFFFFFFFF:
                    raise ValueError(f"timeout_s[{name}] = {sec} s is not a positive time")
                cfg.timeout_us[names.index(name)] = us
        if "align_s" in ov:
            sec = float(ov.pop("align_s"))
            us = round(sec * 1e6)
            if not 0 <= us <= 0xFFFFFFFF:
                raise ValueError(f"align_s = {sec} s is not a time >= 0")
            cfg.align_us = us
        for key, hi in (("max_delta_counter", 0xFF), ("max_catchup_steps", 0xFFFF)):
            if key in ov:
                v = int(ov.pop(key))
                if not 0 <= v <= hi:
                    raise ValueError(f"{key} = {v} is outside 0..{hi}")
                setattr(cfg, key, v)
        if ov:
            raise TypeError(f"unknown Ecu option(s): {sorted(ov)}")

    @property
    def step_s(self) -> float:
        """The diagnosis step (the table's design dt) in seconds."""
        return self.table.dt

    def rx(self, can_id: int, data: bytes, t: float) -> None:
        """One received frame at time t [s]. Bad frames are counted (see counters()), not raised."""
        if not 0 <= can_id <= 0xFFFFFFFF:
            raise ValueError(f"CAN ID {can_id} is not a 32-bit value")
        raw = bytes(data)
        if len(raw) > 255:
            raise ValueError(f"frame of {len(raw)} bytes")
        _check(self._dll.fdi_ecu_rx(self._self, can_id, len(raw), raw, _t_us(t)), "fdi_ecu_rx")

    def poll(self, t: float) -> list[tuple[int, bytes]]:
        """Run the diagnosis steps due by t [s]; the diagnosis frame to send (0 or 1 of them)."""
        _check(self._dll.fdi_ecu_poll(self._self, _t_us(t), ctypes.byref(self._tx)), "fdi_ecu_poll")
        tx = self._tx
        return [(int(tx.frame[i].can_id), bytes(tx.frame[i].data[: tx.frame[i].dlc])) for i in range(tx.n_frames)]

    def process(self, frames: Iterable[tuple[float, int, bytes]]) -> list[tuple[float, int, bytes]]:
        """Offline replay: rx + poll for every (t, can_id, data), in C in one call (no Python per frame);
        returns the diagnosis frames with the time of the frame after which each was produced. Frames longer
        than 8 bytes count as bad DLC (as in rx)."""
        fl = list(frames)
        n = len(fl)
        ids = (ctypes.c_uint32 * n)()
        dlcs = (ctypes.c_uint8 * n)()
        times = (ctypes.c_uint32 * n)()
        buf = bytearray(8 * n)
        for k, (t, can_id, data) in enumerate(fl):
            if not 0 <= can_id <= 0xFFFFFFFF:
                raise ValueError(f"CAN ID {can_id} is not a 32-bit value")
            ids[k] = can_id
            times[k] = _t_us(t)
            dlcs[k] = min(len(data), 255)
            if len(data) <= 8:
                buf[8 * k : 8 * k + len(data)] = data
        data_arr = (ctypes.c_uint8 * (8 * n)).from_buffer(buf) if n else None
        out = (ctypes.c_uint8 * (8 * n))()
        out_idx = (ctypes.c_long * n)()
        m = int(self._dll.fdi_py_process(self._self, n, ids, dlcs, data_arr, times, out, out_idx, n))
        if m < 0:
            raise EcuError("fdi_ecu_rx/poll failed during process()")
        raw = bytes(out)
        return [(float(fl[out_idx[i]][0]), self.bus.diag_id, raw[8 * i : 8 * i + 8]) for i in range(m)]

    def process_arrays(self, t: Any, can_id: Any, dlc: Any, data: Any) -> tuple[NDArray[np.int64], bytes]:
        """`process` on frames held in arrays, for a whole log without Python work per frame: times [s], CAN
        IDs, payload lengths (above 8: bad DLC, as in rx) and payloads as n rows of 8 bytes (zero padded).
        Returns the index of the frame after which each diagnosis frame was produced, and their payloads
        (8 bytes each, concatenated)."""
        t_us = (np.rint(np.asarray(t, dtype=np.float64) * 1e6).astype(np.int64) & 0xFFFFFFFF).astype(np.uint32)
        n = t_us.size
        ids_in = np.asarray(can_id)
        if n and (ids_in.min() < 0 or ids_in.max() > 0xFFFFFFFF):
            raise ValueError("CAN IDs must be 32-bit values")
        ids = np.ascontiguousarray(ids_in, dtype=np.uint32)
        dlcs = np.ascontiguousarray(np.minimum(np.asarray(dlc), 255), dtype=np.uint8)
        raw_in = np.ascontiguousarray(np.frombuffer(data, dtype=np.uint8) if isinstance(data, bytes | bytearray)
                                      else np.asarray(data, dtype=np.uint8).reshape(-1))
        if not ids.size == dlcs.size == n or raw_in.size != 8 * n:
            raise ValueError(f"process_arrays: {n} times, {ids.size} IDs, {dlcs.size} lengths, {raw_in.size} bytes "
                             "(8 per frame)")
        out = np.zeros(8 * n, dtype=np.uint8)
        out_idx = np.zeros(n, dtype=np.int64 if ctypes.sizeof(ctypes.c_long) == 8 else np.int32)
        m = int(self._dll.fdi_py_process(self._self, n, ids.ctypes.data, dlcs.ctypes.data, raw_in.ctypes.data,
                                         t_us.ctypes.data, out.ctypes.data, out_idx.ctypes.data, n))
        if m < 0:
            raise EcuError("fdi_ecu_rx/poll failed during process_arrays()")
        return out_idx[:m].astype(np.int64), out[: 8 * m].tobytes()

    def counters(self) -> EcuCounters:
        c = self._types["Counters"]()
        _check(self._dll.fdi_ecu_counters(self._self, ctypes.byref(c)), "fdi_ecu_counters")
        msgs = {}
        for i, (name, _) in enumerate(self.bus.messages):
            m = c.msg[i]
            msgs[name] = MessageCounters(
                name, int(m.can_id), int(m.received), int(m.accepted), int(m.timeouts),
                {r: int(m.rejected[k]) for k, r in enumerate(REASONS)},
            )
        return EcuCounters(
            int(c.frames), {r: int(c.rejected[k]) for k, r in enumerate(REASONS)}, int(c.steps),
            int(c.steps_skipped), int(c.tx_frames), msgs,
        )

    def explain(self) -> Evidence:
        """The exoneration's evidence after the last step (fdi_diag_explain of the ECU's diagnoser)."""
        e = self._types["Evidence"]()
        _check(self._dll.fdi_py_ecu_explain(self._self, ctypes.byref(e)), "fdi_diag_explain")
        nf = self.table.n_faults
        return Evidence(
            episode_age=int(e.episode_age), undecided=int(e.undecided), latched=int(e.latched),
            implied=tuple(float(e.implied[j]) for j in range(nf)),
            cleared_run=tuple(int(e.cleared_run[j]) for j in range(nf)), cleared=int(e.cleared),
            clears=tuple(int(e.clears[i]) for i in range(self.table.n_tests)),
        )

    def result(self) -> EcuResult:
        r = self._types["Result"]()
        _check(self._dll.fdi_ecu_result(self._self, ctypes.byref(r)), "fdi_ecu_result")
        d = r.diag
        n = self.table.n_tests
        return EcuResult(
            step=int(r.step), t_us=int(r.t_us), status=int(r.status), validity=int(r.validity),
            alarm_mask=int(d.alarm_mask), evaluable_mask=int(d.evaluable_mask), accused_mask=int(d.accused_mask),
            candidates=int(d.iso.candidates), class_mask=int(d.iso.class_mask), n_classes=int(d.iso.n_classes),
            detected=bool(d.iso.detected), isolated=bool(d.iso.isolated), iso_class=int(r.iso_class),
            test_status=tuple(TEST_STATUS_NAMES[int(d.status[i])] for i in range(n)),
            residuals=tuple(float(d.residual[i]) for i in range(n)),
            ratios=tuple(float(d.ratio[i]) for i in range(n)),
            spreads=tuple(float(d.spread[i]) for i in range(n)),
            offsets=tuple(float(d.offset[i]) for i in range(n)),
            estimates=_estimates(d, self.table),
            test_names=self.table.test_names,
            sensitivities=_sensitivities(d, n),
            in_envelope=bool(d.in_envelope),
        )


# ------------------------------------------------------------------------------------------ the diagnoser alone
FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class DiagRun:
    """The diagnoser over a sequence of frames: per step and test the residual, per test its sensitivities
    (columns in `TableInfo.sens_faults` order; empty without sensitivities), and the result after every step."""

    residuals: FloatArray  # [step, test]
    sensitivities: tuple[FloatArray, ...]  # per test: [step, sensitivity]
    results: tuple[EcuResult, ...]


class Diagnoser:
    """The generic diagnoser (fw/include/fdi_diag.h) on a table without a bus (``"three_tank"``, or any built-in
    table): frames of the table's signals in, alarms, isolation and sensitivities out, one step per frame.
    Overrides as `Ecu` (no bus options); defaults fdi_diag_config_default."""

    def __init__(self, table: str | Path, **overrides: Any) -> None:
        lib = _lib(table)
        self._dll = lib.dll
        self._types = lib.types
        self._caps = lib.caps
        self.table = table_info(table)
        cfg = lib.types["DiagConfig"]()
        _check(self._dll.fdi_diag_config_default(ctypes.byref(cfg), lib.table), "fdi_diag_config_default")
        ov = dict(overrides)
        _apply_diag(self._dll, cfg, ov, self.table.mso_ids, self.table.n_est)
        if ov:
            raise TypeError(f"unknown Diagnoser option(s): {sorted(ov)}")
        self.config = cfg
        self._buf = ctypes.create_string_buffer(lib.diag_size)
        self._self = ctypes.cast(self._buf, ctypes.c_void_p)
        _check(self._dll.fdi_py_diag_init(self._self, ctypes.byref(cfg)), "fdi_diag_init")
        self._steps = 0

    def _frames(self, signals: Mapping[str, Any]) -> NDArray[np.float32]:
        names = self.table.signal_names
        unknown = set(signals) - set(names)
        if unknown:
            raise ValueError(f"not signals of table {self.table.name}: {sorted(unknown)}; its signals are {names}")
        n = len(next(iter(signals.values())))
        cols = [np.asarray(signals[s], dtype=np.float32) if s in signals else np.full(n, np.nan, np.float32)
                for s in names]
        return np.ascontiguousarray(np.column_stack(cols), dtype=np.float32)

    def _result(self) -> EcuResult:
        r = self._types["DiagResult"]()
        _check(self._dll.fdi_diag_result(self._self, ctypes.byref(r)), "fdi_diag_result")
        n = self.table.n_tests
        return EcuResult(
            step=self._steps, t_us=0, status=0, validity=0, alarm_mask=int(r.alarm_mask),
            evaluable_mask=int(r.evaluable_mask), accused_mask=int(r.accused_mask),
            candidates=int(r.iso.candidates), class_mask=int(r.iso.class_mask), n_classes=int(r.iso.n_classes),
            detected=bool(r.iso.detected), isolated=bool(r.iso.isolated), iso_class=0,
            test_status=tuple(TEST_STATUS_NAMES[int(r.status[i])] for i in range(n)),
            residuals=tuple(float(r.residual[i]) for i in range(n)), ratios=tuple(float(r.ratio[i]) for i in range(n)),
            spreads=tuple(float(r.spread[i]) for i in range(n)), offsets=tuple(float(r.offset[i]) for i in range(n)),
            estimates=_estimates(r, self.table),
            test_names=self.table.test_names, sensitivities=_sensitivities(r, n), in_envelope=bool(r.in_envelope))

    def step(self, values: Mapping[str, float], validity: int | None = None) -> EcuResult:
        """One step with one frame (signals by name; a missing one is invalid); validity default: every signal
        given."""
        frame = self._frames({k: [v] for k, v in values.items()})[0]
        sf = self._types["SignalFrame"]()
        for i, v in enumerate(frame.tolist()):
            sf.value[i] = v
        names = self.table.signal_names
        valid = sum(1 << i for i, s in enumerate(names) if s in values) if validity is None else validity
        _check(self._dll.fdi_diag_step(self._self, ctypes.byref(sf), valid), "fdi_diag_step")
        self._steps += 1
        return self._result()

    def run(self, signals: Mapping[str, Any], results: bool = True) -> DiagRun:
        """One step per sample of `signals` (the table's signals by name, equal lengths; a signal not given is
        invalid): the residuals and sensitivities in one C call per batch, and with `results` the result after
        every step (slower: one call per step)."""
        frames = self._frames(signals)
        n, ns = frames.shape
        valid = sum(1 << i for i, s in enumerate(self.table.signal_names) if s in signals)
        validity = np.full(n, valid, dtype=np.uint32)
        caps = self._caps
        out_r = np.zeros((n, caps.max_tests), dtype=np.float32)
        out_s = np.zeros((n, caps.max_sens), dtype=np.float32)
        res: list[EcuResult] = []
        chunk = 1 if results else max(n, 1)
        for a in range(0, n, chunk):
            b = min(n, a + chunk)
            m = int(self._dll.fdi_py_diag_run(
                self._self, b - a, ns, frames[a:b].ctypes.data, validity[a:b].ctypes.data,
                out_r[a:b].ctypes.data, out_s[a:b].ctypes.data))
            if m != b - a:
                raise EcuError("fdi_diag_step failed during run()")
            self._steps += m
            if results:
                res.append(self._result())
        nt = self.table.n_tests
        counts = [len(self.table.sens_faults(i)) if bool(self.config.sensitivities) else 0 for i in range(nt)]
        starts = np.cumsum([0, *counts])
        sens = tuple(out_s[:, starts[i]:starts[i + 1]].astype(np.float64) for i in range(nt))
        return DiagRun(out_r[:, :nt].astype(np.float64), sens, tuple(res))
