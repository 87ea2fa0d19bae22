"""Opening a python-can bus from command-line options, and a stop flag set by SIGINT/SIGTERM.

The same options everywhere (``--interface``, ``--channel``): ``udp_multicast`` (channel = multicast group,
default 239.74.163.2; works across processes, inside a private network namespace too), ``socketcan``
(``can0``/``vcan0`` where the kernel has AF_CAN), ``virtual`` (in one process, for tests), or any other
python-can interface.
"""

from __future__ import annotations

import argparse
import os
import resource
import signal
from pathlib import Path
from types import FrameType

import can

DEFAULT_INTERFACE = "udp_multicast"
DEFAULT_CHANNEL = "239.74.163.2"


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
