#!/usr/bin/env bash
# Prepare the QEMU guest of the SocketCAN test (tests/host/test_vcan_qemu.py) in a cache outside git:
#   .cache/vm/vmlinuz       Debian's linux-image-*-amd64 kernel (apt-get download + dpkg -x, no install)
#   .cache/vm/initrd.gz     busybox (static) + tests/vm/init + the kernel modules for virtio 9p and CAN/vcan
# Idempotent: does nothing when both exist for the current init script. Needs apt-get, dpkg, gzip, busybox
# (busybox-static); prints the cache directory on success.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cache="${FDI_VM_CACHE:-$top/.cache/vm}"
mkdir -p "$cache"
cd "$cache"

stamp="initrd-$(sha1sum "$top/tests/vm/init" | cut -c1-12)"
if [ -f vmlinuz ] && [ -f initrd.gz ] && [ -f "$stamp" ]; then echo "$cache"; exit 0; fi

busybox_bin="$(command -v busybox || echo /bin/busybox)"
# ldd exits 1 on a static binary; read its text first (under pipefail a pipe would fail on that status)
ldd_text="$(LC_ALL=C ldd "$busybox_bin" 2>&1 || true)"
if [ ! -x "$busybox_bin" ] || [[ "$ldd_text" != *"not a dynamic executable"* ]]; then
  echo "prepare.sh: no static busybox (apt-get install busybox-static)" >&2; exit 1
fi

# 1. the kernel package (the version linux-image-amd64 points to)
if [ ! -d kernel/boot ]; then
  kernel_pkg() { apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-[0-9]/ {print $2; exit}'; }
  pkg="$(kernel_pkg)"
  if [ -z "$pkg" ] && [ "$(id -u)" -eq 0 ]; then apt-get update -qq >/dev/null 2>&1 || true; pkg="$(kernel_pkg)"; fi
  [ -n "$pkg" ] || { echo "prepare.sh: apt-cache knows no linux-image-amd64 (apt-get update?)" >&2; exit 1; }
  rm -f linux-image-*.deb
  apt-get download -q "$pkg" >/dev/null
  rm -rf kernel
  dpkg -x linux-image-*.deb kernel
  rm -f linux-image-*.deb
fi
cp kernel/boot/vmlinuz-* vmlinuz
moddir="$(ls -d kernel/lib/modules/*)"

# 2. the modules with their dependencies (the "depends=" field of each .ko's modinfo), dependencies first
declare -A path_of=() done_mod=()
while IFS= read -r ko; do
  name="$(basename "$ko" .ko)"; path_of["${name//-/_}"]="$ko"
done < <(find "$moddir" -name '*.ko')
order=()
add_mod() {
  local m="${1//-/_}" dep
  [ -n "${done_mod[$m]:-}" ] && return 0
  [ -n "${path_of[$m]:-}" ] || { echo "prepare.sh: module $m not found" >&2; exit 1; }
  done_mod[$m]=1
  for dep in $(tr '\0' '\n' < "${path_of[$m]}" | sed -n 's/^depends=//p' | tr ',' ' '); do add_mod "$dep"; done
  order+=("$m")
}
for m in virtio virtio_ring virtio_pci netfs 9pnet 9pnet_virtio 9p can can_raw can_dev vcan; do add_mod "$m"; done

# 3. the initramfs
root="$(mktemp -d)"
trap 'rm -rf "$root"' EXIT
mkdir -p "$root"/{bin,sbin,proc,sys,dev,host,results,tmp,modules}
cp "$busybox_bin" "$root/bin/busybox"
for app in sh mount umount insmod ip sleep kill cat echo poweroff ls mkdir sync wait dmesg date; do
  ln -sf busybox "$root/bin/$app"
done
: > "$root/modules/order"
for m in "${order[@]}"; do
  cp "${path_of[$m]}" "$root/modules/$m.ko"
  echo "$m" >> "$root/modules/order"
done
cp "$top/tests/vm/init" "$root/init"
chmod +x "$root/init"
cpio_cmd=(cpio -o -H newc --quiet)
command -v cpio >/dev/null || cpio_cmd=("$busybox_bin" cpio -o -H newc)
(cd "$root" && find . | "${cpio_cmd[@]}" 2>/dev/null) | gzip -1 > initrd.gz.tmp
mv initrd.gz.tmp initrd.gz
rm -f initrd-*
touch "$stamp"
echo "$cache"
