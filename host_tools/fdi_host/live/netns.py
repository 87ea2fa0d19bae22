"""Where a live bus can run on this machine: SocketCAN vcan if the kernel has AF_CAN, otherwise python-can's
udp_multicast inside a private network namespace.

A private network namespace has only a loopback device, down. Root makes one with ``unshare -n``, any other
user with ``unshare -rn`` (a new user namespace in which the user is root, where the kernel allows
unprivileged user namespaces, as Debian's does by default). `netns_command` wraps a command so that it first
brings ``lo`` up with multicast and routes 239.0.0.0/8 over it. Multicast traffic then stays inside the
namespace: parallel runs (other tests, other users) cannot see or disturb each other's frames.
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
from dataclasses import dataclass
from pathlib import Path

ENV_INSIDE = "FDI_PRIVATE_NETNS"  # set inside the namespace made by `netns_command`
_SETUP = 'ip link set lo up && ip link set lo multicast on && ip route add 239.0.0.0/8 dev lo && exec "$@"'


def have_af_can() -> bool:
    """True if the kernel supports CAN sockets (socket(AF_CAN, SOCK_RAW, CAN_RAW) can be created)."""
    af_can = getattr(socket, "AF_CAN", None)
    if af_can is None:
        return False
    try:
        socket.socket(af_can, socket.SOCK_RAW, getattr(socket, "CAN_RAW", 1)).close()
    except OSError:
        return False
    return True


def vcan_available(channel: str = "vcan0") -> bool:
    """AF_CAN works and the interface exists (created by the administrator: ip link add vcan0 type vcan)."""
    return have_af_can() and Path(f"/sys/class/net/{channel}").exists()


@dataclass(frozen=True)
class NetnsCheck:
    ok: bool
    reason: str


def unshare_argv() -> list[str]:
    """The unshare command that makes a private network namespace for this user (see the module doc)."""
    return ["unshare", "-n"] if os.geteuid() == 0 else ["unshare", "-r", "-n"]


def check_unshare() -> NetnsCheck:
    """Can this process make a private network namespace with a multicast-capable loopback?"""
    for tool in ("unshare", "ip"):
        if shutil.which(tool) is None:
            return NetnsCheck(False, f"`{tool}` not found (util-linux / iproute2)")
    try:
        proc = subprocess.run([*unshare_argv(), "sh", "-c", _SETUP, "sh", "true"], capture_output=True, text=True,
                              timeout=20, check=False)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return NetnsCheck(False, f"unshare failed: {exc}")
    if proc.returncode != 0:
        return NetnsCheck(False, f"`{' '.join(unshare_argv())}` not permitted here (unprivileged user namespaces "
                          f"off?): {proc.stderr.strip() or proc.returncode}")
    return NetnsCheck(True, "private network namespace with multicast on lo")


def inside_private_netns() -> bool:
    return os.environ.get(ENV_INSIDE) == "1"


def netns_command(argv: list[str]) -> list[str]:
    """`argv` run in a new network namespace with lo up, multicast on and 239.0.0.0/8 routed to lo."""
    return [*unshare_argv(), "env", f"{ENV_INSIDE}=1", "sh", "-c", _SETUP, "sh", *argv]
