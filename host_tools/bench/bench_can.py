"""Benchmark of the live CAN loop: ~1 kHz of simulated traffic for 60 s over python-can udp_multicast in a
private network namespace, the ECU (C core through the bindings) as its own process.

Printed numbers:
* frames lost: sent by the simulator vs received by a listener process and by the ECU (goal 0);
* frame-to-diagnosis latency p50/p99/max (goal p99 < 2 ms): from the wall-clock send time of the frame that
  completed a diagnosis step (the first frame after the step boundary, named by the ECU log) to the receive
  time of that step's FDI_Diagnosis frame at the listener; also split into bus in, ECU, bus out;
* offline replay speed vs real time (goal >= 200x): the same drive through `fdi-replay --offline`'s two code
  paths (one C call; frame by frame with the residual log).
All clocks are the host's wall clock (kernel receive stamps and time.time()).

    python host_tools/bench/bench_can.py [--duration 60] [--table kin] [--out-dir out/bench_can]
"""

from __future__ import annotations

import argparse
import bisect
import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from collections import Counter
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from fdi_host.can import traffic
from fdi_host.can.dbc import RomoDatabase
from fdi_host.ecu.session import DIAG_ID, load_steps
from fdi_host.live.bus import StopFlag, open_bus, try_realtime
from fdi_host.live.netns import check_unshare, inside_private_netns, netns_command
from fdi_host.live.sender import send_paced
from fdi_host.replay import replay_offline, replay_offline_fast
from fdi_host.sim.scenario import load_scenario
from fdi_host.sim.vehicle_sim import simulate

CHANNEL = "239.74.163.9"


def listener(out: Path, ready: Path) -> int:
    """Receive every frame until SIGTERM; save (receive time, id, counter) to `out` (.npz)."""
    stop = StopFlag()
    bus = open_bus("udp_multicast", CHANNEL)
    ready.write_text("ready\n")
    t: list[float] = []
    ids: list[int] = []
    cnt: list[int] = []
    try:
        while not stop():
            m = bus.recv(timeout=0.05)
            if m is not None:
                t.append(float(m.timestamp))
                ids.append(int(m.arbitration_id))
                cnt.append(m.data[1] & 0x0F if len(m.data) > 1 else -1)
    finally:
        bus.shutdown()
    np.savez(out, t=np.asarray(t), id=np.asarray(ids, dtype=np.int64), counter=np.asarray(cnt, dtype=np.int64))
    return 0


