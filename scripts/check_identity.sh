#!/usr/bin/env bash
# Host and target compute the same bits: the benchmark drive of fw/bench/bench_drive.h (host_tools/bench/
# fw_bench_drive.py) through the host build's fdi_bench_host and the Cortex-M4F build's bare-metal bench under qemu,
# for the kinematic and the generated ROMO table, sensitivities off and on. Each prints a digest of every step's
# result (masks, candidates, every residual, test ratio and sensitivity, bit for bit); the script prints them side by
# side and fails when one pair differs. A gate of scripts/test_fw.sh, and a line of scripts/bench_fw.sh.
# Usage: scripts/check_identity.sh HOST_BUILD_DIR M4_BUILD_DIR (both built, fdi_bench_host and fdi_bench_m4 in them)
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"
host_dir="${1:?host build dir}"
m4_dir="${2:?Cortex-M4F build dir}"
mkdir -p build/bench
drive="$top/build/bench/fdi_bench_drive.bin"
[ -f "$drive" ] || .venv/bin/python host_tools/bench/fw_bench_drive.py "$drive" >/dev/null
m4_out="$(cd build/bench && timeout 300 qemu-system-arm -M mps2-an386 -cpu cortex-m4 -icount shift=0 -nographic \
  -monitor none -serial none -semihosting-config enable=on,target=native \
  -kernel "$top/$m4_dir/fw/bench/fdi_bench_m4.elf" 2>&1)"
digest_of() { sed -nE 's/.*results digest ([0-9a-f]{8}).*/\1/p'; }
fail=0
for table in 0 1; do
  for sens in 0 1; do
    name="$([ "$table" = 0 ] && echo "kinematic table" || echo "generated ROMO table")"
    onoff="$([ "$sens" = 1 ] && echo on || echo off)"
    host="$("$host_dir/fw/bench/fdi_bench_host" "$drive" "$table" "$sens" | digest_of)"
    m4="$(echo "$m4_out" | grep -F "m4: $name, sensitivities $onoff:" | digest_of)"
    if [ -n "$host" ] && [ "$host" = "$m4" ]; then verdict="same"; else verdict="DIFFERENT"; fail=1; fi
    echo "identity: $name, sensitivities $onoff: x86-64 ${host:-none}, Cortex-M4F ${m4:-none}: $verdict"
  done
done
exit "$fail"
