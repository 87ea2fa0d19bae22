#!/usr/bin/env bash
# Benchmarks of the fdi library (prints numbers; not a test), for the table that ships (the generated ROMO table)
# and the kinematic table, both through one simulated drive as the ECU sees it (host_tools/bench/fw_bench_drive.py: cornering,
# fault-free, then a vx sensor offset that the ROMO table isolates at once, then a steering offset it cannot separate
# from the other front wheel's; fw/bench/bench_drive.h classifies the steps):
#   host:   instructions per fdi_diag_step with valgrind callgrind (build/bench, gcc -O3), fault-free steps, steps
#           inside an isolation episode with one class (or none) left and with several ("undecided": the exoneration
#           asks for sensitivities), sensitivities off and on
#   target: Cortex-M4F under qemu-system-arm -M mps2-an386 -icount shift=0 (SysTick counted, calibrated by a known
#           loop): the same per phase and the largest single step of the drive; arm-none-eabi-size of the libraries,
#           the ROMO target with and without its sensitivity code (-DFDI_GEN_SENSITIVITIES=0), sizeof(fdi_diag_t);
#           all of it at -O3 (CMake Release, the generated generators at -Os: cmake/FdiGenerated.cmake), with every
#           source at -O3 (FDI_GENERATED_FOR_SIZE=OFF, the ROMO table only), and, as firmware is often built, at -Os
#           (MinSizeRel); whether the host and the target compute the same bits at every step of the drive
#           (scripts/check_identity.sh); per function on the M4 (scripts/profile_m4.sh): instructions per step, calls
#           per step and instructions a call, for both tables; the const data of the hand-written kinematic table
# and the goals of issue 45 with PASS/MISS, for the robust diagnosis the ECU ships (fdi_diag_config_default: on-line
# estimators and adaptive thresholds): <= 25,000 instructions for the largest step on the M4 (ROMO table in the ECU's
# configuration, isolation included, under 2 % of a 168 MHz core at 100 Hz; with every sensitivity reported as
# information), sizeof(fdi_diag_t) <= 4 KB on the M4, <= 128 KB of text for the ROMO diagnosis as the ECU links it
# (libfdi.a + libfdi_romo.a; the generic core alone as information). (Issue 21's goals, 5,000 instructions and 32 KB,
# were those of the fixed-gate diagnosis, before estimators and adaptive thresholds; issue 45 replaced them.)
# Usage: scripts/bench_fw.sh
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
[ -x .venv/bin/python ] || bash scripts/bootstrap.sh
# this run's output becomes section bench_fw of docs/results.md: scripts/results_doc.py runs the script under it
[ -n "${FDI_RESULTS_SECTION:-}" ] || exec .venv/bin/python scripts/results_doc.py bench_fw --run \
  --display "bash scripts/bench_fw.sh" -- bash scripts/bench_fw.sh "$@"
goal_insn=25000
goal_ram=4096
goal_lib=131072

mkdir -p build/bench
drive="$top/build/bench/fdi_bench_drive.bin"
.venv/bin/python host_tools/bench/fw_bench_drive.py "$drive"

echo "== host (x86-64, gcc -O3): callgrind, instructions per fdi_diag_step"
cmake -S . -B build/bench -DCMAKE_BUILD_TYPE=Release -DFDI_BUILD_TESTS=OFF -DFDI_BUILD_BENCH=ON >/dev/null
cmake --build build/bench -j 2 >/dev/null
for table in 0 1; do
  for sens in 0 1; do
    out="$(mktemp)"
    line="$(valgrind --tool=callgrind --collect-atstart=no --toggle-collect='bench_step_*' --callgrind-out-file="$out" \
      build/bench/fw/bench/fdi_bench_host "$drive" "$table" "$sens" 2>&1 | grep -E "^steps")"
    ann="$(callgrind_annotate --inclusive=yes "$out" 2>/dev/null)"
    rm -f "$out"
    ir_of() { echo "$ann" | awk -v f="$1" '$0 ~ (":" f " ") {gsub(",", "", $1); print $1; exit}'; }
    n_free="$(echo "$line" | sed -E 's/.*fault-free ([0-9]+),.*/\1/')"
    n_epi="$(echo "$line" | sed -E 's/.*episode ([0-9]+),.*/\1/')"
    n_und="$(echo "$line" | sed -E 's/.*undecided ([0-9]+) steps.*/\1/')"
    ir_free="$(ir_of bench_step_fault_free)"
    ir_epi="$(ir_of bench_step_episode)"
    ir_und="$(ir_of bench_step_undecided)"
    name="$(echo "$line" | sed -E 's/^steps [0-9]+ ([^,]*),.*/\1/')"
    echo "x86-64: $name, sensitivities $([ "$sens" = 1 ] && echo on || echo off): fault-free" \
      "$(( ${ir_free:-0} / (n_free > 0 ? n_free : 1) )), episode $(( ${ir_epi:-0} / (n_epi > 0 ? n_epi : 1) )), undecided" \
      "$(( ${ir_und:-0} / (n_und > 0 ? n_und : 1) )) instructions/step ($n_free, $n_epi and $n_und steps)"
  done
