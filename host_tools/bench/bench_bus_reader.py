"""Benchmark of the frame reader (`fdi_host.live.bus.BusReader`) on python-can's udp_multicast bus: its cost per
frame, through python-can's public API only (``bus.recv``, then ``bus.recv(timeout=0)`` for every frame already
queued), against one ``bus.recv`` per call.

A sender bus queues a burst of frames in the receiver's socket; the reader then takes them all, timed. Repeated,
the first repetitions dropped (warm-up); printed: median, smallest and largest cost per frame [us]. Runs in a
private network namespace (`fdi_host.live.netns`), so the multicast traffic stays on this machine's loopback.
The machine is shared: compare numbers from the same run.

    python host_tools/bench/bench_bus_reader.py [--frames 1000] [--reps 30]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from collections.abc import Sequence

import can

from fdi_host.live.bus import BusOptions, BusReader, open_bus, set_receive_buffer
from fdi_host.live.netns import check_unshare, inside_private_netns, netns_command

CHANNEL = "239.74.163.77"
WARM_UP = 3


def measure(reader: BusReader, tx: can.BusABC, n: int, reps: int) -> list[float]:
    """Cost per frame [us] of reading bursts of `n` frames, one value per repetition after the warm-up."""
    msgs = [can.Message(arbitration_id=0x100 + i % 20, data=bytes(range(8)), is_extended_id=False) for i in range(n)]
    out = []
    for rep in range(reps + WARM_UP):
        for m in msgs:
            tx.send(m)
        time.sleep(0.05)  # every datagram queued
        got = 0
        t0 = time.perf_counter()
        while got < n:
            frames = reader.read(0.5)
            if not frames:
                raise SystemExit(f"lost {n - got} of {n} frames (receive buffer too small?)")
            got += len(frames)
        if rep >= WARM_UP:
            out.append((time.perf_counter() - t0) / n * 1e6)
    return out


def run(n: int, reps: int) -> int:
    tx = open_bus(BusOptions(interface="udp_multicast", channel=CHANNEL))
    rx = open_bus(BusOptions(interface="udp_multicast", channel=CHANNEL))
    try:
        set_receive_buffer(rx, 8 * 1024 * 1024)
        for name, reader in (("bus.recv + every queued frame (bus.recv(0))", BusReader(rx)),
                             ("one bus.recv per call", BusReader(rx, drain=False))):
            us = measure(reader, tx, n, reps)
            print(f"{name}: median {statistics.median(us):.2f} us/frame, min {min(us):.2f}, max {max(us):.2f} "
                  f"({reps} bursts of {n} frames)", flush=True)
    finally:
        tx.shutdown()
        rx.shutdown()
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    args_list = list(sys.argv[1:] if argv is None else argv)
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    ap.add_argument("--frames", type=int, default=1000, help="frames per burst (default 1000)")
    ap.add_argument("--reps", type=int, default=30, help="bursts measured (default 30)")
    args = ap.parse_args(args_list)
    if inside_private_netns():
        return run(args.frames, args.reps)
    chk = check_unshare()
    if not chk.ok:
        print(f"bench_bus_reader: {chk.reason}; measuring on this host's network", file=sys.stderr)
        return run(args.frames, args.reps)
    return subprocess.run(netns_command([sys.executable, __file__, *args_list]), check=False).returncode


if __name__ == "__main__":
    raise SystemExit(main())
