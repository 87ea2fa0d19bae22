"""Opening a python-can bus from command-line options, reading frames from it, and a stop flag set by
SIGINT/SIGTERM.

The same options everywhere (`add_bus_arguments`): python-can's full configuration, as ``can.Bus()`` takes it.
``--interface`` and ``--channel`` (any python-can interface: ``socketcan`` with ``can0``/``vcan0``, ``pcan``,
``kvaser``, ``vector``, ``slcan``, ``virtual`` in one process, ``udp_multicast`` ...), ``--bitrate``, ``--fd``,
``--data-bitrate``, ``--bus-arg KEY=VALUE`` for any other keyword argument of the interface (typed: integers,
floats, true/false; a quoted value stays text), and python-can's configuration: a file given with
``--can-config FILE`` (its section ``--can-context``, else ``[default]``), otherwise python-can's own files
(``~/can.conf``, ``/etc/can.conf``, ``~/.can``, ``~/.canrc``; ``can.ini`` on Windows), and the environment
(``CAN_INTERFACE``, ``CAN_CHANNEL``, ``CAN_BITRATE``, ``CAN_CONFIG``). The command line comes first, then the
configuration in python-can's order (`resolve_bus`, with ``can.util.load_config``).

Without any of them the bus is SocketCAN ``vcan0`` where the kernel has AF_CAN and the interface exists, and
otherwise the simulated bus, python-can's ``udp_multicast`` on group 239.74.163.2 (it works across processes,
inside a private network namespace too), with a one-line note saying why (`default_bus`).

Reading (`frame_reader`): every frame as ``(can_id, data, timestamp)`` with the SocketCAN flags in the ID
(`CAN_EFF_FLAG` for a 29-bit ID, `CAN_RTR_FLAG`, `CAN_ERR_FLAG`), as the SocketCAN ECU program hands raw IDs
to the C core, which counts flagged frames as unknown IDs; through python-can's public API on every interface:
``bus.recv`` waits for the first frame, then ``bus.recv(timeout=0)`` takes every frame already queued, so that a
burst costs one wake-up (`BusReader`).
"""

from __future__ import annotations

import argparse
import configparser
import os
import re
import resource
import signal
import socket
import struct
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import Any, NamedTuple

import can

from fdi_analysis.cli.common import fail, one_line
from fdi_host.errors import FdiHostError
from fdi_host.live.netns import have_af_can, vcan_available

SIMULATED_INTERFACE = "udp_multicast"  # the simulated bus: works across processes without a CAN kernel
DEFAULT_INTERFACE = SIMULATED_INTERFACE  # kept for callers: the interface of the fallback bus
DEFAULT_CHANNEL = "239.74.163.2"  # its multicast group
VCAN_CHANNEL = "vcan0"
CHANNEL_DEFAULTS = {SIMULATED_INTERFACE: DEFAULT_CHANNEL, "socketcan": VCAN_CHANNEL, "virtual": "0"}
CAN_EFF_FLAG = 0x80000000  # SocketCAN's flags in the raw can_id (linux/can.h)
CAN_RTR_FLAG = 0x40000000
CAN_ERR_FLAG = 0x20000000
CAN_EFF_MASK = 0x1FFFFFFF
RxFrame = tuple[int, bytes, float]  # (can_id with SocketCAN flags, payload, receive time [s, wall clock])
BusValue = str | int | float | bool
# What opening a bus raises for a bad configuration or an adapter that is missing or busy
BUS_ERRORS: tuple[type[BaseException], ...] = (OSError, ValueError, ImportError, TypeError, can.CanError,
                                                configparser.Error)
# --bus-arg keys that have an option of their own, or that would change how the configuration is read
_OWN_OPTION = {"interface": "--interface", "bustype": "--interface", "channel": "--channel",
               "bitrate": "--bitrate", "fd": "--fd", "data_bitrate": "--data-bitrate",
               "config_context": "--can-context", "ignore_config": "--can-config", "context": "--can-context"}
_KEY = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")