done

echo "== target (Cortex-M4F, arm-none-eabi-gcc -O3, the generated generators -Os: FDI_GENERATED_FOR_SIZE=ON)"
# configure_m4 DIR CMAKE_ARGS...: a Cortex-M4F build tree (the toolchain file only on its first configuration).
configure_m4() {
  local dir="$1" toolchain=()
  shift
  [ -f "$dir/CMakeCache.txt" ] || toolchain=(-DCMAKE_TOOLCHAIN_FILE=cmake/arm-none-eabi-cortex-m4f.cmake)
  cmake -S . -B "$dir" "${toolchain[@]}" "$@" >/dev/null
}
# run_m4 DIR: the bare-metal bench of build tree DIR under qemu (its printed lines).
run_m4() {
  (cd build/bench && timeout 300 qemu-system-arm -M mps2-an386 -cpu cortex-m4 -icount shift=0 -nographic \
    -monitor none -serial none -semihosting-config enable=on,target=native -kernel "$top/$1/fw/bench/fdi_bench_m4.elf" \
    2>&1)
}
configure_m4 build/m4 -DCMAKE_BUILD_TYPE=Release
cmake --build build/m4 -j 2 >/dev/null
configure_m4 build/m4-nosens -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_FLAGS=-DFDI_GEN_SENSITIVITIES=0
cmake --build build/m4-nosens -j 2 --target fdi_romo >/dev/null
text_of() { arm-none-eabi-size -t "$1" | tail -1 | awk '{print $1}'; }
for lib in fw/libfdi.a fw/ecu/libfdi_ecu.a fw/vehicles/romo/libfdi_romo.a fw/vehicles/romo/libfdi_romo_can.a \
           fw/vehicles/three_tank/libfdi_three_tank.a; do
  arm-none-eabi-size -t "build/m4/$lib"
done
gens=fw/vehicles/romo/CMakeFiles/fdi_romo.dir/generated
romo_gen="$(text_of "build/m4/$gens/fdi_romo_generators.c.obj")"
romo_gen_nosens="$(text_of "build/m4-nosens/$gens/fdi_romo_generators.c.obj")"
romo_lib="$(text_of build/m4/fw/vehicles/romo/libfdi_romo.a)"
romo_lib_nosens="$(text_of build/m4-nosens/fw/vehicles/romo/libfdi_romo.a)"
lib_text="$(text_of build/m4/fw/libfdi.a)"
echo "m4 flash: libfdi.a (generic core) text $lib_text B; ROMO target libfdi_romo.a text $romo_lib B" \
  "($romo_lib_nosens B with -DFDI_GEN_SENSITIVITIES=0), of which the generated generators $romo_gen B ($romo_gen_nosens B)"
# const data (.rodata, strings included) of the hand-written kinematic table and generators (their headers cite this)
rodata_of() { arm-none-eabi-size -A "$1" | awk '$1 ~ /^\.rodata/ {s += $2} END {print s + 0}'; }
kin_objs=build/m4/fw/vehicles/romo/CMakeFiles/fdi_romo.dir/src
echo "m4 const data: the kinematic table (fdi_kin_table.c) $(rodata_of "$kin_objs/fdi_kin_table.c.obj") B, the" \
  "kinematic generators' six descriptors with their names (fdi_romo_kin.c) $(rodata_of "$kin_objs/fdi_romo_kin.c.obj") B"
arm-none-eabi-size build/m4/fw/bench/fdi_bench_m4.elf
m4_out="$(run_m4 build/m4)"
echo "$m4_out"
# the same bits on the host as on the target (its digests of every step's results; a gate of scripts/test_fw.sh)
bash scripts/check_identity.sh build/bench build/m4 || true

