"""fw/bench/m4/profile.py: qemu's trace of the profile build -> instructions per step, per phase and function. A
synthetic trace: each block's instructions count for its function once per execution, a step of a phase runs from
its bench_step_<phase> entry to the next block of the harness, blocks outside steps count for nothing; --lines
spreads one function's instructions over the source lines of their addresses."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

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


def trace_of(tmp_path: Path) -> Path:
    log = "".join([block(0x100, 5), block(0x200, 2), block(0x210, 3), block(0x300, 10), block(0x400, 40),
                   block(0x308, 4)])
    # two fault-free steps and one undecided step, the harness between them
    steps = [0x100, 0x200, 0x300, 0x400, 0x308, 0x100, 0x200, 0x300, 0x308, 0x100, 0x210, 0x300, 0x400, 0x400,
             0x308, 0x100]
    log += "".join(run(a) for a in steps)
    trace = tmp_path / "trace.log"
    trace.write_text(log)
    return trace


def test_steps_are_attributed_to_their_phase_and_function(tmp_path: Path) -> None:
    prof = profile_m4.profile(trace_of(tmp_path), FakeSymbols())
    per, steps_of = prof.per, prof.steps
    assert steps_of == {"fault-free": 2, "undecided": 1}
    assert per["fault-free"] == {"bench_step_fault_free": 4, "fdi_diag_step": 28, "romo_gen_step": 40}
    assert per["undecided"] == {"bench_step_undecided": 3, "fdi_diag_step": 14, "romo_gen_step": 80}
    assert "main" not in per["fault-free"] and "main" not in per["undecided"]


def test_calls_count_the_entries_of_a_function_not_its_inner_blocks(tmp_path: Path) -> None:
    prof = profile_m4.profile(trace_of(tmp_path), FakeSymbols())
    # fdi_diag_step is entered at 0x300 once per step (0x308, inside it, is no call); romo_gen_step once in the
    # first fault-free step, twice in the undecided one
    assert prof.calls["fault-free"] == {"bench_step_fault_free": 2, "fdi_diag_step": 2, "romo_gen_step": 1}
    assert prof.calls["undecided"] == {"bench_step_undecided": 1, "fdi_diag_step": 1, "romo_gen_step": 2}


def test_lines_spread_one_functions_instructions_over_its_source_lines(tmp_path: Path,
                                                                       monkeypatch: pytest.MonkeyPatch,
                                                                       capsys: pytest.CaptureFixture[str]) -> None:
    prof = profile_m4.profile(trace_of(tmp_path), FakeSymbols(), "fdi_diag_step")
    assert prof.blocks["fault-free"] == {0x300: 2, 0x308: 2}
    assert prof.blocks["undecided"] == {0x300: 1, 0x308: 1}
    # block 0x300 holds 0x300..0x312 (10 instructions), block 0x308 0x308..0x30e (4): the first 4 of 0x300 on line
    # 7, the rest on line 9
    lines = {a: ("d.c:7" if a < 0x308 else "d.c:9") for a in range(0x300, 0x314, 2)}
    monkeypatch.setattr(profile_m4, "source_lines", lambda elf, addrs: {a: lines[a] for a in addrs})
    profile_m4.print_lines(prof, Path("x.elf"), "fdi_diag_step", 5)
    out = capsys.readouterr().out.splitlines()
    # per fault-free step: 10 + 4 instructions, 4 on line 7, 6 + 4 on line 9
    assert out[0] == "fault-free: fdi_diag_step, 14 instructions per step, by source line"
    assert out[1].split() == ["10.0", "71.4", "%", "d.c:9"]
    assert out[2].split() == ["4.0", "28.6", "%", "d.c:7"]
    assert out[3].startswith("undecided: fdi_diag_step, 14 instructions")


def test_ops_counts_one_functions_instructions_by_kind(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # romo_gen_step's block: a spill store and reload, a constant from the literal pool, an input, two multiplies,
    # a division, a push; the diagnoser's blocks are all nop
    gen = ["e92d 4ff0  push.w   {r4, r5, r6, r7, r8, sb, sl, fp, lr}", "ed8d 0a01  vstr     s0, [sp, #4]",
           "ed9f 7a05  vldr     s14, [pc, #0x14]", "ed90 7a02  vldr     s14, [r0, #8]",
           "ee27 7a27  vmul.f32 s14, s14, s15", "ee27 7a27  vmul.f32 s14, s14, s15",
           "ee87 7a27  vdiv.f32 s14, s14, s15", "ed9d 0a01  vldr     s0, [sp, #4]"]
    log = "".join([block(0x100, 5), block(0x200, 2), block(0x210, 3), block(0x300, 10), block(0x308, 4)])
    log += "IN: x\n" + "".join(f"0x{0x400 + 4 * k:08x}:  {ins}\n" for k, ins in enumerate(gen)) + "\n"
    steps = [0x100, 0x200, 0x300, 0x400, 0x308, 0x100, 0x200, 0x300, 0x308, 0x100, 0x210, 0x300, 0x400, 0x400,
             0x308, 0x100]
    log += "".join(run(a) for a in steps)
    trace = tmp_path / "trace.log"
    trace.write_text(log)
    prof = profile_m4.profile(trace, FakeSymbols(), "romo_gen_step")
    assert prof.per["fault-free"]["romo_gen_step"] == 8 and prof.per["undecided"]["romo_gen_step"] == 16
    profile_m4.print_ops(prof, "romo_gen_step", 10)
    out = capsys.readouterr().out.splitlines()
    # fault-free: one execution in two steps; stack accesses: push, vstr [sp], vldr [sp] = 3 of 8
    assert out[0] == ("fault-free: romo_gen_step, 4 instructions per step by kind; the stack's loads and stores 2 "
                      "(37.5 %)")
    rows = {" ".join(r.split()[3:]): float(r.split()[0]) for r in out[1:8]}
    assert rows == {"vldr (stack)": 0.5, "vmul.f32": 1.0, "vstr (stack)": 0.5, "vldr (literal pool)": 0.5,
                    "vldr (memory)": 0.5, "vdiv.f32": 0.5, "push.w (stack)": 0.5}
    assert out[8].startswith("undecided: romo_gen_step, 16 instructions per step by kind")
    assert profile_m4.op_kind("ldr.w", "r3, [pc, #0x1c]") == "ldr.w (literal pool)"
    assert profile_m4.op_kind("vpop", "{s16, s17}") == "vpop (stack)"
    assert profile_m4.op_kind("vmla.f32", "s0, s1, s2") == "vmla.f32"