BUS_HELP = """\
The bus is python-can's, configured as can.Bus() is: these options first, then python-can's configuration
(--can-config FILE, else ~/can.conf, /etc/can.conf, ~/.can, ~/.canrc, on Windows can.ini; the environment
variables CAN_INTERFACE, CAN_CHANNEL, CAN_BITRATE and CAN_CONFIG). With none of them: SocketCAN vcan0 where
the kernel has it, else the simulated bus (udp_multicast 239.74.163.2), with a note. Examples:
  --interface pcan --channel PCAN_USBBUS1 --bitrate 500000
  --interface slcan --channel /dev/ttyACM0 --bitrate 500000
  --interface kvaser --channel 0 --fd --bitrate 500000 --data-bitrate 2000000
  --interface vector --channel 0 --bitrate 500000 --bus-arg app_name=CANalyzer
  --interface socketcan --channel can0                         (bitrate: set with ip link)
  --can-config bus.ini --can-context vehicle                   (bus.ini: [vehicle] interface = pcan ...)
"""


class BusConfigError(FdiHostError, ValueError):
    """Bus options or a python-can configuration that cannot be used (a missing file or section, a bad value)."""


class BusArg(NamedTuple):
    """One ``--bus-arg KEY=VALUE``: the keyword argument, its typed value, and the text as given."""

    key: str
    value: BusValue
    text: str


def parse_bus_value(text: str) -> BusValue:
    """A --bus-arg value typed as python-can's configuration files are (`can.util.cast_from_string`), plus
    hexadecimal integers (0x1F) and yes/no/on/off: an integer, a float, a bool, or text (a value in quotes stays
    text: '"0012"')."""
    if len(text) >= 2 and text[0] == text[-1] and text[0] in "\"'":
        return text[1:-1]
    if re.fullmatch(r"[-+]?0[xX][0-9a-fA-F]+", text):
        return int(text, 16)
    lowered = text.lower()
    if lowered in ("yes", "on"):
        return True
    if lowered in ("no", "off"):
        return False
    return can.util.cast_from_string(text)


def parse_bus_arg(text: str) -> BusArg:
    """``KEY=VALUE`` -> a `BusArg` (argparse type of ``--bus-arg``)."""
    key, sep, value = text.partition("=")
    key = key.strip()
    if not sep or not _KEY.fullmatch(key):
        raise argparse.ArgumentTypeError(f"{text!r}: expected KEY=VALUE, e.g. receive_own_messages=true")
    if key in _OWN_OPTION:
        raise argparse.ArgumentTypeError(f"{text!r}: use {_OWN_OPTION[key]} for {key}")
    return BusArg(key, parse_bus_value(value.strip()), text)


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: a whole number of bit/s, e.g. 500000") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r}: must be > 0")
    return value


def add_bus_arguments(ap: argparse.ArgumentParser) -> None:
    """The bus options of every program that opens a bus (`BusOptions.from_args` reads them back)."""
    g = ap.add_argument_group("CAN bus (python-can)", BUS_HELP)
    g.add_argument("--interface", default=None,
                   help="python-can interface: socketcan, pcan, kvaser, vector, slcan, virtual, udp_multicast, ... "
                   "(default: python-can's configuration, else vcan0 or the simulated bus, see above)")
    g.add_argument("--channel", default=None,
                   help=f"channel: can0/vcan0 for socketcan, PCAN_USBBUS1 for pcan, a serial port for slcan, the "
                   f"multicast group for udp_multicast (default {DEFAULT_CHANNEL}), ...")
    g.add_argument("--bitrate", type=_positive_int, metavar="BIT/S", help="bit rate, e.g. 500000")
    g.add_argument("--fd", action=argparse.BooleanOptionalAction, default=None,
                   help="CAN FD (python-can's fd=True); --no-fd: classic CAN")
    g.add_argument("--data-bitrate", type=_positive_int, metavar="BIT/S",
                   help="CAN FD data phase bit rate, e.g. 2000000")
    g.add_argument("--bus-arg", type=parse_bus_arg, action="append", default=[], metavar="KEY=VALUE",
                   help="any other keyword argument of the interface, typed (123, 0x1F, 1.5, true; quoted: "
                   "text), repeatable: --bus-arg receive_own_messages=true --bus-arg app_name=CANalyzer")
    g.add_argument("--can-config", type=Path, metavar="FILE",
                   help="python-can configuration file to read (instead of python-can's own: ~/.canrc, ...)")
    g.add_argument("--can-context", metavar="SECTION",
                   help="its section (default [default]); also the suffix of the environment variables, "
                   "CAN_INTERFACE_<SECTION> and so on (python-can's config_context)")


