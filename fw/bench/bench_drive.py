"""The drive the fw benchmarks step through (scripts/bench_fw.sh): a simulated ROMO drive as the ECU's 10 ms steps
see it (the CAN frames' values, DBC scaling; fdi_host.can.ecu_view), fault-free first, then a step fault that starts
an isolation episode in both benchmarked tables, written as a small binary file for bench_host.c and bench_m4.c.

File layout (little-endian): uint32 magic 0x42494446 ("FDIB"), uint32 n_steps, uint32 n_signals, uint32 fault_step
(first step with the fault), then per step: uint32 validity mask, n_signals float32 values in the frame order of the
ROMO target (fdi_romo_signal_names). The omega1_m sample is invalid for 20 steps at 1 s (a re-arm and a filter
restart inside the warm-up).

Usage: python fw/bench/bench_drive.py OUT.bin
"""

from __future__ import annotations

import argparse
import struct
from pathlib import Path

import numpy as np

SCENARIO = "cornering"
DURATION_S = 14.0
FAULT = ("f4", 8.0, 0.5)  # vx sensor offset 0.5 m/s from 8 s: both tables alarm within ~0.1 s
SEED = 5
DT = 0.01
DROP = ("omega1_m", 100, 120)  # signal invalid on steps [100, 120)
MAGIC = 0x42494446


def write_drive(out: Path) -> tuple[int, int]:
    from fdi_host.ecu.bindings import table_info
    from fdi_host.tuning.drives import drive

    names = table_info("romo").signal_names
    t, sig = drive(SCENARIO, faults=[FAULT], duration=DURATION_S, seed=SEED, dt=DT, as_ecu_sees=True)
    n = len(t)
    values = np.column_stack([np.asarray(sig[s], dtype=np.float32) for s in names])
    validity = np.full(n, (1 << len(names)) - 1, dtype=np.uint32)
    drop = names.index(DROP[0])
    validity[DROP[1]:DROP[2]] &= ~np.uint32(1 << drop)
    fault_step = int(np.searchsorted(t, FAULT[1] - 1e-9))
    with out.open("wb") as fh:
        fh.write(struct.pack("<4I", MAGIC, n, len(names), fault_step))
        for k in range(n):
            fh.write(struct.pack("<I", int(validity[k])))
            fh.write(values[k].astype("<f4").tobytes())
    return n, fault_step


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    args = ap.parse_args()
    n, fault_step = write_drive(args.out)
    print(f"wrote {args.out}: {SCENARIO} drive, {n} steps of {DT * 1e3:g} ms, {FAULT[0]} {FAULT[2]:g} from step "
          f"{fault_step}")


if __name__ == "__main__":
    main()
