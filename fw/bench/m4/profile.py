"""Where the instructions of a diagnosis step go on the Cortex-M4F: per phase of the benchmark drive and per function,
from qemu's instruction trace of the profile build of bench_m4.c (scripts/profile_m4.sh makes both).

qemu -d in_asm,exec,nochain logs each translation block once with its instructions (in_asm) and every execution of
a block (exec, unchained, so none is skipped). A step of a phase is every block executed from the entry of its
bench_step_<phase> function up to the next block of the harness (bench_m4.c's own functions); a block's
instructions count for the function holding it (the ELF's symbols, arm-none-eabi-nm). Printed: per phase the mean
instructions per step in total and per function (the largest first), from the same run, so they add up, and each
function's calls per step and its own instructions a call (a call: an execution of the block at the function's
first address; a function inlined into its caller has no calls of its own and counts for the caller). With
--lines FUNCTION, also the source lines of that function (and of what the compiler inlined into it) where its
instructions go, per phase (arm-none-eabi-addr2line of every executed instruction's address). With --ops FUNCTION,
its instruction mix per phase: executed instructions by mnemonic, the loads and stores by what they address (the
stack: spilled values and locals; the literal pool: constants; other memory), so that a long function shows how
much of it moves values rather than computes them, and how many of its instructions take more than one cycle
(divisions and square roots: 14 on the Cortex-M4F's FPU).

Usage: python fw/bench/m4/profile.py TRACE.log FIRMWARE.elf [--top N] [--lines FUNCTION] [--ops FUNCTION]
"""

from __future__ import annotations

import argparse
import bisect
import re
import subprocess
from collections import Counter, defaultdict
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path

PHASES = {"bench_step_warmup": "warm-up", "bench_step_fault_free": "fault-free",
          "bench_step_episode": "episode", "bench_step_undecided": "undecided"}
# the harness (bench_m4.c and its start-up): a block of these ends the step under way
HARNESS = {"main", "bench_table_drive", "bench_phase_step", "put", "put_u", "put_phase", "semi_call", "read_drive",
           "ticks_since", "cal_loop", "Reset_Handler", "bench_exit"}
BLOCK = re.compile(r"^0x([0-9a-f]{8}):\s+(?:[0-9a-f]{4} ){1,2}\s*(\S+)\s*(.*)$")
MEMORY = ("ldr", "str", "vldr", "vstr", "vldm", "vstm", "vpush", "vpop", "push", "pop")
EXEC = re.compile(r"^Trace \d+: 0x[0-9a-f]+ \[[0-9a-f]+/([0-9a-f]+)/")


class Symbols:
    """The ELF's function symbols: address -> name."""

    def __init__(self, elf: Path) -> None:
        out = subprocess.run(["arm-none-eabi-nm", "-n", "-S", str(elf)], capture_output=True, text=True,
                             check=True).stdout
        rows = []
        for line in out.splitlines():
            p = line.split()
            if len(p) >= 4 and p[2] in "tTwW":
                rows.append((int(p[0], 16) & ~1, int(p[1], 16), p[3]))
        rows.sort()
        self.starts = [r[0] for r in rows]
        self.rows = rows

    def name(self, pc: int) -> str:
        i = bisect.bisect_right(self.starts, pc) - 1
        if i >= 0 and pc < self.rows[i][0] + self.rows[i][1]:
            return self.rows[i][2]
        return "?"


class Profile:
    """Instructions per phase and function, steps per phase, and block executions per phase of one function."""

    def __init__(self) -> None:
        self.per: dict[str, Counter[str]] = defaultdict(Counter)
        self.calls: dict[str, Counter[str]] = defaultdict(Counter)  # phase -> function -> entries
        self.steps: Counter[str] = Counter()
        self.blocks: dict[str, Counter[int]] = defaultdict(Counter)  # phase -> block start -> executions
        self.insns: dict[int, list[int]] = {}  # block start -> its instructions' addresses
        self.ops: dict[int, list[str]] = {}  # block start -> its instructions' kinds (op_kind)


def op_kind(mnemonic: str, operands: str) -> str:
    """An instruction's kind for the mix: its mnemonic, a load or store with what it addresses (the stack, the
    literal pool of constants, other memory; push and pop are stack accesses by name)."""
    if not mnemonic.startswith(MEMORY):
        return mnemonic
    if mnemonic.startswith(("vpush", "vpop", "push", "pop")) or "[sp" in operands:
        return f"{mnemonic} (stack)"
    return f"{mnemonic} (literal pool)" if "[pc" in operands else f"{mnemonic} (memory)"


