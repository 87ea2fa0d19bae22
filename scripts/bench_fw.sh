#!/usr/bin/env bash
# Benchmarks of the fdi library (prints numbers; not a test). Uses the builds of scripts/test_fw.sh layout:
#   host:   instructions per fdi_diag_step with valgrind callgrind (build/bench, Release, N steps), for the
#           kinematic table (4 hand-written tests) and the generated ROMO table (fw/vehicles/romo), sensitivities off
#   target: arm-none-eabi-size of the libraries for Cortex-M4F and instructions per fdi_diag_step of both tables
#           under qemu-system-arm -M mps2-an386 -icount shift=0 (SysTick counted, calibrated by a known loop)
# Usage: scripts/bench_fw.sh [N]   (N host steps, default 10000; the first 320 are warm-up steps)
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
n="${1:-10000}"

echo "== host (x86-64, gcc -O3): callgrind"
cmake -S . -B build/bench -DCMAKE_BUILD_TYPE=Release -DFDI_BUILD_TESTS=OFF -DFDI_BUILD_BENCH=ON >/dev/null
cmake --build build/bench -j 2 >/dev/null
for table in 0 1; do
  out="$(mktemp)"
  line="$(valgrind --tool=callgrind --toggle-collect=fdi_diag_step --callgrind-out-file="$out" \
    build/bench/fw/bench/fdi_bench_host "$n" "$table" 2>&1 | grep -E "^steps")" || true
  echo "$line"
  ir="$(callgrind_annotate "$out" 2>/dev/null | awk '/PROGRAM TOTALS/ {gsub(",", "", $1); print $1; exit}')"
  rm -f "$out"
  name="$(echo "$line" | sed -E 's/^steps [0-9]+ ([^:]*):.*/\1/')"
  echo "fdi_diag_step: $ir instructions in $n steps = $((ir / n)) instructions/step ($name)"
done

echo "== target (Cortex-M4F, arm-none-eabi-gcc -O3)"
toolchain=()
[ -f build/m4/CMakeCache.txt ] || toolchain=(-DCMAKE_TOOLCHAIN_FILE=cmake/arm-none-eabi-cortex-m4f.cmake)
cmake -S . -B build/m4 "${toolchain[@]}" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build/m4 -j 2 >/dev/null
for lib in fw/libfdi.a fw/ecu/libfdi_ecu.a fw/vehicles/romo/libfdi_romo.a fw/vehicles/romo/libfdi_romo_can.a \
           fw/vehicles/three_tank/libfdi_three_tank.a; do
  arm-none-eabi-size -t "build/m4/$lib"
done
arm-none-eabi-size build/m4/fw/bench/fdi_bench_m4.elf
timeout 120 qemu-system-arm -M mps2-an386 -cpu cortex-m4 -icount shift=0 -nographic -monitor none -serial none \
  -semihosting-config enable=on,target=native -kernel build/m4/fw/bench/fdi_bench_m4.elf