@dataclass(frozen=True)
class BusOptions:
    """What a command line says about the bus (None: not given); the rest comes from python-can's configuration."""

    interface: str | None = None
    channel: str | None = None
    bitrate: int | None = None
    fd: bool | None = None
    data_bitrate: int | None = None
    args: tuple[BusArg, ...] = ()
    config_file: Path | None = None
    context: str | None = None

    @classmethod
    def from_args(cls, args: argparse.Namespace) -> BusOptions:
        """The options `add_bus_arguments` added, as parsed."""
        return cls(args.interface, args.channel, args.bitrate, args.fd, args.data_bitrate, tuple(args.bus_arg),
                   args.can_config, args.can_context)

    @property
    def given(self) -> bool:
        """Whether any bus option was given on the command line."""
        return self != BusOptions()

    def kwargs(self) -> dict[str, Any]:
        """The keyword arguments for can.Bus the command line gives."""
        out: dict[str, Any] = {k: v for k, v in (("interface", self.interface), ("channel", self.channel),
                                                 ("bitrate", self.bitrate), ("fd", self.fd),
                                                 ("data_bitrate", self.data_bitrate)) if v is not None}
        out.update((a.key, a.value) for a in self.args)
        return out

    def argv(self) -> list[str]:
        """These options as command-line arguments again (for the programs ``fdi-live`` starts)."""
        out: list[str] = []
        for flag, value in (("--interface", self.interface), ("--channel", self.channel),
                            ("--bitrate", self.bitrate), ("--data-bitrate", self.data_bitrate),
                            ("--can-config", self.config_file), ("--can-context", self.context)):
            if value is not None:
                out += [flag, str(value)]
        if self.fd is not None:
            out.append("--fd" if self.fd else "--no-fd")
        for a in self.args:
            out += ["--bus-arg", a.text]
        return out


@dataclass(frozen=True)
class BusConfig:
    """A resolved bus: the keyword arguments for ``can.Bus`` (`kwargs`, with ``interface``), where they came from
    (`source`: command line, python-can configuration, or default) and the note of a fallback."""

    kwargs: dict[str, Any]
    source: str
    note: str | None = None

    @property
    def interface(self) -> str:
        return str(self.kwargs["interface"])

    @property
    def channel(self) -> Any:
        return self.kwargs.get("channel")

    def describe(self) -> str:
        """The bus in a few words: ``pcan PCAN_USBBUS1 (500 kbit/s, FD data 2000 kbit/s)``."""
        text = self.interface if self.channel is None else f"{self.interface} {self.channel}"
        rates = []
        if self.kwargs.get("bitrate"):
            rates.append(f"{self.kwargs['bitrate'] / 1000:g} kbit/s")
        if self.kwargs.get("fd"):
            data = self.kwargs.get("data_bitrate")
            rates.append(f"FD{f' data {data / 1000:g} kbit/s' if data else ''}")
        if self.interface == SIMULATED_INTERFACE:
            rates.append("the simulated bus")
        return f"{text} ({', '.join(rates)})" if rates else text

    def open(self) -> can.BusABC:
        """The bus; raises one of `BUS_ERRORS` with python-can's message if it cannot be opened."""
        return can.Bus(ignore_config=True, **self.kwargs)


def vcan_missing() -> str | None:
    """Why SocketCAN vcan0 cannot be used here (no AF_CAN in the kernel, no such interface), None if it can."""
    if vcan_available(VCAN_CHANNEL):
        return None
    if not have_af_can():
        return "the kernel has no AF_CAN"
    return f"no {VCAN_CHANNEL} interface (ip link add {VCAN_CHANNEL} type vcan && ip link set {VCAN_CHANNEL} up)"


def default_bus() -> tuple[str, str, str | None]:
    """The bus when nothing names one: (interface, channel, note). SocketCAN vcan0 where the kernel has AF_CAN
    and the interface exists; otherwise the simulated bus, with a note saying why (never a bus called vcan that
    is not one)."""
    why = vcan_missing()
    if why is None:
        return "socketcan", VCAN_CHANNEL, None
    return SIMULATED_INTERFACE, DEFAULT_CHANNEL, (f"no SocketCAN {VCAN_CHANNEL} ({why}); on the simulated bus, "
                                                  f"python-can {SIMULATED_INTERFACE} {DEFAULT_CHANNEL}")


def _check_config_file(options: BusOptions) -> None:
    """A --can-config file must exist (python-can skips a missing one silently) and hold the --can-context."""
    path = options.config_file
    if path is None:
        return
    if not path.is_file():
        raise BusConfigError(f"{path}: no such python-can configuration file")
    parser = configparser.ConfigParser()
    parser.read(path)
    if options.context is not None and not parser.has_section(options.context):
        sections = ", ".join(f"[{s}]" for s in parser.sections()) or "none"
        raise BusConfigError(f"{path}: no section [{options.context}] (its sections: {sections})")