def profile(trace: Path, syms: Symbols, lines_of: str | None = None) -> Profile:
    """Read the trace; block executions are kept for the function lines_of."""
    out = Profile()
    addrs: list[int] = []
    kinds: list[str] = []
    cur: int | None = None
    names: dict[int, tuple[str, bool]] = {}  # pc -> its function, and whether pc is the function's first address
    phase: str | None = None
    with trace.open(errors="replace") as fh:
        for line in fh:
            m = BLOCK.match(line)
            if m:
                addrs.append(int(m.group(1), 16))
                kinds.append(op_kind(m.group(2), m.group(3)))
                cur = addrs[0]
                continue
            if cur is not None:  # the end of a block's listing
                out.insns[cur] = addrs
                out.ops[cur] = kinds
                cur, addrs, kinds = None, [], []
            m = EXEC.match(line)
            if not m:
                continue
            pc = int(m.group(1), 16)
            known = names.get(pc)
            if known is None:
                known = names[pc] = (syms.name(pc), pc == syms.starts[bisect.bisect_right(syms.starts, pc) - 1])
            fn, entry = known
            if fn in PHASES and entry:
                phase = PHASES[fn]
                out.steps[phase] += 1
            elif fn in HARNESS:
                phase = None
            if phase is not None:
                out.per[phase][fn] += len(out.insns.get(pc, ()))
                if entry:
                    out.calls[phase][fn] += 1
                if fn == lines_of:
                    out.blocks[phase][pc] += 1
    return out


def source_lines(elf: Path, addrs: list[int]) -> dict[int, str]:
    """file:line (basename) of each address, innermost inlined frame first (arm-none-eabi-addr2line -i)."""
    if not addrs:
        return {}
    text = subprocess.run(["arm-none-eabi-addr2line", "-e", str(elf), "-i", "-a", *[hex(a) for a in addrs]],
                          capture_output=True, text=True, check=True).stdout
    where: dict[int, str] = {}
    cur: int | None = None
    for line in text.splitlines():
        if line.startswith("0x"):
            cur = int(line, 16)
        elif cur is not None and cur not in where:
            where[cur] = Path(line.split(" ")[0]).name
    return where


def _tallies(prof: Profile, kinds: Callable[[int], Iterable[str]]) -> Iterator[tuple[str, int, Counter[str]]]:
    """Per phase with steps and kept blocks: the phase, its steps and its executed instructions counted by
    `kinds` (block start -> one key per instruction of the block)."""
    for phase in PHASES.values():
        n = prof.steps.get(phase, 0)
        if n == 0 or not prof.blocks[phase]:
            continue
        tally: Counter[str] = Counter()
        for b, times in prof.blocks[phase].items():
            for k in kinds(b):
                tally[k] += times
        yield phase, n, tally


def _print_rows(tally: Counter[str], n: int, top: int) -> None:
    total = sum(tally.values())
    for key, ins in tally.most_common(top):
        print(f"  {ins / n:8,.1f}  {100 * ins / total:5.1f} %  {key}")


def print_lines(prof: Profile, elf: Path, fn: str, top: int) -> None:
    """Per phase, the source lines of fn's executed instructions (the most instructions first)."""
    addrs = sorted({a for per in prof.blocks.values() for b in per for a in prof.insns.get(b, ())})
    where = source_lines(elf, addrs)
    for phase, n, per_line in _tallies(prof, lambda b: (where.get(a, "?") for a in prof.insns.get(b, ()))):
        print(f"{phase}: {fn}, {sum(per_line.values()) / n:,.0f} instructions per step, by source line")
        _print_rows(per_line, n, top)


def print_ops(prof: Profile, fn: str, top: int) -> None:
    """Per phase, fn's executed instructions by kind (op_kind; the most first) and its stack loads and stores."""
    for phase, n, mix in _tallies(prof, lambda b: prof.ops.get(b, ())):
        total = sum(mix.values())
        stack = sum(v for k, v in mix.items() if k.endswith("(stack)"))
        print(f"{phase}: {fn}, {total / n:,.0f} instructions per step by kind; the stack's loads and stores "
              f"{stack / n:,.0f} ({100 * stack / total:.1f} %)")
        _print_rows(mix, n, top)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("trace", type=Path)
    ap.add_argument("elf", type=Path)
    ap.add_argument("--top", type=int, default=12, help="functions listed per phase (default 12)")
    ap.add_argument("--lines", metavar="FUNCTION", help="also where FUNCTION's instructions go, by source line")
    ap.add_argument("--ops", metavar="FUNCTION", help="also FUNCTION's instruction mix (kinds of instructions)")
    args = ap.parse_args()
    if args.lines and args.ops and args.lines != args.ops:
        ap.error("--lines and --ops take the same function (one function's blocks are kept)")
    prof = profile(args.trace, Symbols(args.elf), args.lines or args.ops)
    per, steps = prof.per, prof.steps
    for phase in PHASES.values():
        n = steps.get(phase, 0)
        if n == 0:
            continue
        total = sum(per[phase].values())
        print(f"{phase}: {n} steps, {total / n:,.0f} instructions per step "
              "(per function: instructions per step, share, calls per step, instructions a call)")
        for fn, ins in per[phase].most_common(args.top):
            calls = prof.calls[phase][fn]
            each = f"{calls / n:8,.2f} calls  {ins / calls:6,.1f} a call" if calls else f"{'(entered mid-way)':>22}"
            print(f"  {ins / n:8,.0f}  {100 * ins / total:5.1f} %  {fn:<28} {each}")
        rest = total - sum(v for _, v in per[phase].most_common(args.top))
        if rest:
            print(f"  {rest / n:8,.0f}  {100 * rest / total:5.1f} %  (the other functions)")
    if args.lines:
        print_lines(prof, args.elf, args.lines, 2 * args.top)
    if args.ops:
        print_ops(prof, args.ops, 2 * args.top)


if __name__ == "__main__":
    main()