def _wait(files: Sequence[Path], timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while not all(f.exists() for f in files):
        if time.monotonic() > deadline:
            raise RuntimeError("listener/ECU did not start")
        time.sleep(0.05)


def _stop(p: subprocess.Popen[bytes]) -> None:
    p.send_signal(signal.SIGTERM)
    try:
        p.wait(60)
    except subprocess.TimeoutExpired:
        p.kill()
        p.wait()


def _pct(x: np.ndarray, q: float) -> float:
    return float(np.percentile(x, q)) * 1e3 if x.size else float("nan")


def run(args: argparse.Namespace) -> int:
    out: Path = args.out_dir
    out.mkdir(parents=True, exist_ok=True)
    for f in ("listener.ready", "ecu.ready"):
        (out / f).unlink(missing_ok=True)
    print(f"simulating {args.duration:.0f} s ({args.scenario}) ...", flush=True)
    res = simulate(load_scenario(args.scenario), [], duration=args.duration)
    frames = traffic.build_frames(res, RomoDatabase())
    rate = len(frames) / args.duration
    print(f"{len(frames)} frames, {rate:.0f} frames/s", flush=True)

    env = os.environ.copy()
    lis = subprocess.Popen([sys.executable, __file__, "--listener", str(out / "listener.npz"),
                            "--out-dir", str(out)], env=env)
    ecu = subprocess.Popen([sys.executable, "-m", "fdi_host.live.ecu", "--interface", "udp_multicast", "--channel",
                            CHANNEL, "--table", args.table, "--log", str(out / "ecu.json"), "--ready-file",
                            str(out / "ecu.ready"), "--quiet", "--realtime"], env=env)
    try:
        _wait([out / "listener.ready", out / "ecu.ready"])
        bus = open_bus("udp_multicast", CHANNEL)
        prio = try_realtime()
        try:
            log = send_paced(bus, frames, 1.0)
        finally:
            bus.shutdown()
            with contextlib.suppress(OSError, AttributeError):
                os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
        time.sleep(0.5)
    finally:
        _stop(ecu)
        _stop(lis)
    sent_t = np.asarray(log.wall)
    lag = (sent_t - log.start_wall) - np.asarray(log.sim_t)
    sent = Counter(log.frame_id)
    with np.load(out / "listener.npz") as z:
        rx_t, rx_id, rx_cnt = z["t"], z["id"], z["counter"]
    rx = Counter(int(i) for i in rx_id)
    lost = {fid: n - rx.get(fid, 0) for fid, n in sent.items()}
    ecu_doc = json.loads((out / "ecu.json").read_text())
    ecu_in = int(ecu_doc["frames_in"])

    # Latency: trigger frame send time -> diagnosis frame receive time at the listener.
    sent_by: dict[tuple[int, int], list[float]] = {}
    for w, fid, c in zip(log.wall, log.frame_id, log.counter, strict=True):
        sent_by.setdefault((fid, c), []).append(w)
    diag_mask = rx_id == DIAG_ID
    d_t, d_c = rx_t[diag_mask], rx_cnt[diag_mask]
    lat, bus_in, ecu_t, bus_out = [], [], [], []
    for s in load_steps(out / "ecu.json"):
        if s.trigger_id < 0 or s.tx_wall <= 0.0:
            continue
        cands = sent_by.get((s.trigger_id, s.trigger_counter), [])
        i = bisect.bisect_right(cands, s.trigger_wall) - 1
        if i < 0:
            continue
        t_send = cands[i]
        j = int(np.searchsorted(d_t, s.tx_wall))
        while j < d_t.size and d_c[j] != s.diag_counter:
            j += 1
        if j >= d_t.size or d_t[j] - s.tx_wall > 0.5:
            continue
        lat.append(d_t[j] - t_send)
        bus_in.append(s.trigger_wall - t_send)
        ecu_t.append(s.tx_wall - s.trigger_wall)
        bus_out.append(d_t[j] - s.tx_wall)
    L = np.asarray(lat)

    off = replay_offline(frames, args.table)
    fast = replay_offline_fast(frames, args.table)
    behind = log.max_behind * 1e3
    print()
    print(f"== live over udp_multicast ({'private netns' if inside_private_netns() else 'this netns'}), "
          f"{args.duration:.0f} s, {rate:.0f} frames/s, table {args.table}")
    print(f"frames sent {len(sent_t)}, received by the listener {sum(rx[f] for f in sent)}, by the ECU {ecu_in}; "
          f"lost (listener) {sum(lost.values())}: " + ", ".join(f"0x{k:03X} {v}" for k, v in sorted(lost.items())))
    print(f"sender ({prio}): largest delay behind schedule {behind:.2f} ms, "
          f"p99 {float(np.percentile(lag, 99)) * 1e3:.3f} ms")
    print(f"diagnosis frames: ECU sent {len(load_steps(out / 'ecu.json'))}, listener received {int(diag_mask.sum())}")
    print(f"frame-to-diagnosis latency over {L.size} steps: p50 {_pct(L, 50):.3f} ms, p99 {_pct(L, 99):.3f} ms, "
          f"max {_pct(L, 100):.3f} ms (goal p99 < 2 ms)")
    for name, arr in (("bus in", bus_in), ("ECU (rx stamp -> send)", ecu_t), ("bus out", bus_out)):
        a = np.asarray(arr)
        print(f"  {name:24s} p50 {_pct(a, 50):.3f} ms  p99 {_pct(a, 99):.3f} ms")
    print(f"== offline replay, {off.frames} frames, {off.log_duration:.1f} s of log (goal >= 200x real time):")
    print(f"  fdi-replay --offline (one C call, Ecu.process): {fast.wall:.3f} s = {fast.speed:.0f}x real time")
    print(f"  fdi-replay --offline --ecu-log (per frame, residual log): {off.wall:.3f} s = {off.speed:.0f}x real time")
    summary = {"frames_sent": len(sent_t), "lost": sum(lost.values()), "ecu_frames_in": ecu_in,
               "latency_ms": {"p50": _pct(L, 50), "p99": _pct(L, 99), "max": _pct(L, 100), "n": int(L.size)},
               "offline_speed": fast.speed, "offline_speed_per_frame": off.speed, "rate_hz": rate,
               "sender_max_behind_ms": behind}
    (out / "bench_can.json").write_text(json.dumps(summary, indent=2) + "\n")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    ap.add_argument("--duration", type=float, default=60.0, help="seconds of live traffic (default 60)")
    ap.add_argument("--scenario", default="slalom", help="scenario driven (default slalom)")
    ap.add_argument("--table", choices=("kin", "romo"), default="kin", help="ECU table (default kin)")
    ap.add_argument("--out-dir", type=Path, default=Path("out/bench_can"))
    ap.add_argument("--listener", type=Path, help=argparse.SUPPRESS)
    args_list = list(sys.argv[1:] if argv is None else argv)
    args = ap.parse_args(args_list)
    if args.listener is not None:
        return listener(args.listener, args.out_dir / "listener.ready")
    if not inside_private_netns():
        chk = check_unshare()
        if not chk.ok:
            print(f"bench_can: {chk.reason}", file=sys.stderr)
            return 2
        return subprocess.run(netns_command([sys.executable, __file__, *args_list]), check=False).returncode
    return run(args)


if __name__ == "__main__":
    raise SystemExit(main())
