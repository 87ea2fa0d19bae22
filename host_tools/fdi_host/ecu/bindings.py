"""Python bindings (ctypes) of the C ECU core `fw/ecu` and the fw/ diagnoser: an ECU process on any CAN interface.

The shared library is the extension ``fdi_host.ecu._fdi_ecu`` that ``pip install -e .`` builds from fw/src,
fw/generated, fw/generated/can and fw/ecu/src (see setup.py); this module loads it with `ctypes.CDLL` and wraps
the C API of ``fw/ecu/include/fdi_ecu.h``::

    ecu = Ecu("kin")                       # or Ecu("romo", warmup_steps=400, timeout_s={"IMU_Motion": 0.02})
    for t, can_id, data in frames:         # t in seconds (monotonic)
        ecu.rx(can_id, data, t)
        for fid, payload in ecu.poll(t):   # FDI_Diagnosis frames (ID 512) to send
            bus.send(...)
    ecu.result().candidates, ecu.counters().rejected

Semantics (frame checks, timeouts, fixed steps at the table's dt, the diagnosis frame) are those of the C core:
a step at T_k sees exactly the frames with t <= T_k, whatever the poll pattern. Times are converted to wrapping
uint32 microseconds.
"""

from __future__ import annotations

import ctypes
import importlib.util
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from functools import cache
from typing import Any

REASONS: tuple[str, ...] = (
    "unknown_id", "own_frame", "bad_dlc", "bad_crc", "out_of_range", "repeated_counter", "counter_jump",
    "sensor_status",
)
MESSAGES: tuple[tuple[str, int], ...] = (
    ("MotionDemand", 80), ("IMU_Motion", 128), ("VelocitySensor", 136), ("WheelRobot1", 256),
    ("WheelRobot2", 257), ("WheelRobot3", 258), ("WheelRobot4", 259), ("BrakeByWire", 272),
)
STATUS_NAMES: dict[int, str] = {
    0: "INIT", 1: "NO_FAULT", 2: "FAULT_DETECTED", 3: "FAULT_ISOLATED", 4: "INPUT_INVALID", 15: "INVALID",
}
TEST_STATUS_NAMES: tuple[str, ...] = ("ok", "alarm", "not_evaluable")
DIAG_ID = 512
TABLES = ("kin", "romo")
_N_MSGS = len(MESSAGES)
_N_REASONS = len(REASONS)
_MODES = {"no_exoneration": 0, "exoneration": 1}


class EcuError(RuntimeError):
    """A call of the C core returned an error status."""


_STATUS = {0: "OK", 1: "BAD_ARG", 2: "NOT_FINITE", 3: "BAD_TABLE"}


def _check(st: int, what: str) -> None:
    if st != 0:
        raise EcuError(f"{what} failed: {_STATUS.get(st, str(st))}")


