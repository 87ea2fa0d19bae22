#!/usr/bin/env bash
# Quality gates of the on-vehicle C library fw/ (see fw/README.md). Build dirs under build/ (gitignored):
#   1. host build (-Werror, all warnings) + cmocka unit tests through CTest         build/fw
#   2. ASan + UBSan (float-divide-by-zero, no recovery) build + CTest              build/fw-san
#   3. cross build for Cortex-M4F (library + bare-metal bench ELF)                  build/m4
#      and the same bits on both: the benchmark drive through the host build's bench and the M4 bench under qemu,
#      a digest of every step's results compared (scripts/check_identity.sh)
#   4. cppcheck --addon=misra over the generic core (fw/src, fw/include, fw/ecu) and the vehicle targets
#      (fw/vehicles/*: hand-written and generated code; zero findings, suppressions: fw/misra_suppressions.txt and
#      the cantools code's deviations by rule, fw/MISRA_DEVIATIONS.md)
#   5. clang-tidy over fw/src, fw/ecu/src and fw/vehicles/*/src with fw/.clang-tidy (warnings are errors)
#   6. libFuzzer harnesses (scripts/fuzz.sh, clang, ASan + UBSan) for FDI_FUZZ_SECONDS (default 20) each
#   (CTest in 1 and 2 includes the long runs of tests/fw/longrun, label "longrun"; CTest in 1 the C package:
#   install + find_package consumer, a consumer with mismatching capacities refused, subproject, CPack, label
#   "package", tests/fw/package_test.cmake)
# Exits non-zero on the first failing gate.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
jobs="${FDI_JOBS:-2}"

run_ctest() { # print CTest's summary lines; fail if any test fails
  local dir="$1" log
  log="$(mktemp)"
  if ! ctest --test-dir "$dir" -j "$jobs" --output-on-failure --output-junit ctest-junit.xml >"$log" 2>&1; then
    cat "$log"; rm -f "$log"; return 1
  fi
  grep -E "tests passed|tests failed|Total Test time|Skipped|Not Run" "$log" || true
  rm -f "$log"
}

echo "== fw: host build + unit tests"
cmake -S . -B build/fw -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_EXPORT_COMPILE_COMMANDS=ON -DFDI_BUILD_TESTS=ON \
  -DFDI_SANITIZE=OFF >/dev/null
cmake --build build/fw -j "$jobs" >/dev/null
run_ctest build/fw

echo "== fw: sanitizer build (ASan + UBSan) + unit tests"
cmake -S . -B build/fw-san -DCMAKE_BUILD_TYPE=Debug -DFDI_SANITIZE=ON -DFDI_BUILD_TESTS=ON -DFDI_BUILD_BENCH=OFF >/dev/null
cmake --build build/fw-san -j "$jobs" >/dev/null
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 run_ctest build/fw-san

echo "== fw: cross build for Cortex-M4F"
toolchain=()
[ -f build/m4/CMakeCache.txt ] || toolchain=(-DCMAKE_TOOLCHAIN_FILE=cmake/arm-none-eabi-cortex-m4f.cmake)
cmake -S . -B build/m4 "${toolchain[@]}" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build/m4 -j "$jobs" >/dev/null
for lib in fw/libfdi.a fw/ecu/libfdi_ecu.a fw/vehicles/romo/libfdi_romo.a fw/vehicles/romo/libfdi_romo_can.a \
           fw/vehicles/three_tank/libfdi_three_tank.a; do
  arm-none-eabi-size -t "build/m4/$lib" | tail -1 |
    awk -v n="$(basename "$lib")" '{print n " (cortex-m4f): text " $1 " B, data " $2 " B, bss " $3 " B"}'
done
bash scripts/check_identity.sh build/fw build/m4

echo "== fw: cppcheck --addon=misra"
# The misra addon's findings do not set cppcheck's exit code, so any output at all fails the gate.
# The cantools-generated frame code keeps its generator's style: rules 2.5, 10.4, 10.8, 15.5, 15.6, 17.7 are
# deviated for the cantools files (generated/can/*_can.[ch]) only (fw/MISRA_DEVIATIONS.md); the core, the ECU core,
# the generated tables, generators and buses have none but the compile-time assertions' Rule 2.3 (marked inline).
can_dev=()
for r in 2.5 10.4 10.8 15.5 15.6 17.7; do
  for f in romo_can.c romo_can.h; do can_dev+=("--suppress=misra-c2012-$r:*generated/can/$f"); done
done
vehicle_dirs=(fw/vehicles/romo/include fw/vehicles/romo/src fw/vehicles/romo/generated fw/vehicles/romo/generated/can
              fw/vehicles/three_tank/generated)
includes=(-I fw/include -I fw/src -I fw/ecu/include)
for d in "${vehicle_dirs[@]}"; do includes+=(-I "$d"); done
# The host tools' plugin glue (generated/plugin/: fdi_py_plugin.h, every vehicle's plugin defines the same symbols in
# a shared library of its own) runs on the host only and is not firmware: out of the gate.
findings="$(cppcheck --addon=misra --std=c99 --enable=warning,style,portability --inline-suppr --error-exitcode=1 -q \
  -i fw/vehicles/romo/generated/plugin -i fw/vehicles/three_tank/generated/plugin \
  --suppressions-list=fw/misra_suppressions.txt "${can_dev[@]}" "${includes[@]}" \
  fw/src fw/include fw/ecu/src fw/ecu/include "${vehicle_dirs[@]}" 2>&1)" ||
  { echo "$findings"; exit 1; }
if [ -n "$findings" ]; then echo "$findings"; echo "cppcheck: findings above"; exit 1; fi
echo "cppcheck: no findings"

echo "== fw: clang-tidy"
clang-tidy -p build/fw --quiet fw/src/*.c fw/ecu/src/*.c fw/vehicles/*/src/*.c 2>/dev/null
echo "clang-tidy: no findings"

echo "== fw: libFuzzer harnesses (tests/fuzz/, ${FDI_FUZZ_SECONDS:-20} s each; bash scripts/fuzz.sh for longer runs)"
FDI_RESULTS_DOC="" bash scripts/fuzz.sh "${FDI_FUZZ_SECONDS:-20}"  # a check, not a result: docs/results.md untouched

echo "== fw: all gates passed"
