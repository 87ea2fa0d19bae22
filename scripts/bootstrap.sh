#!/usr/bin/env bash
# Set up everything the project needs on a fresh Debian machine: Debian packages (only the missing ones)
# and a Python venv under .venv with the project installed in editable mode (this builds the C extension), its
# dependencies at the versions of constraints.txt (the ones CI and the committed generated files are verified with).
# Safe to run again: it only does what is still missing (a changed pyproject.toml or constraints.txt reinstalls).
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$top"

debs=(build-essential cmake python3-venv libcmocka-dev cppcheck clang clang-tidy valgrind
      gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm iproute2
      qemu-system-x86 busybox-static)  # the last two: the SocketCAN/vcan guest of tests/vm
missing=()
for p in "${debs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "${#missing[@]}" -gt 0 ]; then
  echo "bootstrap: installing Debian packages: ${missing[*]}"
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${missing[@]}" >/dev/null
fi

py="${PYTHON:-python3}"
stamp=".venv/.installed-$(cat pyproject.toml constraints.txt $(ls setup.py 2>/dev/null) | sha1sum | cut -c1-12)"
if [ ! -x .venv/bin/python ]; then
  echo "bootstrap: creating .venv"
  "$py" -m venv .venv
fi
if [ ! -f "$stamp" ]; then
  echo "bootstrap: installing the project and its dev dependencies into .venv"
  .venv/bin/python -m pip install -q -c constraints.txt --upgrade pip setuptools wheel
  # without build isolation: the build uses the pinned setuptools and wheel just installed
  .venv/bin/python -m pip install -q -c constraints.txt --no-build-isolation -e ".[dev]"
  rm -f .venv/.installed-*
  touch "$stamp"
fi
