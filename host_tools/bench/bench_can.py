"""Benchmark of the live CAN loop: a simulated drive live over python-can udp_multicast in a private network
namespace, the ECU (C core through the bindings) as its own process, optionally with other ECUs' traffic up
to a full bus (``--bus-load``).

Printed numbers (each against its goal):
* frames lost: sent vs received by a listener process and by the ECU (goal 0), per kind (the simulator's
  sensor frames, other ECUs' frames); the rate achieved at the listener;
* frame-to-diagnosis latency p50/p99/max (goal p99 < 1 ms): from the wall-clock send time of the frame that
  completed a diagnosis step (the first frame after the step boundary, named by the ECU log) to the receive
  time of that step's FDI_Diagnosis frame at the listener; also split into bus in, ECU, bus out;
* what the ECU did with the other ECUs' frames: counted (unknown ID) and ignored; diagnosis steps with an
  alarm (the drive is fault-free: goal 0);
* offline replay speed vs real time (goal >= 1,000x, PASS/MISS): the same drive through `fdi-replay --offline`'s
  two code paths (one C call; frame by frame with the residual log, the anchor of the ratio), the time in the C
  call alone, and the one-call path on the log with the other ECUs' frames (with its C call alone), all from
  frame objects in memory; and the fleet's path on the ECU's receive log of the run (every frame of the full
  bus): the file read as columns (against python-can's reader), the replay from them, and both together;
* the load average at the start and at the end (the machine is shared: the goals are about a quiet machine).
During the live phase the bench holds a CPU wake-up latency request of 0 us (PM QoS, as cyclictest does; root):
on this virtual machine an idle vCPU otherwise halts and waits for the host to run it again when a frame
arrives, which dominates the latency on a quiet machine (``--no-pm-qos`` measures without).
All clocks are the host's wall clock (kernel receive stamps and time.time()).

    python host_tools/bench/bench_can.py [--duration 60] [--vehicle romo] [--bus-load 4000] [--out-dir out/bench_can]
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
from typing import Any

import numpy as np

from fdi_host.can import background, traffic
from fdi_host.can.dbc import CanDatabase
from fdi_host.can.frame import Frame
from fdi_host.can.log_columns import read_log_columns
from fdi_host.can.logs import read_log, write_log
from fdi_host.ecu.session import DIAG_ID, load_steps
from fdi_host.live.bus import (
    CAN_EFF_MASK,
    CpuLatencyRequest,
    StopFlag,
    open_bus,
    set_affinity,
    set_receive_buffer,
    try_realtime,
)
from fdi_host.live.netns import check_unshare, inside_private_netns, netns_command
from fdi_host.live.sender import SendLog, send_paced
from fdi_host.replay import replay_columns, replay_offline, replay_offline_fast
from fdi_host.sim.scenario import load_scenario
from fdi_host.sim.vehicle_sim import simulate
from fdi_host.vehicle import add_vehicle_argument

CHANNEL = "239.74.163.9"
LISTENER_RCVBUF = 16 * 1024 * 1024  # bytes: the listener is a measuring tool; it must not be the one that drops
SENDER_CPU, ECU_CPU = 0, 1  # with --pin
GOAL_P99_MS = 1.0
GOAL_OFFLINE_X = 1000.0


def load_text() -> str:
    one, five, fifteen = os.getloadavg()
    return f"load average {one:.2f} {five:.2f} {fifteen:.2f} (1/5/15 min) on {os.cpu_count()} cores"


def listener(out: Path, ready: Path) -> int:
    """Receive every frame until SIGTERM; save (receive time, id, counter) to `out` (.npz)."""
    stop = StopFlag()
    bus = open_bus("udp_multicast", CHANNEL)
    set_receive_buffer(bus, LISTENER_RCVBUF)
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


def background_for(args: argparse.Namespace, sim_frames: Sequence[Frame]) -> list[Frame]:
    """The other ECUs' frames that bring the bus to `args.bus_load` frames/s (none if the drive reaches it)."""
    if not args.bus_load:
        return []
    return background.for_drive(sim_frames, float(args.bus_load), args.duration, args.seed)


