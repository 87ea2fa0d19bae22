"""The pure C SocketCAN ECU (fw/ecu/linux/fdi_ecu_socketcan.c) on a real vcan0, inside a QEMU guest.

This machine's kernel has no AF_CAN, so tests/vm boots Debian's kernel under QEMU (TCG, no KVM, virtual clock)
with a busybox initramfs (tests/vm/prepare.sh, cached in .cache/vm). In the guest, fdi-can-play plays a
simulated drive (fig6 profile, vx sensor drifting from 5 s, f4) onto vcan0 in real time, fdi-ecu-socketcan
(kin table) answers with diagnosis frames and fdi-can-record records them. The test checks the frames (E2E CRC,
counter sequence), the ECU's counters (every frame received and accepted) and that the guest's diagnosis is the
one the offline bindings (fdi_host.ecu.bindings, the same C core) give on the same log: no detection before the
fault, the fault isolated as f4 and as nothing else, with the same timing within a few steps. Skipped, with the
reason, where qemu-system-x86_64, busybox-static or the kernel package are not available.
"""

from __future__ import annotations

import collections
import itertools
import shutil
import subprocess
from pathlib import Path

import pytest

from fdi_host.can import e2e
from fdi_host.can.dbc import CanDatabase
from fdi_host.can.logs import read_log, write_log
from fdi_host.can.traffic import build_frames
from fdi_host.ecu.bindings import DIAG_ID, Ecu
from fdi_host.sim.faults import FaultSpec
from fdi_host.sim.scenario import load_scenario
from fdi_host.sim.vehicle_sim import simulate

REPO = Path(__file__).resolve().parents[2]
BUILD = REPO / "build" / "vm"
ONSET = 5.0
DURATION = 10.0
VM_TIMEOUT_S = 240

RUN_SH = """\
# everything the run touches lives in the guest's tmpfs: a 9p access during the run would stall the guest's
# virtual clock (I/O wait is skipped time under -icount sleep=off)
cp {bindir}/fdi-can-record {bindir}/fdi-ecu-socketcan {bindir}/fdi-can-play /results/drive.log /tmp/
cd /tmp
./fdi-can-record vcan0 /tmp/diag.log --id 200 > /tmp/record.out &
REC=$!
./fdi-ecu-socketcan vcan0 --table kin --quiet > /tmp/ecu.out &
ECU=$!
sleep 1
./fdi-can-play vcan0 /tmp/drive.log > /tmp/play.out
sleep 0.3
kill -INT $ECU; wait $ECU
kill -INT $REC; wait $REC
cp /tmp/diag.log /tmp/record.out /tmp/ecu.out /tmp/play.out /results/
"""


def _kv(path: Path) -> dict[str, str]:
    out = {}
    for line in path.read_text().splitlines():
        for item in line.split():
            if "=" in item:
                k, v = item.split("=", 1)
                out[(line.split()[0] + "." + k) if line.startswith("msg.") else k] = v
    return out


@pytest.fixture(scope="module")
def guest_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    if shutil.which("qemu-system-x86_64") is None:
        pytest.skip("qemu-system-x86_64 is not installed (scripts/bootstrap.sh installs qemu-system-x86)")
    prep = subprocess.run(["bash", str(REPO / "tests/vm/prepare.sh")], capture_output=True, text=True, timeout=600)
    if prep.returncode != 0:
        pytest.skip(f"the QEMU guest cannot be prepared here: {prep.stderr.strip()[-300:]}")
    cfg = ["cmake", "-S", str(REPO), "-B", str(BUILD), "-DCMAKE_BUILD_TYPE=Release", "-DFDI_LINUX_STATIC=ON",
           "-DFDI_BUILD_TESTS=OFF", "-DFDI_BUILD_BENCH=OFF"]
    subprocess.run(cfg, check=True, capture_output=True, timeout=300)
    subprocess.run(["cmake", "--build", str(BUILD), "-j", "2", "--target", "fdi_ecu_socketcan", "fdi_can_play",
                    "fdi_can_record"], check=True, capture_output=True, timeout=600)
    res_dir = tmp_path_factory.mktemp("vm")
    sim = simulate(load_scenario("fig6"), [FaultSpec("f4", ONSET, 2.0, shape="ramp", ramp=4.0)], duration=DURATION)
    write_log(build_frames(sim), res_dir / "drive.log")
    bindir = "/host" + str(BUILD / "fw" / "ecu" / "linux")
    (res_dir / "run.sh").write_text(RUN_SH.format(bindir=bindir))
    vm = subprocess.run(["bash", str(REPO / "tests/vm/run_guest.sh"), str(res_dir), str(VM_TIMEOUT_S)],
                        capture_output=True, text=True, timeout=VM_TIMEOUT_S + 30)
    log = (res_dir / "guest.log").read_text() if (res_dir / "guest.log").exists() else "(no guest.log)"
    shutil.copytree(res_dir, BUILD / "last-run", dirs_exist_ok=True)  # kept for a look after a failure
    assert vm.returncode == 0, f"guest did not power off by itself (rc {vm.returncode}):\n{log}\n{vm.stdout[-2000:]}"
    assert "vcan0 up" in log, log
    assert "run.sh exit 0" in log, log
    return res_dir