def configured_interface(options: BusOptions) -> str | None:
    """The interface python-can's configuration names, in its order (`can.util.load_config`): the module's
    ``can.rc``, the environment (with the context's suffix, then without), the configuration file (its context's
    section, then [default]); None if none does."""
    sources = [dict(can.rc), can.util.load_environment_config(options.context), can.util.load_environment_config(),
               *(can.util.load_file_config(options.config_file, section)
                 for section in ((options.context, "default") if options.context else ("default",)))]
    for cfg in sources:
        name = cfg.get("interface") or cfg.get("bustype")
        if name:
            return str(name)
    return None


def resolve_bus(options: BusOptions) -> BusConfig:
    """The bus the options and python-can's configuration name (`can.util.load_config`: the command line first),
    or `default_bus` when none names an interface; channel defaults per interface (`CHANNEL_DEFAULTS`)."""
    _check_config_file(options)
    given = options.kwargs()
    note = None
    if "interface" in given:
        source = "command line"
    elif configured_interface(options) is not None:
        source = f"python-can configuration{f' {options.config_file}' if options.config_file else ''}"
    else:
        interface, channel, note = default_bus()
        given = {"interface": interface, "channel": channel, **given}
        source = "default"
    cfg = dict(can.util.load_config(path=options.config_file, config=given, context=options.context))
    if cfg.get("channel") is None:
        cfg["channel"] = CHANNEL_DEFAULTS.get(str(cfg["interface"]))
    if cfg["channel"] is None:
        del cfg["channel"]  # the interface's own default (PCAN_USBBUS1, ...)
    return BusConfig(cfg, source, note)


def open_bus(options: BusOptions | str | None = None, channel: str | None = None) -> can.BusABC:
    """Open the bus `options` name (or the interface and channel given as text); raises one of `BUS_ERRORS` with
    python-can's message if it cannot be opened."""
    if not isinstance(options, BusOptions):
        options = BusOptions(interface=options, channel=channel)
    return resolve_bus(options).open()


def open_cli_bus(prog: str, options: BusOptions) -> tuple[can.BusABC, BusConfig] | None:
    """The bus of a command line: the fallback note (if any) as one line on stderr; None after one error line
    ``PROG: error: cannot open the CAN bus (...): why`` (`fdi_analysis.cli.common.fail`) if it cannot be opened:
    the caller then exits with `fdi_analysis.cli.common.EXIT_ERROR`."""
    what = options.interface or "configured"
    try:
        cfg = resolve_bus(options)
        what = cfg.describe()
        if cfg.note is not None:
            print(f"{prog}: {cfg.note}", file=sys.stderr, flush=True)
        return cfg.open(), cfg
    except BUS_ERRORS as exc:
        fail(prog, f"cannot open the CAN bus ({what}): {one_line(exc)}")
        return None


def set_receive_buffer(bus: can.BusABC, nbytes: int) -> int:
    """Ask for a kernel receive buffer of `nbytes` on the bus's socket (udp_multicast, socketcan); returns the
    size the kernel granted (0 if the bus has no socket). Beyond ``net.core.rmem_max`` only with CAP_NET_ADMIN
    (SO_RCVBUFFORCE); otherwise the kernel caps it there. A larger buffer rides out scheduling pauses of the
    receiving process at a high frame rate without dropping frames."""
    try:
        fd = bus.fileno()
    except NotImplementedError:
        return 0
    if fd < 0:
        return 0
    sock = socket.socket(fileno=os.dup(fd))
    try:
        try:
            sock.setsockopt(socket.SOL_SOCKET, getattr(socket, "SO_RCVBUFFORCE", 33), nbytes)
        except OSError:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, nbytes)
        return int(sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF))
    finally:
        sock.close()


def raw_id(arbitration_id: int, extended: bool, remote: bool = False, error: bool = False) -> int:
    """The SocketCAN raw can_id of a frame: the ID with the EFF/RTR/ERR flags."""
    return (arbitration_id | (CAN_EFF_FLAG if extended else 0) | (CAN_RTR_FLAG if remote else 0)
            | (CAN_ERR_FLAG if error else 0))


def rx_frame(msg: can.Message) -> RxFrame:
    """A received `can.Message` as ``(raw can_id, payload, receive time)``."""
    return (raw_id(msg.arbitration_id, msg.is_extended_id, msg.is_remote_frame, msg.is_error_frame),
            bytes(msg.data), float(msg.timestamp))