def bg_sender(args: argparse.Namespace) -> int:
    """Second sender process: the other ECUs' frames, from the wall time written to `<out>/bg.start`."""
    out: Path = args.out_dir
    frames = read_log(out / "bg_frames.log")
    bus = open_bus("udp_multicast", CHANNEL)
    prio = "normal priority" if args.no_realtime else try_realtime()
    if args.pin:
        prio += f", {set_affinity([SENDER_CPU])}"
    (out / "bg.ready").write_text(prio + "\n")
    _wait([out / "bg.start"])
    first_wall = float((out / "bg.start").read_text()) + frames[0].timestamp
    try:
        log = send_paced(bus, frames, 1.0, first_wall=first_wall)
    finally:
        bus.shutdown()
    log.save(out / "bg_send.npz")
    (out / "bg_send.json").write_text(json.dumps({"max_behind": log.max_behind, "start_wall": log.start_wall}) + "\n")
    return 0


def _wait(files: Sequence[Path], timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while not all(f.exists() for f in files):
        if time.monotonic() > deadline:
            raise RuntimeError(f"not started: {[str(f) for f in files if not f.exists()]}")
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


def _merge_logs(a: SendLog, b: SendLog) -> SendLog:
    """Two senders' logs as one, ordered by send time, frame times relative to the first one's start."""
    order = np.argsort(np.asarray(a.wall + b.wall), kind="stable")

    def col(x: list[float] | list[int], y: list[float] | list[int]) -> list[Any]:
        return list(np.asarray([*x, *y])[order].tolist())

    b_sim_t = [x + b.start_wall - a.start_wall for x in b.sim_t]
    return SendLog(col(a.sim_t, b_sim_t), col(a.wall, b.wall), col(a.frame_id, b.frame_id),
                   col(a.counter, b.counter), max(a.max_behind, b.max_behind), a.start_wall)


def run(args: argparse.Namespace) -> int:
    out: Path = args.out_dir
    out.mkdir(parents=True, exist_ok=True)
    for f in ("listener.ready", "ecu.ready", "bg.ready", "bg.start", "bg_send.npz", "bg_send.json"):
        (out / f).unlink(missing_ok=True)
    load_start = load_text()
    print(f"start: {load_start}", flush=True)
    print(f"simulating {args.duration:.0f} s ({args.scenario}) ...", flush=True)
    res = simulate(load_scenario(args.scenario), [], duration=args.duration)
    sim_frames = traffic.build_frames(res, CanDatabase())
    sim_rate = len(sim_frames) / args.duration
    bg_frames = background_for(args, sim_frames)
    frames = background.merge_frames(sim_frames, bg_frames)
    load = background.bus_load(frames, args.duration)
    print(f"{len(sim_frames)} simulator frames ({sim_rate:.0f}/s) + {len(bg_frames)} other ECUs' frames "
          f"({len(bg_frames) / args.duration:.0f}/s, {len({f.frame_id for f in bg_frames})} IDs, "
          f"{len({f.frame_id for f in bg_frames if f.frame_id > 0x7FF})} extended) = {load.frames_per_s:.0f} frames/s; "
          f"on a 500 kbit/s bus {load.nominal:.0%} load ({load.worst_case:.0%} with worst-case stuffing)", flush=True)
    separate = args.bg_sender == "separate" and bool(bg_frames)
    if bg_frames:
        print(f"other ECUs' frames sent by {'a second sender process' if separate else 'the simulator sender'}")
    to_send = sim_frames if separate else frames
    if separate:
        write_log(bg_frames, out / "bg_frames.log")

    env = os.environ.copy()
    me = [sys.executable, __file__]
    lis = subprocess.Popen([*me, "--listener", str(out / "listener.npz"), "--out-dir", str(out)], env=env)
    ecu_prog = ["-m", "fdi_host.live.ecu"] if args.ecu_script is None else [str(args.ecu_script)]
    ecu_cmd = [sys.executable, *ecu_prog, "--interface", "udp_multicast", "--channel", CHANNEL,
               "--vehicle", args.vehicle, "--log", str(out / "ecu.json"), "--ready-file", str(out / "ecu.ready"),
               "--rx-log", str(out / "ecu_rx.log"), "--quiet", *([] if args.no_realtime else ["--realtime"]),
               *(["--cpu", str(ECU_CPU)] if args.pin else [])]
    ecu = subprocess.Popen(ecu_cmd, env=env)
    procs = [lis, ecu]
    waits = [out / "listener.ready", out / "ecu.ready"]
    if separate:
        procs.append(subprocess.Popen([*me, "--bg-child", "--out-dir", str(out), "--bus-load", str(args.bus_load),
                                       "--seed", str(args.seed),
                                       *(["--no-realtime"] if args.no_realtime else []),
                                       *(["--pin"] if args.pin else [])], env=env))
        waits.append(out / "bg.ready")
    qos = CpuLatencyRequest(0) if not args.no_pm_qos else None
    try:
        _wait(waits)
        bus = open_bus("udp_multicast", CHANNEL)
        prio = "normal priority (--no-realtime)" if args.no_realtime else try_realtime()
        if args.pin:
            prio += f", {set_affinity([SENDER_CPU])}"
        try:
            def announce(wall: float) -> None:  # the second sender: the wall time of the drive's t = 0
                if separate:
                    (out / "bg.start.tmp").write_text(f"{wall - to_send[0].timestamp!r}\n")
                    (out / "bg.start.tmp").replace(out / "bg.start")

            log = send_paced(bus, to_send, 1.0, on_start=announce, lead=0.2)
        finally:
            bus.shutdown()
            with contextlib.suppress(OSError, AttributeError):
                os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
        if separate:
            procs[2].wait(60)
            bg_log = SendLog.load(out / "bg_send.npz")
            info = json.loads((out / "bg_send.json").read_text())
            bg_log.max_behind, bg_log.start_wall = float(info["max_behind"]), float(info["start_wall"])
            log = _merge_logs(log, bg_log)
        time.sleep(0.5)
    finally:
        _stop(ecu)
        _stop(lis)
        for p in procs[2:]:
            if p.poll() is None:
                _stop(p)
        if qos is not None:
            qos.close()
    qos_note = qos.note if qos is not None else "no CPU wake-up latency request (--no-pm-qos)"
    log.save(out / "send.npz")
    load_live = load_text()
    report(args, out, frames, sim_frames, bg_frames, log, f"{prio}; live phase: {qos_note}", load_live, load_start)
    return 0


def report(args: argparse.Namespace, out: Path, frames: Sequence[Frame], sim_frames: Sequence[Frame],
           bg_frames: Sequence[Frame], log: SendLog, prio: str, load_live: str, load_start: str) -> None:
    sim_ids = {f.frame_id for f in sim_frames}
    sent_t = np.asarray(log.wall)
    sent = Counter(log.frame_id)
    with np.load(out / "listener.npz") as z:
        rx_t, rx_id, rx_cnt = z["t"], z["id"], z["counter"]
    rx = Counter(int(i) for i in rx_id)
    lost = {fid: n - rx.get(fid, 0) for fid, n in sent.items()}
    lost_sim = sum(v for k, v in lost.items() if k in sim_ids)
    lost_bg = sum(v for k, v in lost.items() if k not in sim_ids)
    rx_sent = np.isin(rx_id, np.fromiter(sent, dtype=np.int64))
    t_rx = rx_t[rx_sent]
    achieved = (t_rx.size - 1) / float(t_rx[-1] - t_rx[0]) if t_rx.size > 1 else float("nan")
    ecu_doc = json.loads((out / "ecu.json").read_text())
    ecu_in = int(ecu_doc["frames_in"])
    counters = ecu_doc.get("counters", {})
    rejected = counters.get("rejected", {}) if isinstance(counters, dict) else {}
    steps = load_steps(out / "ecu.json")
    alarm_steps = sum(1 for s in steps if s.alarm_mask)

    # Latency: trigger frame send time -> diagnosis frame receive time at the listener.
    sent_by: dict[tuple[int, int], list[float]] = {}
    for w, fid, c in zip(log.wall, log.frame_id, log.counter, strict=True):
        sent_by.setdefault((fid, c), []).append(w)
    diag_mask = rx_id == DIAG_ID
    d_t, d_c = rx_t[diag_mask], rx_cnt[diag_mask]
    lat, bus_in, ecu_t, bus_out = [], [], [], []
    for s in steps:
        if s.trigger_id < 0 or s.tx_wall <= 0.0:
            continue
        cands = sent_by.get((s.trigger_id & CAN_EFF_MASK, s.trigger_counter), [])
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
    lag = (sent_t - log.start_wall) - np.asarray(log.sim_t)

    load_off = load_text()
    off = replay_offline(sim_frames, args.vehicle)
    fast = replay_offline_fast(sim_frames, args.vehicle)
    fast_all = replay_offline_fast(frames, args.vehicle) if bg_frames else None
    load_end = load_text()
    behind = log.max_behind * 1e3
    n_sent = len(sent_t)
    n_sim = sum(sent[f] for f in sim_ids)
    print()
    print(f"== live over udp_multicast ({'private netns' if inside_private_netns() else 'this netns'}), "
          f"{args.duration:.0f} s, table {args.vehicle}; {load_live} (at the end of the live phase)")
    requested = args.bus_load or round(len(frames) / args.duration)
    print(f"frames sent {n_sent} ({n_sim} simulator, {n_sent - n_sim} other ECUs'); received by the listener "
          f"{int(rx_sent.sum())} at {achieved:.0f} frames/s (requested {requested:.0f})")
    print(f"  lost at the listener: {lost_sim + lost_bg} (simulator {lost_sim}: "
          + ", ".join(f"0x{k:03X} {v}" for k, v in sorted(lost.items()) if k in sim_ids)
          + f"; other ECUs' {lost_bg}) (goal 0)")
    print(f"  ECU: {ecu_in} frames in, lost {n_sent - ecu_in} (goal 0); counted as unknown IDs and ignored by the C "
          f"core {int(rejected.get('unknown_id', 0))} (of {n_sent - n_sim} other ECUs' frames sent); other rejections "
          f"{sum(int(v) for k, v in rejected.items() if k != 'unknown_id')}")
    print(f"sender ({prio}): largest delay behind schedule {behind:.2f} ms, "
          f"p99 {float(np.percentile(lag, 99)) * 1e3:.3f} ms")
    print(f"diagnosis frames: ECU sent {len(steps)}, listener received {int(diag_mask.sum())}; "
          f"steps with an alarm {alarm_steps} (fault-free drive: goal 0)")
    print(f"frame-to-diagnosis latency over {L.size} steps: p50 {_pct(L, 50):.3f} ms, p99 {_pct(L, 99):.3f} ms, "
          f"max {_pct(L, 100):.3f} ms (goal p99 < {GOAL_P99_MS:g} ms)")
    for name, arr in (("bus in", bus_in), ("ECU (rx stamp -> send)", ecu_t), ("bus out", bus_out)):
        a = np.asarray(arr)
        print(f"  {name:24s} p50 {_pct(a, 50):.3f} ms  p99 {_pct(a, 99):.3f} ms  max {_pct(a, 100):.3f} ms")
    print(f"== offline replay, {off.frames} simulator frames, {off.log_duration:.1f} s of log "
          f"(goal >= {GOAL_OFFLINE_X:,.0f}x real time); {load_off}")
    print(f"  fdi-replay --offline (one C call, Ecu.process_arrays): {fast.wall:.3f} s = {fast.speed:,.0f}x real time "
          f"({_verdict(fast.speed)}); "
          f"of which the C call (rx + poll per frame, {len(fast.records)} diagnosis steps) {fast.c_wall:.3f} s = "
          f"{off.log_duration / fast.c_wall if fast.c_wall > 0 else float('inf'):,.0f}x real time")
    if fast_all is not None:
        c_speed = fast_all.log_duration / fast_all.c_wall if fast_all.c_wall > 0 else float("inf")
        print(f"  the same with the other ECUs' frames ({fast_all.frames} frames): {fast_all.wall:.3f} s = "
              f"{fast_all.speed:,.0f}x real time ({_verdict(fast_all.speed)}); of which the C call "
              f"{fast_all.c_wall:.3f} s = {c_speed:,.0f}x real time, the rest the frames' conversion into arrays "
              "(one Python object each) and the records")
    rx_log = out / "ecu_rx.log"
    if rx_log.is_file():  # the fleet's path (replay_log): the log file read as columns, then one C call
        t_read = time.perf_counter()
        read_log(rx_log)
        t_read = time.perf_counter() - t_read
        t_cols = time.perf_counter()
        columns = read_log_columns(rx_log)
        t_cols = time.perf_counter() - t_cols
        from_file = replay_columns(columns, args.vehicle)
        total = t_cols + from_file.wall
        print(f"  from the ECU's receive log of the run ({rx_log.name}, candump, {len(columns)} frames, "
              f"{from_file.log_duration:.1f} s): read as columns {t_cols:.3f} s (python-can's reader {t_read:.2f} s, "
              f"{t_read / t_cols:.1f}x as long); replay from the columns {from_file.wall:.3f} s = "
              f"{from_file.speed:,.0f}x real time ({_verdict(from_file.speed)}); read and replay {total:.3f} s = "
              f"{from_file.log_duration / total:,.0f}x real time")
    print(f"  fdi-replay --offline --ecu-log (per frame, residual log): {off.wall:.3f} s = {off.speed:,.0f}x real time "
          f"(one C call: {fast.speed / off.speed:.1f}x faster)")
    print(f"end: {load_end} (start: {load_start})")
    summary = {"frames_sent": n_sent, "frames_sent_sim": n_sim, "lost": lost_sim + lost_bg, "lost_sim": lost_sim,
               "lost_bg": lost_bg, "ecu_frames_in": ecu_in, "ecu_rejected": rejected,
               "alarm_steps": alarm_steps, "achieved_rate_hz": achieved, "requested_rate_hz": args.bus_load,
               "latency_ms": {"p50": _pct(L, 50), "p99": _pct(L, 99), "max": _pct(L, 100), "n": int(L.size)},
               "offline_speed": fast.speed, "offline_speed_with_background": fast_all.speed if fast_all else None,
               "offline_speed_per_frame": off.speed, "sender_max_behind_ms": behind,
               "load": {"start": load_start, "live_end": load_live, "end": load_end}}
    (out / "bench_can.json").write_text(json.dumps(summary, indent=2) + "\n")


def _verdict(speed: float) -> str:
    return f"goal >= {GOAL_OFFLINE_X:,.0f}x: {'PASS' if speed >= GOAL_OFFLINE_X else 'MISS'}"


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None,
                                 epilog="example: python host_tools/bench/bench_can.py --bus-load 4000 --vehicle romo",
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=float, default=60.0, help="seconds of live traffic (default 60)")
    ap.add_argument("--scenario", default="slalom", help="scenario driven (default slalom)")
    add_vehicle_argument(ap)
    ap.add_argument("--bus-load", type=float, default=0.0, metavar="HZ",
                    help="total frames/s on the bus: other ECUs' frames (IDs the ECU does not subscribe to) are "
                    "added to the drive's ~1,200/s (default 0: the drive's traffic only)")
    ap.add_argument("--bg-sender", choices=("same", "separate"), default="same",
                    help="other ECUs' frames from the simulator's sender process or from a second one (default same)")
    ap.add_argument("--seed", type=int, default=background.DEFAULT_SEED, help="seed of the other ECUs' traffic")
    ap.add_argument("--no-realtime", action="store_true",
                    help="no SCHED_FIFO for the sender and the ECU (as without root)")
    ap.add_argument("--no-pm-qos", action="store_true",
                    help="no CPU wake-up latency request during the live phase (by default the bench holds 0 us on "
                    "/dev/cpu_dma_latency, as cyclictest does: idle vCPUs poll instead of halting)")
    ap.add_argument("--pin", action="store_true",
                    help=f"sender(s) on CPU {SENDER_CPU}, ECU on CPU {ECU_CPU} (the listener and other jobs anywhere)")
    ap.add_argument("--out-dir", type=Path, default=Path("out/bench_can"))
    ap.add_argument("--ecu-script", type=Path, help=argparse.SUPPRESS)  # another fdi-ecu (an older version)
    ap.add_argument("--listener", type=Path, help=argparse.SUPPRESS)
    ap.add_argument("--bg-child", action="store_true", help=argparse.SUPPRESS)
    args_list = list(sys.argv[1:] if argv is None else argv)
    args = ap.parse_args(args_list)
    if args.bg_child:
        return bg_sender(args)
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
    # the run's output becomes section bench_can of docs/results.md (the run in its private network namespace included)
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))
    import results_doc

    rerun = results_doc.run_script("bench_can", __file__, sys.argv[1:], ok_codes=(0,))
    raise SystemExit(main() if rerun is None else rerun)