def test_guest_ecu_counts_every_frame(guest_run: Path) -> None:
    played = _kv(guest_run / "play.out")
    ecu = _kv(guest_run / "ecu.out")
    n_log = len(read_log(guest_run / "drive.log"))
    assert int(played["sent"]) == n_log and int(played["send_errors"]) == 0
    assert int(ecu["frames"]) == n_log
    assert all(int(v) == 0 for k, v in ecu.items() if k.startswith("rejected."))
    for can_id in ("0x080", "0x088", "0x100", "0x110"):
        assert ecu[f"msg.{can_id}.received"] == ecu[f"msg.{can_id}.accepted"]
        assert int(ecu[f"msg.{can_id}.timeouts"]) <= 1  # at most once, when the log ends
    assert int(ecu["tx_errors"]) == 0
    assert int(_kv(guest_run / "record.out")["frames"]) == int(ecu["tx_frames"]) > 0.9 * DURATION / 0.01


def test_guest_diagnosis_equals_offline(guest_run: Path) -> None:
    db = CanDatabase()
    guest = read_log(guest_run / "diag.log")
    assert all(f.frame_id == DIAG_ID for f in guest)
    counters = [e2e.counter_of(f.data) for f in guest]
    assert all(b == e2e.next_counter(a) for a, b in itertools.pairwise(counters))
    g = [(f.timestamp, db.decode(DIAG_ID, f.data).signals) for f in guest]  # raises on a bad CRC

    drive = read_log(guest_run / "drive.log")
    off_frames = Ecu("kin").process((f.timestamp, f.frame_id, f.data) for f in drive)
    off = [(t, db.decode(DIAG_ID, d).signals) for t, _, d in off_frames]

    # the guest's ECU ran before and after the log: its steps without input say INPUT_INVALID (4); the log starts
    # with the first INIT (0) frame
    t0_guest = next(t for t, s in g if s["FDI_Status"] == 0) - 0.01

    def first_detection(frames: list[tuple[float, dict[str, float]]], t0: float) -> float:
        return next(t for t, s in frames if s["FDI_Status"] in (2, 3)) - t0

    det_g, det_o = first_detection(g, t0_guest), first_detection(off, 0.0)
    assert det_o > ONSET and det_g > ONSET - 0.05
    assert abs(det_g - det_o) < 0.1, (det_g, det_o)

    def isolated(frames: list[tuple[float, dict[str, float]]]) -> collections.Counter[int]:
        return collections.Counter(int(s["FDI_CandidateFaults"]) for _, s in frames if s["FDI_Status"] == 3)

    iso_g, iso_o = isolated(g), isolated(off)
    assert set(iso_o) == {0x08} and set(iso_g) == {0x08}  # f4 and nothing else
    assert abs(iso_g[0x08] - iso_o[0x08]) <= 0.1 * iso_o[0x08]
    assert all(s["FDI_IsolationClass"] == 4 for _, s in g if s["FDI_Status"] == 3)
    in_log = [s for t, s in g if t0_guest + 0.005 <= t <= t0_guest + DURATION - 0.05]
    assert len(in_log) > 0.9 * DURATION / 0.01
    assert sum(s["FDI_Status"] == 4 for s in in_log) == 0  # no input timeout while the log plays