# ------------------------------------------------------------------------------------------ ctypes mirrors
def _struct_types(max_tests: int) -> dict[str, type[ctypes.Structure]]:
    class DiagConfig(ctypes.Structure):
        _fields_ = [
            ("table", ctypes.c_void_p), ("d_x", ctypes.c_float), ("d_y", ctypes.c_float),
            ("cusum_k", ctypes.c_float), ("cusum_h", ctypes.c_float), ("set_count", ctypes.c_uint16),
            ("clear_count", ctypes.c_uint16), ("warmup_steps", ctypes.c_uint16), ("mode", ctypes.c_int),
            ("iso_settle_steps", ctypes.c_uint16), ("episode_clear_steps", ctypes.c_uint16),
        ]

    class Config(ctypes.Structure):
        _fields_ = [
            ("diag", DiagConfig), ("timeout_us", ctypes.c_uint32 * _N_MSGS),
            ("max_delta_counter", ctypes.c_uint8), ("max_catchup_steps", ctypes.c_uint16),
        ]

    class MsgCounters(ctypes.Structure):
        _fields_ = [
            ("can_id", ctypes.c_uint32), ("received", ctypes.c_uint32), ("accepted", ctypes.c_uint32),
            ("timeouts", ctypes.c_uint32), ("rejected", ctypes.c_uint32 * _N_REASONS),
        ]

    class Counters(ctypes.Structure):
        _fields_ = [
            ("frames", ctypes.c_uint32), ("rejected", ctypes.c_uint32 * _N_REASONS), ("steps", ctypes.c_uint32),
            ("steps_skipped", ctypes.c_uint32), ("tx_frames", ctypes.c_uint32), ("msg", MsgCounters * _N_MSGS),
        ]

    class IsoResult(ctypes.Structure):
        _fields_ = [
            ("candidates", ctypes.c_uint32), ("class_mask", ctypes.c_uint32), ("n_classes", ctypes.c_uint8),
            ("detected", ctypes.c_bool), ("isolated", ctypes.c_bool),
        ]

    class DiagResult(ctypes.Structure):
        _fields_ = [
            ("n_tests", ctypes.c_uint8), ("alarm_mask", ctypes.c_uint32), ("evaluable_mask", ctypes.c_uint32),
            ("status", ctypes.c_int * max_tests), ("residual", ctypes.c_float * max_tests),
            ("ratio", ctypes.c_float * max_tests), ("accused_mask", ctypes.c_uint32), ("iso", IsoResult),
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

    return {"Config": Config, "Counters": Counters, "Result": Result, "Tx": Tx, "DiagResult": DiagResult}


@dataclass(frozen=True)
class _Lib:
    dll: ctypes.CDLL
    types: dict[str, type[ctypes.Structure]]
    ecu_size: int


@cache
def _lib() -> _Lib:
    spec = importlib.util.find_spec("fdi_host.ecu._fdi_ecu")
    if spec is None or spec.origin is None:
        raise ImportError("fdi_host.ecu._fdi_ecu is not built: run `pip install -e .` (scripts/bootstrap.sh)")
    dll = ctypes.CDLL(spec.origin)
    dll.fdi_py_sizeof.restype = ctypes.c_size_t
    dll.fdi_py_sizeof.argtypes = [ctypes.c_int]
    max_tests = int(dll.fdi_py_sizeof(7))
    types = _struct_types(max_tests)
    for what, name in ((1, "Config"), (2, "Counters"), (3, "Result"), (4, "Tx")):
        c_size, py_size = int(dll.fdi_py_sizeof(what)), ctypes.sizeof(types[name])
        if c_size != py_size:
            raise ImportError(f"fdi_host.ecu.bindings: ctypes mirror of {name} has {py_size} bytes, C has {c_size}")
    if int(dll.fdi_py_sizeof(5)) != types["Result"].diag.offset:
        raise ImportError("fdi_host.ecu.bindings: layout of fdi_ecu_result_t differs from its ctypes mirror")
    if int(dll.fdi_py_sizeof(6)) != types["DiagResult"].iso.offset:
        raise ImportError("fdi_host.ecu.bindings: layout of fdi_diag_result_t differs from its ctypes mirror")
    vp, st = ctypes.c_void_p, ctypes.c_int
    sigs: dict[str, tuple[Any, list[Any]]] = {
        "fdi_py_table": (vp, [ctypes.c_char_p]),
        "fdi_py_table_int": (ctypes.c_longlong, [vp, ctypes.c_int, ctypes.c_int]),
        "fdi_py_table_str": (ctypes.c_char_p, [vp, ctypes.c_int, ctypes.c_int]),
        "fdi_ecu_config_default": (st, [vp, vp]),
        "fdi_ecu_init": (st, [vp, vp]),
        "fdi_ecu_rx": (st, [vp, ctypes.c_uint32, ctypes.c_uint8, ctypes.c_char_p, ctypes.c_uint32]),
        "fdi_ecu_poll": (st, [vp, ctypes.c_uint32, vp]),
        "fdi_ecu_counters": (st, [vp, vp]),
        "fdi_ecu_result": (st, [vp, vp]),
        "fdi_py_process": (ctypes.c_long, [vp, ctypes.c_long, vp, vp, vp, vp, vp, vp, ctypes.c_long]),
    }
    for name, (res, args) in sigs.items():
        fn = getattr(dll, name)
        fn.restype = res
        fn.argtypes = args
    return _Lib(dll, types, int(dll.fdi_py_sizeof(0)))


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

    @property
    def n_tests(self) -> int:
        return len(self.mso_ids)

    def fault_labels(self, mask: int) -> list[str]:
        """Short labels ("f4") of the faults in a bitmask."""
        return [f"f{j + 1}" for j in range(self.n_faults) if mask >> j & 1]


def _table_ptr(name: str) -> int:
    if name not in TABLES:
        raise ValueError(f"unknown table {name!r}; use one of {TABLES}")
    ptr = _lib().dll.fdi_py_table(name.encode())
    if not ptr:
        raise EcuError(f"table {name!r} is not in the library")
    return int(ptr)


@cache
def table_info(name: str) -> TableInfo:
    dll = _lib().dll
    t = _table_ptr(name)
    nf, nt = int(dll.fdi_py_table_int(t, 0, 0)), int(dll.fdi_py_table_int(t, 1, 0))

    def ints(what: int, n: int) -> tuple[int, ...]:
        return tuple(int(dll.fdi_py_table_int(t, what, i)) for i in range(n))

    def strs(what: int, n: int) -> tuple[str, ...]:
        return tuple((dll.fdi_py_table_str(t, what, i) or b"").decode() for i in range(n))

    mso = ints(2, nt)
    interp = strs(1, nt)
    return TableInfo(
        name=name, n_faults=nf, fault_names=strs(0, nf),
        test_names=tuple(f"MSO{m}: {s}" for m, s in zip(mso, interp, strict=True)), mso_ids=mso,
        test_fault_masks=ints(4, nt), test_input_masks=ints(5, nt),
        has_generator=tuple(k != 0 for k in ints(3, nt)), iso_class=ints(6, nf),
        dt=int(dll.fdi_py_table_int(t, 8, 0)) * 1e-6,
    )


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
    validity: int  # FDI_SIGM_* mask used by the last step
    alarm_mask: int
    evaluable_mask: int
    accused_mask: int  # tests accused in the current isolation episode (latched alarms)
    candidates: int  # fault bitmask (bit j = fault f(j+1))
    class_mask: int
    n_classes: int
    detected: bool
    isolated: bool
    iso_class: int  # FDI_IsolationClass as sent: 0 none, 1..25 lowest fault of the class, 255 not isolated
    test_status: tuple[str, ...]  # per test: ok / alarm / not_evaluable
    residuals: tuple[float, ...]
    ratios: tuple[float, ...]
    test_names: tuple[str, ...]

    @property
    def status_name(self) -> str:
        return STATUS_NAMES.get(self.status, str(self.status))

    def candidate_labels(self) -> list[str]:
        return [f"f{j + 1}" for j in range(32) if self.candidates >> j & 1]


# ------------------------------------------------------------------------------------------ the ECU
def _t_us(t: float) -> int:
    return round(t * 1e6) & 0xFFFFFFFF


class Ecu:
    """One ECU core instance (C struct in a ctypes buffer) on table ``"romo"`` (generated) or ``"kin"``.

    Overrides: ``d_x``, ``d_y``, ``cusum_k``, ``cusum_h``, ``set_count``, ``clear_count``, ``warmup_steps``,
    ``mode`` ("exoneration" | "no_exoneration"), ``iso_settle_steps``, ``episode_clear_steps`` (fdi_diag.h),
    ``timeout_s`` (one value for all messages or a mapping
    message name -> seconds), ``max_delta_counter``, ``max_catchup_steps``.
    """

    def __init__(self, table: str = "romo", **overrides: Any) -> None:
        lib = _lib()
        self._dll = lib.dll
        self._types = lib.types
        self.table = table_info(table)
        cfg = lib.types["Config"]()
        _check(self._dll.fdi_ecu_config_default(ctypes.byref(cfg), _table_ptr(table)), "fdi_ecu_config_default")
        self._apply(cfg, dict(overrides))
        self.config = cfg
        self._buf = ctypes.create_string_buffer(lib.ecu_size)
        self._self = ctypes.cast(self._buf, ctypes.c_void_p)
        _check(self._dll.fdi_ecu_init(self._self, ctypes.byref(cfg)), "fdi_ecu_init")
        self._tx = lib.types["Tx"]()

    @staticmethod
    def _apply(cfg: Any, ov: dict[str, Any]) -> None:
        d = cfg.diag
        for key in ("d_x", "d_y", "cusum_k", "cusum_h"):
            if key in ov:
                setattr(d, key, float(ov.pop(key)))
        for key in ("set_count", "clear_count", "warmup_steps", "iso_settle_steps", "episode_clear_steps"):
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
        if "timeout_s" in ov:
            to = ov.pop("timeout_s")
            names = [n for n, _ in MESSAGES]
            items: Iterable[tuple[str, float]] = (
                to.items() if isinstance(to, Mapping) else ((n, float(to)) for n in names)
            )
            for name, sec in items:
                if name not in names:
                    raise ValueError(f"timeout_s: unknown message {name!r}; messages are {names}")
                us = round(float(sec) * 1e6)
                if not 0 < us <= 0xFFFFFFFF:
                    raise ValueError(f"timeout_s[{name}] = {sec} s is not a positive time")
                cfg.timeout_us[names.index(name)] = us
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
        return [(float(fl[out_idx[i]][0]), DIAG_ID, raw[8 * i : 8 * i + 8]) for i in range(m)]

    def counters(self) -> EcuCounters:
        c = self._types["Counters"]()
        _check(self._dll.fdi_ecu_counters(self._self, ctypes.byref(c)), "fdi_ecu_counters")
        msgs = {}
        for i, (name, _) in enumerate(MESSAGES):
            m = c.msg[i]
            msgs[name] = MessageCounters(
                name, int(m.can_id), int(m.received), int(m.accepted), int(m.timeouts),
                {r: int(m.rejected[k]) for k, r in enumerate(REASONS)},
            )
        return EcuCounters(
            int(c.frames), {r: int(c.rejected[k]) for k, r in enumerate(REASONS)}, int(c.steps),
            int(c.steps_skipped), int(c.tx_frames), msgs,
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
            test_names=self.table.test_names,
        )