class BusReader:
    """Frames from any python-can bus through its public API: ``bus.recv(timeout)`` waits for the first, then
    (with `drain`) ``bus.recv(0)`` takes every frame already queued, up to `max_batch`: one wake-up of the
    reading loop per burst. CAN FD frames come back like classic ones (a payload longer than 8 bytes: the C core
    rejects it as a bad DLC)."""

    def __init__(self, bus: can.BusABC, max_batch: int = 256, drain: bool = True) -> None:
        self.bus = bus
        self.max_batch = max_batch if drain else 1

    def read(self, timeout: float) -> list[RxFrame]:
        """The frames queued now, after waiting up to `timeout` [s] for the first one ([] if none came)."""
        recv = self.bus.recv
        msg = recv(max(0.0, timeout))
        out: list[RxFrame] = []
        while msg is not None:
            out.append(rx_frame(msg))
            if len(out) >= self.max_batch:
                break
            msg = recv(0.0)
        return out

    def close(self) -> None:
        """Nothing to release (the bus is the caller's); kept for readers that hold a resource."""


def frame_reader(bus: can.BusABC, drain: bool = True) -> BusReader:
    """The reader for `bus`: every frame queued per wake-up (`BusReader`), through python-can's public API."""
    return BusReader(bus, drain=drain)


def signal_ready(path: Path | None) -> None:
    """Tell a supervisor (fdi-live) that this process listens on the bus: write `path` when given."""
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("ready\n", encoding="utf-8")


class StopFlag:
    """Set by SIGINT or SIGTERM (installed on construction); call it to ask whether to stop."""

    def __init__(self) -> None:
        self.stopped = False
        self.signal: int | None = None
        signal.signal(signal.SIGINT, self._handler)
        signal.signal(signal.SIGTERM, self._handler)

    def _handler(self, signum: int, frame: FrameType | None) -> None:
        self.stopped = True
        self.signal = signum

    def __call__(self) -> bool:
        return self.stopped


def set_affinity(cpus: Sequence[int]) -> str:
    """Run this process on the given CPUs only (where the platform allows); returns what was done."""
    if not hasattr(os, "sched_setaffinity"):
        return "no CPU affinity on this platform"
    try:
        os.sched_setaffinity(0, set(cpus))
    except (OSError, ValueError) as exc:
        return f"any CPU ({exc})"
    return f"CPU {','.join(str(c) for c in sorted(set(cpus)))}"


class CpuLatencyRequest:
    """A PM QoS request on the CPU wake-up latency (``/dev/cpu_dma_latency``, root), held until `close`: with
    0 us idle CPUs poll instead of entering a sleep state; in a virtual machine (haltpoll) the vCPU then never
    halts, so the host does not have to schedule it back in when a frame or a timer wakes a process (on this
    2-core VM, when it is otherwise quiet, that costs up to several milliseconds; real-time latency tools such
    as cyclictest make the same request). Costs power: idle CPUs spin. `note`: what was done, for the log."""

    PATH = "/dev/cpu_dma_latency"

    def __init__(self, latency_us: int = 0) -> None:
        self._fd: int | None = None
        try:
            fd = os.open(self.PATH, os.O_WRONLY)
        except OSError as exc:
            self.note = f"no CPU wake-up latency request ({self.PATH}: {exc.strerror})"
            return
        try:
            os.write(fd, struct.pack("=i", latency_us))
        except OSError as exc:
            os.close(fd)
            self.note = f"no CPU wake-up latency request ({exc.strerror})"
            return
        self._fd = fd
        self.note = f"CPU wake-up latency {latency_us} us (PM QoS)"

    @property
    def active(self) -> bool:
        return self._fd is not None

    def close(self) -> None:
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None


def try_realtime(priority: int = 10, rttime_limit_s: float = 2.0) -> str:
    """Real-time priority (SCHED_FIFO) for a paced sender or the ECU loop, where permitted (root).

    Safety net: RLIMIT_RTTIME stops the process if it runs `rttime_limit_s` of CPU without ever blocking
    (these loops block on sleep/recv every few milliseconds). Returns what was done, for the log.
    """
    if not hasattr(os, "sched_setscheduler"):
        return "no real-time scheduling on this platform"
    try:
        lim = round(rttime_limit_s * 1e6)
        resource.setrlimit(resource.RLIMIT_RTTIME, (lim, lim))
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except (OSError, ValueError) as exc:
        return f"normal priority ({exc})"
    return f"SCHED_FIFO priority {priority}"
