"""Opening a python-can bus from command-line options, reading frames from it, and a stop flag set by
SIGINT/SIGTERM.

The same options everywhere (``--interface``, ``--channel``): ``udp_multicast`` (channel = multicast group,
default 239.74.163.2; works across processes, inside a private network namespace too), ``socketcan``
(``can0``/``vcan0`` where the kernel has AF_CAN), ``virtual`` (in one process, for tests), or any other
python-can interface.

Reading (`frame_reader`): every frame as ``(can_id, data, timestamp)`` with the SocketCAN flags in the ID
(`CAN_EFF_FLAG` for a 29-bit ID, `CAN_RTR_FLAG`, `CAN_ERR_FLAG`), as the SocketCAN ECU program hands raw IDs
to the C core, which counts flagged frames as unknown IDs. On a udp_multicast bus the reader takes the
datagrams from the bus's own socket (python-can's wire format: one msgpack map per frame, kernel receive
stamp) and drains all that are queued per wake-up, without building a `can.Message` per frame (python-can's
``recv`` costs about 15 us per frame, this path about 10 us); on any other bus it calls ``bus.recv``.
"""

from __future__ import annotations

import argparse
import os
import resource
import select
import signal
import socket
import struct
import time
from collections.abc import Sequence
from pathlib import Path
from types import FrameType

import can
import msgpack  # type: ignore[import-untyped]

DEFAULT_INTERFACE = "udp_multicast"
DEFAULT_CHANNEL = "239.74.163.2"
CAN_EFF_FLAG = 0x80000000  # SocketCAN's flags in the raw can_id (linux/can.h)
CAN_RTR_FLAG = 0x40000000
CAN_ERR_FLAG = 0x20000000
CAN_EFF_MASK = 0x1FFFFFFF
RxFrame = tuple[int, bytes, float]  # (can_id with SocketCAN flags, payload, receive time [s, wall clock])


def add_bus_arguments(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("--interface", default=DEFAULT_INTERFACE,
                    help=f"python-can interface (default {DEFAULT_INTERFACE}; socketcan, virtual, ...)")
    ap.add_argument("--channel", default=None,
                    help=f"channel: multicast group for udp_multicast (default {DEFAULT_CHANNEL}), can0/vcan0 for "
                    "socketcan")


def open_bus(interface: str, channel: str | None) -> can.BusABC:
    """Open the bus; raises `can.CanError`/`OSError` with python-can's message if it cannot be opened."""
    if channel is None:
        channel = DEFAULT_CHANNEL if interface == "udp_multicast" else "vcan0" if interface == "socketcan" else "0"
    return can.Bus(interface=interface, channel=channel)


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


class BusReader:
    """Frames from any python-can bus through ``bus.recv``: one frame per call."""

    def __init__(self, bus: can.BusABC) -> None:
        self.bus = bus

    def read(self, timeout: float) -> list[RxFrame]:
        """The next frame, after waiting up to `timeout` [s] ([] if none came)."""
        msg = self.bus.recv(timeout=timeout)
        if msg is None:
            return []
        fid = raw_id(int(msg.arbitration_id), bool(msg.is_extended_id), bool(msg.is_remote_frame),
                     bool(msg.is_error_frame))
        return [(fid, bytes(msg.data), float(msg.timestamp))]


class UdpMulticastReader:
    """Frames straight from a python-can udp_multicast bus's socket: every datagram queued at a wake-up, each
    decoded from python-can's msgpack map (its keys ``arbitration_id``, ``is_extended_id``,
    ``is_remote_frame``, ``is_error_frame``, ``data``) with the kernel's receive stamp (SO_TIMESTAMPNS, which
    python-can switches on; the wall clock if the stamp is missing). CAN FD frames are returned like classic
    ones (their payload may be longer than 8 bytes: the C core rejects it as a bad DLC)."""

    _TS = struct.Struct("@ll")

    def __init__(self, bus: can.BusABC, max_batch: int = 256) -> None:
        self.bus = bus
        self._sock = socket.socket(fileno=os.dup(bus.fileno()))  # the same socket (a second descriptor)
        self._sock.setblocking(False)
        self._fd = self._sock.fileno()
        self._anc = socket.CMSG_SPACE(self._TS.size)
        self.max_batch = max_batch

    def read(self, timeout: float) -> list[RxFrame]:
        """The frames queued now, after waiting up to `timeout` [s] for the first one ([] if none came)."""
        ready, _, _ = select.select([self._fd], [], [], max(0.0, timeout))
        return self._drain() if ready else []

    def _drain(self) -> list[RxFrame]:
        out: list[RxFrame] = []
        recvmsg = self._sock.recvmsg
        unpackb = msgpack.unpackb
        ts_unpack = self._TS.unpack
        for _ in range(self.max_batch):
            try:
                raw, anc, _flags, _addr = recvmsg(4096, self._anc)
            except (BlockingIOError, InterruptedError):
                break
            try:
                d = unpackb(raw, raw=False)
                fid = raw_id(int(d["arbitration_id"]), bool(d.get("is_extended_id")), bool(d.get("is_remote_frame")),
                             bool(d.get("is_error_frame")))
                data = bytes(d.get("data") or b"")
            except (ValueError, KeyError, TypeError) as exc:  # msgpack's errors are ValueError subclasses
                raise can.CanOperationError(f"could not unpack a received frame: {exc}") from exc
            if anc:
                sec, nsec = ts_unpack(anc[0][2][: self._TS.size])
                ts = sec + nsec * 1e-9
            else:
                ts = time.time()
            out.append((fid, data, ts))
        return out

    def close(self) -> None:
        self._sock.close()


def frame_reader(bus: can.BusABC) -> BusReader | UdpMulticastReader:
    """The fastest reader for `bus`: its socket directly for udp_multicast, ``bus.recv`` otherwise."""
    try:
        from can.interfaces.udp_multicast import UdpMulticastBus
    except ImportError:  # pragma: no cover - part of python-can
        return BusReader(bus)
    if isinstance(bus, UdpMulticastBus) and bus.fileno() >= 0:
        return UdpMulticastReader(bus)
    return BusReader(bus)


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
