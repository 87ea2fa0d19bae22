#!/usr/bin/env bash
# libFuzzer harnesses of the C library (tests/fuzz/), built with clang -fsanitize=fuzzer,address,undefined.
#   bash scripts/fuzz.sh [seconds]        run each harness for `seconds` (default 30); CI uses 20
#   FUZZ_RUNS=10000000 bash scripts/fuzz.sh   run each harness for that many executions instead
#   FUZZ_ONLY="diag ecu"   run only these harnesses;  FUZZ_MAX_LEN=1024   longest input (default 4096 bytes)
# Harnesses: fuzz_iso (table check + isolation), fuzz_diag (diagnoser step path), and fuzz_ecu (CAN frame
# ingestion + step through fw/ecu on the ROMO bus); the generic core with the ROMO target (fw/vehicles/romo).
# The corpus persists in build/fuzz/corpus_<name>.
# Prints the executions per harness; exits non-zero on any crash, invariant violation or sanitizer report
# (the reproducer is left in build/fuzz/crash-*).
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
# this run's output becomes section fuzz of docs/results.md (FDI_RESULTS_DOC= for a trial run, as CI does):
# scripts/results_doc.py (standard library only) runs the script under it
[ -n "${FDI_RESULTS_SECTION:-}" ] || exec python3 scripts/results_doc.py fuzz --run \
  --display "$(printf '%s' "${FUZZ_RUNS:+FUZZ_RUNS=$FUZZ_RUNS }${FUZZ_ONLY:+FUZZ_ONLY=\"$FUZZ_ONLY\" }")bash scripts/fuzz.sh $*" \
  -- bash scripts/fuzz.sh "$@"
seconds="${1:-30}"
out=build/fuzz
mkdir -p "$out"
cc="${FUZZ_CC:-clang}"
romo=fw/vehicles/romo
flags=(-g -O2 -std=c99 -Wall -Wextra -Werror -fsanitize=fuzzer,address,undefined,float-divide-by-zero
       -fno-sanitize-recover=all -fno-omit-frame-pointer -Ifw/include -Ifw/src -I"$romo/include" -I"$romo/generated"
       -Itests/fw -Itests/fuzz)
lib=(fw/src/*.c "$romo"/src/fdi_romo_kin.c "$romo"/src/fdi_kin_table.c "$romo"/generated/*.c)

harnesses=(iso diag)
build() { # name, extra sources...
  local name="$1"; shift
  "$cc" "${flags[@]}" "$@" "${lib[@]}" "tests/fuzz/fuzz_${name}.c" -lm -o "$out/fuzz_${name}"
}
pids=()
build iso & pids+=($!)
build diag & pids+=($!)
build ecu -Ifw/ecu/include -I"$romo/generated/can" fw/ecu/src/fdi_ecu.c "$romo"/src/fdi_romo_ecu.c \
  "$romo"/generated/can/*.c & pids+=($!)
harnesses+=(ecu)
for p in "${pids[@]}"; do wait "$p"; done  # set -e: a failed build stops the script

limit=(-max_total_time="$seconds")
[ -n "${FUZZ_RUNS:-}" ] && limit=(-runs="$FUZZ_RUNS")
status=0
[ -n "${FUZZ_ONLY:-}" ] && read -r -a harnesses <<<"$FUZZ_ONLY"
for h in "${harnesses[@]}"; do
  mkdir -p "$out/corpus_$h"
  log="$out/fuzz_$h.log"
  if (cd "$out" && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
      "./fuzz_$h" "${limit[@]}" -max_len="${FUZZ_MAX_LEN:-4096}" -timeout=10 -rss_limit_mb=1024 -print_final_stats=1 \
      -artifact_prefix="./crash-$h-" "corpus_$h") >"$log" 2>&1; then
    runs="$(grep -m1 'stat::number_of_executed_units' "$log" | awk '{print $2}')"
    rate="$(grep -m1 'stat::average_exec_per_sec' "$log" | awk '{print $2}')"
    echo "fuzz_$h: ${runs} executions (${rate}/s), 0 crashes, 0 sanitizer reports"
  else
    echo "fuzz_$h: FAILED, see $log:"; grep -E "ERROR|invariant|runtime error|SUMMARY|Test unit written" "$log" | head -20
    status=1
  fi
done
exit "$status"