# The same bench with every source at -O3 (the generated generators too): what FDI_GENERATED_FOR_SIZE changes.
echo "== target (Cortex-M4F, arm-none-eabi-gcc -O3 for every source: FDI_GENERATED_FOR_SIZE=OFF)"
configure_m4 build/m4-o3 -DCMAKE_BUILD_TYPE=Release -DFDI_GENERATED_FOR_SIZE=OFF
cmake --build build/m4-o3 -j 2 --target fdi_bench_m4 >/dev/null
romo_gen_o3="$(text_of "build/m4-o3/$gens/fdi_romo_generators.c.obj")"
echo "m4 all -O3 flash: ROMO target libfdi_romo.a text $(text_of build/m4-o3/fw/vehicles/romo/libfdi_romo.a) B, of which" \
  "the generated generators $romo_gen_o3 B"
run_m4 build/m4-o3 | grep -E "ROMO table" | sed 's/^m4: /m4 all -O3: /'

# The same bench built for size (CMake MinSizeRel, -Os), as firmware is often built: its instruction counts and flash.
echo "== target (Cortex-M4F, arm-none-eabi-gcc -Os, CMake MinSizeRel)"
configure_m4 build/m4-os -DCMAKE_BUILD_TYPE=MinSizeRel
cmake --build build/m4-os -j 2 --target fdi_bench_m4 >/dev/null
lib_text_os="$(text_of build/m4-os/fw/libfdi.a)"
romo_lib_os="$(text_of build/m4-os/fw/vehicles/romo/libfdi_romo.a)"
echo "m4 -Os flash: libfdi.a (generic core) text $lib_text_os B; ROMO target libfdi_romo.a text $romo_lib_os B"
m4_os_out="$(run_m4 build/m4-os)"
echo "$m4_os_out" | sed 's/^m4: /m4 -Os: /'

# Per function: instructions per step, calls per step and instructions a call, from qemu's instruction trace of a
# profile build (-g) of the same bench (the headers' cost figures point here); the largest 20 per phase.
for table in romo kin; do
  bash scripts/profile_m4.sh "$table" off --top 20 | sed -n '/^== per phase/,$p'
done

echo "== goals (issue 45: the robust diagnosis, estimators and adaptive thresholds included)"
verdict() { if [ "$1" -le "$2" ]; then echo PASS; else echo MISS; fi; }
worst_of() { echo "$1" | awk -v k="generated ROMO table, sensitivities $2" \
  'index($0, k) {for (i = 1; i <= NF; ++i) if ($i == "worst") {print $(i + 1); exit}}'; }
worst="$(worst_of "$m4_out" off)"
worst_all="$(worst_of "$m4_out" on)"
worst_os="$(worst_of "$m4_os_out" off)"
ram="$(echo "$m4_out" | awk '/sizeof\(fdi_diag_t\)/ {print $3; exit}')"
# The ECU ships with fdi_diag_config_default (fw/ecu/src/fdi_ecu.c): sensitivities computed only where the on-line
# exoneration reads them, none reported; "sensitivities on" (every test's sensitivities at every step, for tools
# that log them) is information, not the shipped configuration.
echo "ROMO table, Cortex-M4F, largest step of the drive (the ECU's configuration, isolation included): ${worst:-?} <=" \
  "$goal_insn instructions: $(verdict "${worst:-999999}" "$goal_insn")"
echo "  (with every sensitivity reported at every step: ${worst_all:-?} instructions)"
echo "sizeof(fdi_diag_t) on Cortex-M4F: ${ram:-?} <= $goal_ram bytes: $(verdict "${ram:-999999}" "$goal_ram")"
# The goal was set on libfdi.a when it held the generated ROMO table too; the diagnosis the ECU links for ROMO is the
# generic core plus the vehicle target (its generated generators, with the sensitivity code the exoneration needs).
shipped=$((lib_text + romo_lib))
echo "ROMO diagnosis as the ECU links it (libfdi.a + libfdi_romo.a) text on Cortex-M4F: $shipped <= $goal_lib bytes:" \
  "$(verdict "$shipped" "$goal_lib")"
echo "  (libfdi.a, the generic core alone: $lib_text bytes: $(verdict "$lib_text" "$goal_lib"))"
shipped_os=$((lib_text_os + romo_lib_os))
echo "built with -Os (MinSizeRel): largest step ${worst_os:-?} <= $goal_insn instructions:" \
  "$(verdict "${worst_os:-999999}" "$goal_insn"); libfdi.a + libfdi_romo.a text $shipped_os <= $goal_lib bytes:" \
  "$(verdict "$shipped_os" "$goal_lib")"
