"""The drive the fw benchmarks step through (scripts/bench_fw.sh): a simulated ROMO drive as the ECU's 10 ms steps
see it (the CAN frames' values, DBC scaling; fdi_host.can.ecu_view), fault-free first, then two isolation episodes
of the ROMO table, written as a small binary file for bench_host.c and bench_m4.c: a vx sensor offset for 2 s
(both tables alarm within ~0.1 s; the ROMO table isolates it at once, so no fault is left to decide) and, after that
episode has ended, a front-left steering offset at its required size (0.06 rad) to the end, which the ROMO table
cannot separate from the front-right one in cornering: the exoneration keeps asking the generators for their
sensitivities for the rest of the drive, the diagnoser's costliest steady state.

File layout (little-endian): uint32 magic 0x42494446 ("FDIB"), uint32 n_steps, uint32 n_signals, uint32 fault_step
(first step with a fault), then per step: uint32 validity mask, n_signals float32 values in the frame order of the
ROMO target (fdi_romo_signal_names). The omega1_m sample is invalid for 20 steps at 1 s (a re-arm and a filter
restart inside the warm-up).

Usage: python host_tools/bench/fw_bench_drive.py OUT.bin
"""

from __future__ import annotations

import argparse
import struct
from pathlib import Path

import numpy as np

SCENARIO = "cornering"
DURATION_S = 24.0
# (fault, onset s, size[, end s]): the first episode ends 3 s after its last alarm (fdi_diag_config_default)
FAULTS = (("f4", 8.0, 0.5, 9.0), ("f6", 16.0, 0.06))
SEED = 5
DT = 0.01
DROP = ("omega1_m", 100, 120)  # signal invalid on steps [100, 120)
MAGIC = 0x42494446


def write_drive(out: Path) -> tuple[int, int]:
    from fdi_host.ecu.bindings import table_info
    from fdi_host.tuning.drives import drive

    names = table_info("romo").signal_names
    t, sig = drive(SCENARIO, faults=FAULTS, duration=DURATION_S, seed=SEED, dt=DT, as_ecu_sees=True)
    n = len(t)
    values = np.column_stack([np.asarray(sig[s], dtype=np.float32) for s in names])
    validity = np.full(n, (1 << len(names)) - 1, dtype=np.uint32)
    drop = names.index(DROP[0])
    validity[DROP[1]:DROP[2]] &= ~np.uint32(1 << drop)
    fault_step = int(np.searchsorted(t, FAULTS[0][1] - 1e-9))
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
    faults = ", ".join(f"{f[0]} {f[2]:g} from {f[1]:g} s" + (f" to {f[3]:g} s" if len(f) > 3 else "") for f in FAULTS)
    print(f"wrote {args.out}: {SCENARIO} drive, {n} steps of {DT * 1e3:g} ms, {faults} (first fault at step "
          f"{fault_step})")


if __name__ == "__main__":
    main()
