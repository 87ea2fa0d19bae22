#!/usr/bin/env bash
# Where the instructions of fdi_diag_step go on the Cortex-M4F: per phase of the benchmark drive (scripts/bench_fw.sh's:
# warm-up, fault-free, an episode with one class left, an undecided one) and per function, from qemu's instruction
# trace of a profile build of the bare-metal bench (fw/bench/m4/bench_m4.c with -DBENCH_PROFILE, -g) analysed by
# fw/bench/m4/profile.py. Prints numbers; not a test. The trace (~300 MB) is deleted afterwards.
# Usage: scripts/profile_m4.sh [romo|kin] [off|on] [--lines FUNCTION] [--ops FUNCTION] [--top N]
#   (default: the generated ROMO table as the ECU runs it: off; --lines also prints where FUNCTION's instructions go
#   by source line, the code the compiler inlined into it included; --ops its instruction mix: mnemonics, and loads
#   and stores by what they address, the stack's being spilled values)
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
[ -x .venv/bin/python ] || bash scripts/bootstrap.sh
table="${1:-romo}"
sens="${2:-off}"
shift $(( $# < 2 ? $# : 2 ))
case "$table" in kin) k=0 ;; romo) k=2 ;; *) echo "table: romo or kin" >&2; exit 2 ;; esac
case "$sens" in off) ;; on) k=$((k + 1)) ;; *) echo "sensitivities: off or on" >&2; exit 2 ;; esac
drive="$top/build/bench/fdi_bench_drive.bin"
mkdir -p build/bench build/m4-prof
.venv/bin/python host_tools/bench/fw_bench_drive.py "$drive"
flags="-mcpu=cortex-m4 -mfpu=fpv4-sp-d16 -mfloat-abi=hard -mthumb -g -DBENCH_PROFILE -DBENCH_ONLY=${k}U"
cmake -S . -B build/m4-prof -DCMAKE_TOOLCHAIN_FILE=cmake/arm-none-eabi-cortex-m4f.cmake -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_C_FLAGS="$flags" >/dev/null
cmake --build build/m4-prof -j 2 --target fdi_bench_m4 >/dev/null
elf="$top/build/m4-prof/fw/bench/fdi_bench_m4.elf"
trace="$top/build/m4-prof/trace.log"
(cd build/bench && timeout 900 qemu-system-arm -M mps2-an386 -cpu cortex-m4 -icount shift=0 -nographic -monitor none \
  -serial none -semihosting-config enable=on,target=native -kernel "$elf" -d in_asm,exec,nochain -D "$trace")
echo "== per phase and function (Cortex-M4F instructions per fdi_diag_step, $table table, sensitivities $sens)"
.venv/bin/python fw/bench/m4/profile.py "$trace" "$elf" "$@"
rm -f "$trace"
