"""Restarts during a live run (``fdi-live --restart-ecu-at T --restart-sim-at T``): the schedule and the
process handling.

A restart kills the process with SIGKILL at drive time T (a crash: it writes nothing, its logs of the run so
far are lost), waits the down time, and starts a new one with the same command line:

* the ECU (``fdi-ecu``) anchors to the drive's t = 0 of ``origin.txt`` and starts stepping at the step
  boundary before its first frame; its tests warm up again before they are evaluated;
* the simulator (``fdi-sim live --resume --frames-from drive.blf``: the vehicle drove on, only the sender
  restarted) sends the frames of the drive not yet due, at their times, every message's alive counter
  starting again at ``--sim-counter-start``; the ECU rejects the first frame of each message (a counter jump:
  fw/ecu takes it as the new reference and accepts the next frame), and warms up again.

Times are on the drive's clock (seconds after its t = 0), read from ``origin.txt`` written by the first
simulator before it sends.
"""

from __future__ import annotations

import signal
import subprocess
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO


@dataclass(frozen=True)
class RestartEvent:
    t: float  # drive time [s]
    target: str  # "ecu" or "sim"
    action: str  # "kill" or "start"


def restart_schedule(ecu_at: Sequence[float], sim_at: Sequence[float], ecu_down: float,
                     sim_down: float) -> list[RestartEvent]:
    """Kill/start events in time order; raises ValueError for negative times, a down time <= 0, or two
    restarts of the same process that overlap (the next kill before the previous restart)."""
    events: list[RestartEvent] = []
    for target, times, down in (("ecu", ecu_at, ecu_down), ("sim", sim_at, sim_down)):
        if times and not down > 0.0:
            raise ValueError(f"{target} down time must be > 0 s, got {down}")
        last_start = -1.0
        for t in sorted(times):
            if not t >= 0.0:
                raise ValueError(f"{target} restart time must be >= 0 s, got {t}")
            if t <= last_start:
                raise ValueError(f"{target} restart at {t:g} s overlaps the previous one (back at {last_start:g} s)")
            events += [RestartEvent(t, target, "kill"), RestartEvent(t + down, target, "start")]
            last_start = t + down
    return sorted(events, key=lambda e: (e.t, e.action != "kill", e.target))


@dataclass
class Managed:
    """One restartable process: its command, its output file (appended to across restarts), its instances."""

    name: str
    cmd: list[str]
    out_path: Path
    proc: subprocess.Popen[bytes] | None = None
    instances: int = 0
    kills: list[float] = field(default_factory=list)  # drive times of the kills
    starts: list[float] = field(default_factory=list)  # drive times of the restarts
    ready: list[float] = field(default_factory=list)  # drive times a restarted instance signalled readiness
    _fh: IO[bytes] | None = None

    def start(self, cmd: list[str] | None = None) -> subprocess.Popen[bytes]:
        if self._fh is None:
            self._fh = self.out_path.open("wb")
        elif self.instances:
            self._fh.write(f"--- {self.name} restarted ---\n".encode())
            self._fh.flush()
        self.proc = subprocess.Popen(cmd or self.cmd, stdout=self._fh, stderr=subprocess.STDOUT)
        self.instances += 1
        return self.proc

    def kill(self) -> bool:
        """SIGKILL the running instance; False if it had already exited."""
        p = self.proc
        if p is None or p.poll() is not None:
            return False
        p.send_signal(signal.SIGKILL)
        p.wait()
        self.proc = None
        return True

    def stop(self, timeout: float = 20.0) -> int:
        """SIGTERM (the process writes its logs), SIGKILL after `timeout`; the exit code (0 if none runs)."""
        p = self.proc
        if p is None:
            return 0
        if p.poll() is None:
            p.send_signal(signal.SIGTERM)
            try:
                p.wait(timeout)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        return int(p.returncode)

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()
            self._fh = None
