#!/usr/bin/env bash
# Boot the QEMU guest of tests/vm (prepare.sh first) with RESULTS_DIR as its writable /results share and the host
# root read-only at /host; the guest runs RESULTS_DIR/run.sh and powers off. No KVM needed (TCG), no network.
#   tests/vm/run_guest.sh RESULTS_DIR [TIMEOUT_SECONDS]      exit 0 when the guest powered off by itself
# The guest clock is virtual (-icount shift=0,sleep=off: 1 ns per instruction, idle time skipped), so the
# guest's timing does not depend on how slow TCG or a loaded host is; FDI_VM_ICOUNT="" runs on real time.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
results="$(cd "$1" && pwd)"
limit="${2:-120}"
cache="${FDI_VM_CACHE:-$top/.cache/vm}"
[ -f "$cache/vmlinuz" ] && [ -f "$cache/initrd.gz" ] || { echo "run_guest.sh: run tests/vm/prepare.sh first" >&2; exit 1; }
icount_opts="-icount shift=0,sleep=off"
[ -z "${FDI_VM_ICOUNT+set}" ] || icount_opts="$FDI_VM_ICOUNT"
# shellcheck disable=SC2086  # icount_opts is a list of options
exec timeout --kill-after=5 "$limit" qemu-system-x86_64 -accel tcg ${icount_opts} -m 512 -smp 1 -nographic -nic none -no-reboot \
  -kernel "$cache/vmlinuz" -initrd "$cache/initrd.gz" \
  -append "console=ttyS0 quiet loglevel=3 panic=-1" \
  -virtfs local,path=/,mount_tag=hostroot,security_model=none,readonly=on \
  -virtfs "local,path=$results,mount_tag=results,security_model=none"
