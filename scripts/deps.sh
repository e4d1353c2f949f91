#!/usr/bin/env bash
# Installs what Lissom needs on Debian 12 (run as root), idempotently:
#   apt packages (compilers, clang-14 and its libFuzzer/sanitizer runtimes for scripts/fuzz.sh, cmocka, the Arm cross toolchain, QEMU, CAN and GPIO tools) and the Python venv
#   in .venv with hil/requirements.txt and the lissom_hil package. Fast when everything is already there.
set -euo pipefail
cd "$(dirname "$0")/.."

PKGS=(gcc make cmake ninja-build pkg-config git libcmocka-dev
      python3 python3-venv python3-dev
      gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm
      libgpiod-dev gpiod can-utils iproute2
      qemu-system-x86 busybox-static xz-utils gcc-12
      clang-format clang-tidy clang-14 libclang-rt-14-dev)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[deps] apt install: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -q >/dev/null
  apt-get install -y -q --no-install-recommends "${missing[@]}" >/dev/null
fi

PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3
stamp=.venv/.lissom-requirements
want=$({ cat hil/requirements.txt; if [ -f hil/pyproject.toml ]; then cat hil/pyproject.toml; fi; } | sha256sum | cut -d' ' -f1)
if [ ! -x .venv/bin/python ] || [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  echo "[deps] python venv (.venv)"
  [ -x .venv/bin/python ] || "$PY" -m venv .venv
  .venv/bin/pip install -q --upgrade pip
  .venv/bin/pip install -q -r hil/requirements.txt
  if [ -f hil/pyproject.toml ]; then .venv/bin/pip install -q -e hil; fi
  echo "$want" > "$stamp"
fi
echo "[deps] ok"
