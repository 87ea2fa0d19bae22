"""``fdi-live``: a simulated drive live over a bus, with the ECU and the monitor as separate processes.

Transport (``--transport auto``): SocketCAN ``vcan0`` where the kernel has AF_CAN and the interface exists;
otherwise python-can ``udp_multicast`` in a private network namespace (the runner re-executes itself under
``unshare -n``, see `fdi_host.netns`), and where that is not permitted udp_multicast in the current network
namespace; ``--transport current`` forces the latter, ``netns`` / ``vcan`` fail if not available.

Order: ``fdi-ecu`` and ``fdi-monitor`` start and signal readiness (ready files), then ``fdi-sim live`` sends the
drive in real time; when it is done the ECU is stopped (SIGTERM: it writes its log), then the monitor (it
scores against the truth and writes report.md/json and plots). Printed: frames sent vs received per message
(from the simulator's send log and the monitor's counts) and the monitor's score table.
"""

from __future__ import annotations

import argparse
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

from fdi_host.live_sender import SendLog
from fdi_host.netns import check_unshare, inside_private_netns, netns_command, vcan_available

EPILOG = """\
examples:
  fdi-live --scenario fig6 --fault f4@5s:0.5 --table kin --out-dir out/live
  fdi-live --scenario straight --duration 12 --no-scenario-faults --fault f4@4s:0.5:end=8s --table kin
  fdi-live --transport current ...     (udp_multicast in this network namespace, no unshare)

outputs in --out-dir: drive.blf + truth.json (what was sent), send.npz (send times), ecu.json (ECU log),
ecu_rx.log (frames as the ECU received them, receive times),
report.md, report.json, diagnosis.png, residuals.png (monitor), ecu.txt / monitor.txt / sim.txt (their output).
"""


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="fdi-live", description=__doc__.splitlines()[0] if __doc__ else None,
                                 epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenario", default="fig6", help="scenario name or TOML path")
    ap.add_argument("--fault", action="append", default=[], metavar="SPEC", help="fault to inject (repeatable)")
    ap.add_argument("--no-scenario-faults", action="store_true", help="ignore the faults of the scenario file")
    ap.add_argument("--duration", type=float, help="override the scenario duration [s]")
    ap.add_argument("--seed", type=int, help="override the noise seed")
    ap.add_argument("--table", choices=("romo", "kin"), default="romo",
                    help="ECU diagnosis table: romo (generated, default) or kin (hand-written kinematic tests)")
    ap.add_argument("--transport", choices=("auto", "vcan", "netns", "current"), default="auto",
                    help="vcan0, udp_multicast in a private netns, or udp_multicast here (default auto)")
    ap.add_argument("--channel", default="239.74.163.2", help="multicast group for udp_multicast")
    ap.add_argument("--grace", type=float, default=3.0, help="scoring grace after a fault's end [s] (default 3)")
    ap.add_argument("--out-dir", type=Path, default=Path("out/live"), help="output directory")
    ap.add_argument("--start-timeout", type=float, default=60.0, help="max wait for ECU and monitor to start [s]")
    return ap


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


def _stop(p: subprocess.Popen[bytes], timeout: float = 20.0) -> int:
    if p.poll() is None:
        p.send_signal(signal.SIGTERM)
        try:
            p.wait(timeout)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()
    return int(p.returncode)


def sent_vs_received(send_log: Path, report: dict[str, Any]) -> list[tuple[int, int, int]]:
    """(frame id, sent, received by the monitor) per simulated message."""
    sent = Counter(SendLog.load(send_log).frame_id)
    msgs = (report.get("frames") or {}).get("messages", {})
    rec = {int(k, 16): int(v["received"]) for k, v in msgs.items()}
    return [(fid, n, rec.get(fid, 0)) for fid, n in sorted(sent.items())]


