"""``fdi-live``: a simulated drive live over a bus, with the ECU and the monitor as separate processes.

Transport (``--transport auto``): the bus the bus options name, when any is given (``--interface``,
``--can-config``, ``--bitrate``, ...: python-can's configuration, as every program takes it, see
`fdi_host.live.bus`; the three programs get the same options); otherwise SocketCAN ``vcan0`` where the kernel has
AF_CAN and the interface exists; otherwise (with a note) the simulated bus, python-can ``udp_multicast`` in a
private network namespace (the runner re-executes itself under ``unshare -n``, see `fdi_host.live.netns`), and
where that is not permitted udp_multicast in the current network namespace. ``--transport current`` forces the
latter, ``netns`` / ``vcan`` fail if not available, ``bus`` takes the bus python-can's configuration names (its
files and environment included) even without an option. python-can's ``virtual`` interface is one process's: it
cannot carry a run of three programs.

Order: ``fdi-ecu`` and ``fdi-monitor`` start and signal readiness (ready files), then ``fdi-sim live`` sends the
drive in real time; when it is done the ECU is stopped (SIGTERM: it writes its log), then the monitor (it
scores against the truth and writes report.md/json and plots). Printed: frames sent vs received per message
(from the simulator's send log and the monitor's counts) and the monitor's score table.

Restarts (`fdi_host.live.restart`): ``--restart-ecu-at T`` / ``--restart-sim-at T`` kill the ECU or the
simulator (SIGKILL) at drive time T and start it again after ``--ecu-down`` / ``--sim-down`` seconds; the
monitor reports the silences as gaps.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from fdi_analysis.cli.common import EXIT_ERROR, EXIT_USAGE, add_version, run
from fdi_host.live.bus import (
    BUS_ERRORS,
    DEFAULT_CHANNEL,
    SIMULATED_INTERFACE,
    VCAN_CHANNEL,
    BusOptions,
    add_bus_arguments,
    resolve_bus,
    vcan_missing,
)
from fdi_host.live.netns import check_unshare, inside_private_netns, netns_command, vcan_available
from fdi_host.live.restart import Managed, RestartEvent, restart_schedule
from fdi_host.live.sender import SendLog
from fdi_host.sim.options import add_drive_arguments
from fdi_host.vehicle import add_vehicle_argument

EPILOG = """\
examples:
  fdi-live --scenario fig6 --fault f4@5s:0.5 --vehicle kin --out-dir out/live
  fdi-live --scenario straight --duration 12 --no-scenario-faults --fault f4@4s:0.5:end=8s --vehicle kin
  fdi-live --transport current ...     (udp_multicast in this network namespace, no unshare)
  fdi-live --interface socketcan --channel vcan1 ...      (any bus python-can opens; the same for the 3 programs)
  fdi-live --can-config bus.ini --can-context bench ...   (the bus in a python-can configuration file)
  fdi-live --scenario cornering --fault f4@5s:0.5 --vehicle kin --bus-load 4000
                                       (other ECUs' frames up to 4,000 frames/s: counted and ignored by the ECU)
  fdi-live --scenario fig6 --duration 21.5 --no-scenario-faults --fault f4@16s:0.5 --vehicle kin
           --restart-ecu-at 1.5 --restart-sim-at 8.5 --sim-counter-start 9
                                       (ECU and simulator killed and restarted; the monitor reports both gaps)

outputs in --out-dir: drive.blf + truth.json (what was sent), send.npz (send times), ecu.json (ECU log),
ecu_rx.log (frames as the ECU received them, receive times; ecu.json and ecu_rx.log come from the last
ECU instance: a killed one writes nothing), send.resumeN.npz (send times of the N-th restarted simulator),
restarts.json (drive times of every kill and restart, and when a restarted ECU listened again),
report.md, report.json, diagnosis.png, residuals.png (monitor), ecu.txt / monitor.txt / sim.txt (their output).
"""


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="fdi-live", description=__doc__.splitlines()[0] if __doc__ else None,
                                 epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_drive_arguments(ap, noise=False)
    add_vehicle_argument(ap, "the ECU's diagnosis (romo: generated; kin: the hand-written kinematic tests)")
    ap.add_argument("--transport", choices=("auto", "bus", "vcan", "netns", "current"), default="auto",
                    help="bus: the bus the options below or python-can's configuration name; vcan: vcan0; netns: "
                    "udp_multicast in a private network namespace; current: udp_multicast here (default auto: bus "
                    "when a bus option other than --channel is given, else vcan0 where the kernel has it, else "
                    "netns, else current)")
    add_bus_arguments(ap)
    ap.add_argument("--grace", type=float, default=3.0, help="scoring grace after a fault's end [s] (default 3)")
    ap.add_argument("--out-dir", type=Path, default=Path("out/live"), help="output directory")
    ap.add_argument("--start-timeout", type=float, default=60.0, help="max wait for ECU and monitor to start [s]")
    ap.add_argument("--restart-ecu-at", type=float, action="append", default=[], metavar="T",
                    help="kill the ECU process (SIGKILL) at drive time T [s] and start it again (repeatable)")
    ap.add_argument("--ecu-down", type=float, default=1.0, metavar="D",
                    help="seconds between killing the ECU and starting it again (default 1)")
    ap.add_argument("--restart-sim-at", type=float, action="append", default=[], metavar="T",
                    help="kill the simulator (SIGKILL) at drive time T [s] and start it again (repeatable); "
                    "the new one sends the recorded drive (drive.blf) from where the drive is")
    ap.add_argument("--sim-down", type=float, default=1.0, metavar="D",
                    help="seconds between killing the simulator and starting it again (default 1; the new one "
                    "needs about a second more before it sends)")
    ap.add_argument("--sim-counter-start", type=int, default=0, metavar="N",
                    help="alive counter of each message's first frame from a restarted simulator (0..14)")
    ap.add_argument("--bus-load", type=float, default=0.0, metavar="HZ",
                    help="other ECUs' frames (IDs not in the DBC) up to HZ frames/s in total, sent with the drive's "
                    "(default 0: none; a full 500 kbit/s bus carries about 4,000)")
    ap.add_argument("--gap-threshold", type=float, default=0.25,
                    help="the monitor reports silences longer than this as gaps [s] (default 0.25)")
    return add_version(ap)


def _py(module: str, *args: str) -> list[str]:
    return [sys.executable, "-m", module, *args]


def _wait_ready(files: Sequence[Path], procs: Sequence[subprocess.Popen[bytes]], timeout: float) -> str | None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if all(f.exists() for f in files):
            return None
        for p in procs:
            if p.poll() is not None:
                return f"{' '.join(map(str, p.args))} exited early with code {p.returncode}"  # type: ignore[arg-type]
        time.sleep(0.05)
    return "ECU/monitor did not start in time"


def sent_vs_received(send_log: Path, report: dict[str, Any]) -> list[tuple[int, int, int]]:
    """(frame id, sent, received by the monitor) per simulated message (the DBC's messages: the monitor
    counts other ECUs' frames only in total, see `other_ecus_sent_vs_received`)."""
    sent = Counter(SendLog.load(send_log).frame_id)
    msgs = (report.get("frames") or {}).get("messages", {})
    rec = {int(k, 16): int(v["received"]) for k, v in msgs.items()}
    return [(fid, n, rec.get(fid, 0)) for fid, n in sorted(sent.items()) if fid in rec]


def other_ecus_sent_vs_received(send_log: Path, report: dict[str, Any]) -> tuple[int, int]:
    """(other ECUs' frames sent, frames of unknown IDs the monitor received)."""
    msgs = (report.get("frames") or {}).get("messages", {})
    known = {int(k, 16) for k in msgs}
    sent = sum(1 for fid in SendLog.load(send_log).frame_id if fid not in known)
    return sent, int((report.get("frames") or {}).get("unknown_ids", 0))


def _wait_origin(path: Path, sim: subprocess.Popen[bytes], timeout: float) -> float | None:
    """The drive's t = 0 (wall clock) once the simulator has written it; None if it exited or timed out."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if path.exists():
            try:
                return float(path.read_text(encoding="utf-8"))
            except ValueError:
                pass  # being written (it is replaced atomically, but be safe)
        if sim.poll() is not None:
            return None
        time.sleep(0.02)
    return None


def _supervise(args: argparse.Namespace, out: Path, ecu: Managed, sim: Managed, sim_resume_cmd: list[str],
               schedule: list[RestartEvent]) -> int:
    """Run the drive to its end, killing and restarting processes on the schedule; the last simulator's exit
    code (or 2 if the first one never started sending)."""
    t_wall = time.monotonic()
    first = sim.start()
    origin = _wait_origin(out / "origin.txt", first, args.start_timeout + 600.0)
    if origin is None:
        first.wait()
        return first.returncode or 2
    pending = list(schedule)
    waiting_ready = False
    rc = 0
    while True:
        now = time.time() - origin
        while pending and pending[0].t <= now:
            ev = pending.pop(0)
            proc = ecu if ev.target == "ecu" else sim
            label = "ECU" if ev.target == "ecu" else "simulator"
            if ev.action == "kill":
                if proc.kill():
                    proc.kills.append(now)
                    print(f"fdi-live: t={now:6.2f} s  {label} killed (SIGKILL)", flush=True)
                else:
                    print(f"fdi-live: t={now:6.2f} s  {label} was not running", flush=True)
            else:
                if ev.target == "ecu":
                    (out / "ecu.ready").unlink(missing_ok=True)
                    ecu.start()
                    waiting_ready = True
                else:
                    sim.start([*sim_resume_cmd, f"--send-log={out / f'send.resume{sim.instances}.npz'}"])
                proc.starts.append(now)
                print(f"fdi-live: t={now:6.2f} s  {label} started again", flush=True)
        if waiting_ready and (out / "ecu.ready").exists():
            waiting_ready = False
            ecu.ready.append(now)
            print(f"fdi-live: t={now:6.2f} s  ECU listening again", flush=True)
        p = sim.proc
        sim_pending = any(e.target == "sim" and e.action == "start" for e in pending)
        if p is not None and p.poll() is not None and not sim_pending:
            rc = int(p.returncode)
            break
        if p is None and not sim_pending:  # killed, no restart left
            break
        time.sleep(0.02)
    for ev in pending:
        print(f"fdi-live: {ev.target} {ev.action} at t={ev.t:.2f} s not done: the drive had ended", flush=True)
    if schedule:
        doc = {m.name: {"killed_at": m.kills, "started_at": m.starts, **({"ready_at": m.ready} if m.ready else {})}
               for m in (ecu, sim)}
        (out / "restarts.json").write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
    print(f"fdi-live: drive done in {time.monotonic() - t_wall:.1f} s (simulation + real-time sending)", flush=True)
    return rc


def run_here(args: argparse.Namespace, bus: list[str], label: str) -> int:
    """The three programs on the bus `bus` (their bus options), described as `label`."""
    out: Path = args.out_dir
    out.mkdir(parents=True, exist_ok=True)
    try:
        schedule = restart_schedule(args.restart_ecu_at, args.restart_sim_at, args.ecu_down, args.sim_down)
    except ValueError as exc:
        print(f"fdi-live: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    if not 0 <= args.sim_counter_start <= 14:
        print("fdi-live: error: --sim-counter-start must be in 0..14", file=sys.stderr)
        return EXIT_USAGE
    for f in ("ecu.ready", "monitor.ready", "ecu.json", "report.json", "origin.txt", "restarts.json"):
        (out / f).unlink(missing_ok=True)
    for old in out.glob("send.resume*.npz"):
        old.unlink()
    ecu_cmd = _py("fdi_host.live.ecu", *bus, "--vehicle", args.vehicle, "--log", str(out / "ecu.json"),
                  "--rx-log", str(out / "ecu_rx.log"), "--ready-file", str(out / "ecu.ready"), "--quiet",
                  "--origin-file", str(out / "origin.txt"), "--realtime", "--cpu-latency", "0")
    mon_cmd = _py("fdi_host.monitor.cli", *bus, "--vehicle", args.vehicle, "--truth", str(out / "truth.json"),
                  "--ecu-log", str(out / "ecu.json"), "--out-dir", str(out), "--grace", str(args.grace),
                  "--ready-file", str(out / "monitor.ready"), "--quiet",
                  "--origin-file", str(out / "origin.txt"), "--gap-threshold", str(args.gap_threshold))
    drive = ["--scenario", args.scenario, "--vehicle", args.vehicle, *bus, "--quiet", "--origin-file",
             str(out / "origin.txt"), "--realtime"]
    for f in args.fault:
        drive += ["--fault", f]
    if args.no_scenario_faults:
        drive.append("--no-scenario-faults")
    if args.duration is not None:
        drive += ["--duration", str(args.duration)]
    if args.truth_vehicle is not None:
        drive += ["--truth-vehicle", args.truth_vehicle]
    if args.seed is not None:
        drive += ["--seed", str(args.seed)]
    sim_cmd = _py("fdi_host.cli", "live", *drive, "--out", str(out / "drive.blf"), "--truth",
                  str(out / "truth.json"), "--send-log", str(out / "send.npz"),
                  *(["--bus-load", str(args.bus_load)] if args.bus_load > 0.0 else []))
    # The restarted simulator sends the drive the first one recorded (drive.blf): the vehicle drove on, only
    # the sending process restarted; live_sim directly, without the simulator's imports, is back in ~1 s.
    sim_resume_cmd = _py("fdi_host.live.sim", *drive, "--resume", "--counter-start", str(args.sim_counter_start),
                         "--frames-from", str(out / "drive.blf"))
    print(f"fdi-live: {label}, table {args.vehicle}, scenario {args.scenario} {' '.join(args.fault)}", flush=True)
    if schedule:
        print("fdi-live: restarts: " + ", ".join(f"{e.target} {e.action} at t={e.t:g} s" for e in schedule),
              flush=True)
    ecu = Managed("ecu", ecu_cmd, out / "ecu.txt")
    sim = Managed("simulator", sim_cmd, out / "sim.txt")
    mon = Managed("monitor", mon_cmd, out / "monitor.txt")
    sim_rc = 2
    try:
        ecu.start()
        mon.start()
        procs = [p for p in (ecu.proc, mon.proc) if p is not None]
        err = _wait_ready([out / "ecu.ready", out / "monitor.ready"], procs, args.start_timeout)
        if err is not None:
            print(f"fdi-live: {err}; see {out}/ecu.txt and {out}/monitor.txt", file=sys.stderr)
            return EXIT_ERROR
        sim_rc = _supervise(args, out, ecu, sim, sim_resume_cmd, schedule)
        time.sleep(0.5)  # the last diagnosis frames
    finally:
        sim.kill()
        ecu_rc = ecu.stop()
        mon_rc = mon.stop(120.0)
        for m in (ecu, sim, mon):
            m.close()
    print((out / "ecu.txt").read_text(encoding="utf-8", errors="replace").strip())
    print((out / "monitor.txt").read_text(encoding="utf-8", errors="replace").strip())
    if sim_rc != 0:
        print((out / "sim.txt").read_text(encoding="utf-8", errors="replace"), file=sys.stderr)
    rp = out / "report.json"
    if sim.kills:
        print("frames sent / received: not compared (a killed simulator writes no send log); see the monitor's "
              "frame table and gaps above")
    elif rp.exists() and (out / "send.npz").exists():
        doc = json.loads(rp.read_text(encoding="utf-8"))
        rows = sent_vs_received(out / "send.npz", doc)
        print("frames sent / received by the monitor: " + ", ".join(f"0x{i:03X} {s}/{r}" for i, s, r in rows))
        other_sent, other_rx = other_ecus_sent_vs_received(out / "send.npz", doc)
        if other_sent:
            print(f"other ECUs' frames sent / received by the monitor: {other_sent}/{other_rx}")
        print(f"lost in total: {sum(s - r for _, s, r in rows) + other_sent - other_rx}")
    rc = max(sim_rc, ecu_rc, mon_rc)
    if rc != 0:
        print(f"fdi-live: exit codes sim {sim_rc}, ecu {ecu_rc}, monitor {mon_rc}", file=sys.stderr)
    return rc


def main(argv: Sequence[str] | None = None) -> int:
    args_list = list(sys.argv[1:] if argv is None else argv)
    args = build_parser().parse_args(args_list)
    return run("fdi-live", lambda: start(args, args_list))


def start(args: argparse.Namespace, args_list: list[str]) -> int:
    """``fdi-live`` after its options are parsed: choose the transport, run the three programs."""
    options = BusOptions.from_args(args)
    group = args.channel or DEFAULT_CHANNEL
    mode = args.transport
    if mode == "auto":
        mode = "bus" if replace(options, channel=None).given else "vcan" if vcan_available() else "netns"
        if mode == "netns" and not inside_private_netns():
            print(f"fdi-live: no SocketCAN {VCAN_CHANNEL} ({vcan_missing()}); the simulated bus, "
                  f"{SIMULATED_INTERFACE} {group} in a private network namespace", file=sys.stderr, flush=True)
    if mode == "bus":
        return _on_configured_bus(args, options)
    if mode == "vcan":
        if not vcan_available():
            print(f"fdi-live: no {VCAN_CHANNEL} (kernel without AF_CAN or interface missing)", file=sys.stderr)
            return EXIT_ERROR
        return run_here(args, ["--interface", "socketcan", "--channel", VCAN_CHANNEL], f"socketcan {VCAN_CHANNEL}")
    simulated = (["--interface", SIMULATED_INTERFACE, "--channel", group], f"{SIMULATED_INTERFACE} {group}")
    if mode == "current" or inside_private_netns():
        return run_here(args, *simulated)
    chk = check_unshare()
    if not chk.ok:
        if args.transport == "auto":  # last resort: multicast on this host's network
            print(f"fdi-live: {chk.reason}; falling back to udp_multicast in this network namespace",
                  file=sys.stderr)
            return run_here(args, *simulated)
        print(f"fdi-live: {chk.reason}; use --transport current to run udp_multicast in this namespace",
              file=sys.stderr)
        return EXIT_ERROR
    env_cmd = netns_command([sys.executable, "-m", "fdi_host.live.runner", *args_list])
    return subprocess.run(env_cmd, check=False, env=os.environ.copy()).returncode


def _on_configured_bus(args: argparse.Namespace, options: BusOptions) -> int:
    """The three programs on the bus the options and python-can's configuration name (each resolves the same
    options itself); not on python-can's virtual bus, which one process cannot share with another."""
    try:
        config = resolve_bus(options)
    except BUS_ERRORS as exc:
        print(f"fdi-live: cannot use the CAN bus: {' '.join(str(exc).split())}", file=sys.stderr)
        return EXIT_ERROR
    if config.interface == "virtual":
        print("fdi-live: python-can's virtual bus lives inside one process; the ECU, the monitor and the simulator "
              "are three: use vcan, udp_multicast or an adapter", file=sys.stderr)
        return EXIT_ERROR
    if config.note is not None:
        print(f"fdi-live: {config.note}", file=sys.stderr, flush=True)
    return run_here(args, options.argv(), f"{config.describe()} (from the {config.source})")


if __name__ == "__main__":
    raise SystemExit(main())
