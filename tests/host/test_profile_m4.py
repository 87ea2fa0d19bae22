"""fw/bench/m4/profile.py: qemu's trace of the profile build -> instructions per step, per phase and function. A
synthetic trace: each block's instructions count for its function once per execution, a step of a phase runs from
its bench_step_<phase> entry to the next block of the harness, blocks outside steps count for nothing."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

spec = importlib.util.spec_from_file_location("fdi_profile_m4", Path(__file__).resolve().parents[2] / "fw" / "bench"
                                              / "m4" / "profile.py")
assert spec is not None and spec.loader is not None
profile_m4 = importlib.util.module_from_spec(spec)
sys.modules["fdi_profile_m4"] = profile_m4
spec.loader.exec_module(profile_m4)


class FakeSymbols(profile_m4.Symbols):  # type: ignore[misc, name-defined]
    def __init__(self) -> None:
        self.rows = [(0x100, 0x40, "main"), (0x200, 0x10, "bench_step_fault_free"),
                     (0x210, 0x10, "bench_step_undecided"), (0x300, 0x100, "fdi_diag_step"),
                     (0x400, 0x80, "romo_gen_step")]
        self.starts = [r[0] for r in self.rows]


def block(addr: int, n: int) -> str:
    return "IN: x\n" + "".join(f"0x{addr + 2 * k:08x}:  0000  nop\n" for k in range(n)) + "\n"


def run(addr: int) -> str:
    return f"Trace 0: 0x7f00 [00000000/{addr:08x}/00000000/ff200000] x\n"


def test_steps_are_attributed_to_their_phase_and_function(tmp_path: Path) -> None:
    log = "".join([block(0x100, 5), block(0x200, 2), block(0x210, 3), block(0x300, 10), block(0x400, 40),
                   block(0x308, 4)])
    # two fault-free steps and one undecided step, the harness between them
    steps = [0x100, 0x200, 0x300, 0x400, 0x308, 0x100, 0x200, 0x300, 0x308, 0x100, 0x210, 0x300, 0x400, 0x400,
             0x308, 0x100]
    log += "".join(run(a) for a in steps)
    trace = tmp_path / "trace.log"
    trace.write_text(log)
    per, steps_of = profile_m4.profile(trace, FakeSymbols())
    assert steps_of == {"fault-free": 2, "undecided": 1}
    assert per["fault-free"] == {"bench_step_fault_free": 4, "fdi_diag_step": 28, "romo_gen_step": 40}
    assert per["undecided"] == {"bench_step_undecided": 3, "fdi_diag_step": 14, "romo_gen_step": 80}
    assert "main" not in per["fault-free"] and "main" not in per["undecided"]