def run_here(args: argparse.Namespace, interface: str, channel: str) -> int:
    out: Path = args.out_dir
    out.mkdir(parents=True, exist_ok=True)
    for f in ("ecu.ready", "monitor.ready", "ecu.json", "report.json", "origin.txt"):
        (out / f).unlink(missing_ok=True)
    bus = ["--interface", interface, "--channel", channel]
    ecu_cmd = _py("fdi_host.ecu_cli", *bus, "--table", args.table, "--log", str(out / "ecu.json"),
                  "--rx-log", str(out / "ecu_rx.log"), "--ready-file", str(out / "ecu.ready"), "--quiet",
                  "--origin-file", str(out / "origin.txt"), "--realtime")
    mon_cmd = _py("fdi_host.monitor", *bus, "--table", args.table, "--truth", str(out / "truth.json"),
                  "--ecu-log", str(out / "ecu.json"), "--out-dir", str(out), "--grace", str(args.grace),
                  "--ready-file", str(out / "monitor.ready"), "--quiet",
                  "--origin-file", str(out / "origin.txt"))
    sim_cmd = _py("fdi_host.sim_cli", "live", "--scenario", args.scenario, *bus, "--out", str(out / "drive.blf"),
                  "--truth", str(out / "truth.json"), "--send-log", str(out / "send.npz"), "--quiet",
                  "--origin-file", str(out / "origin.txt"), "--realtime")
    for f in args.fault:
        sim_cmd += ["--fault", f]
    if args.no_scenario_faults:
        sim_cmd.append("--no-scenario-faults")
    if args.duration is not None:
        sim_cmd += ["--duration", str(args.duration)]
    if args.seed is not None:
        sim_cmd += ["--seed", str(args.seed)]
    print(f"fdi-live: {interface} {channel}, table {args.table}, scenario {args.scenario} {' '.join(args.fault)}",
          flush=True)
    with (out / "ecu.txt").open("wb") as ecu_out, (out / "monitor.txt").open("wb") as mon_out, \
            (out / "sim.txt").open("wb") as sim_out:
        ecu = subprocess.Popen(ecu_cmd, stdout=ecu_out, stderr=subprocess.STDOUT)
        mon = subprocess.Popen(mon_cmd, stdout=mon_out, stderr=subprocess.STDOUT)
        try:
            err = _wait_ready([out / "ecu.ready", out / "monitor.ready"], [ecu, mon], args.start_timeout)
            if err is not None:
                print(f"fdi-live: {err}; see {out}/ecu.txt and {out}/monitor.txt", file=sys.stderr)
                return 2
            t0 = time.monotonic()
            sim_rc = subprocess.run(sim_cmd, stdout=sim_out, stderr=subprocess.STDOUT, check=False).returncode
            print(f"fdi-live: drive done in {time.monotonic() - t0:.1f} s (simulation + real-time sending)", flush=True)
            time.sleep(0.5)  # the last diagnosis frames
        finally:
            ecu_rc = _stop(ecu)
            mon_rc = _stop(mon, 120.0)
    print((out / "ecu.txt").read_text(encoding="utf-8", errors="replace").strip())
    print((out / "monitor.txt").read_text(encoding="utf-8", errors="replace").strip())
    if sim_rc != 0:
        print((out / "sim.txt").read_text(encoding="utf-8", errors="replace"), file=sys.stderr)
    rp = out / "report.json"
    if rp.exists() and (out / "send.npz").exists():
        rows = sent_vs_received(out / "send.npz", json.loads(rp.read_text(encoding="utf-8")))
        print("frames sent / received by the monitor: " + ", ".join(f"0x{i:03X} {s}/{r}" for i, s, r in rows))
        print(f"lost in total: {sum(s - r for _, s, r in rows)}")
    rc = max(sim_rc, ecu_rc, mon_rc)
    if rc != 0:
        print(f"fdi-live: exit codes sim {sim_rc}, ecu {ecu_rc}, monitor {mon_rc}", file=sys.stderr)
    return rc


def main(argv: Sequence[str] | None = None) -> int:
    args_list = list(sys.argv[1:] if argv is None else argv)
    args = build_parser().parse_args(args_list)
    mode = args.transport
    if mode == "auto":
        mode = "vcan" if vcan_available() else "netns"
    if mode == "vcan":
        if not vcan_available():
            print("fdi-live: no vcan0 (kernel without AF_CAN or interface missing)", file=sys.stderr)
            return 2
        return run_here(args, "socketcan", "vcan0")
    if mode == "current" or inside_private_netns():
        return run_here(args, "udp_multicast", args.channel)
    chk = check_unshare()
    if not chk.ok:
        if args.transport == "auto":  # last resort: multicast on this host's network
            print(f"fdi-live: {chk.reason}; falling back to udp_multicast in this network namespace",
                  file=sys.stderr)
            return run_here(args, "udp_multicast", args.channel)
        print(f"fdi-live: {chk.reason}; use --transport current to run udp_multicast in this namespace",
              file=sys.stderr)
        return 2
    env_cmd = netns_command([sys.executable, "-m", "fdi_host.live_runner", *args_list])
    return subprocess.run(env_cmd, check=False, env=os.environ.copy()).returncode


if __name__ == "__main__":
    raise SystemExit(main())
