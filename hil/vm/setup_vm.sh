#!/usr/bin/env bash
# Prepares the QEMU guest that gives the HIL tests a real vcan0 (and gpio-sim) on a host whose own kernel
# has no CAN support. Debian 12, run as root. Idempotent: a second run only checks a stamp (well under 1 s).
#
# What it puts in $LISSOM_VM_DIR (default ${XDG_CACHE_HOME:-~/.cache}/lissom-vm):
#   debs/         the kernel package (the headers and kernel source packages used for gpio-sim are deleted
#                 after the build)
#   kernel/       linux-image-amd64 unpacked with dpkg -x (NOT installed as the host's kernel)
#   vmlinux       the uncompressed kernel (boots ~2x faster than vmlinuz under TCG: no emulated decompressor)
#   gpiosim/      gpio-sim.ko built out of tree (Debian's kernel config lacks CONFIG_GPIO_SIM)
#   initrd.img    busybox + the modules for virtio-9p, overlayfs, CAN, vcan, configfs, gpio-sim
#   ready         stamp: kernel version + hash of the files in hil/vm
# Host packages it installs if missing (apt, --no-install-recommends):
#   qemu-system-x86 busybox-static can-utils gpiod iproute2 python3 xz-utils, and gcc-12 make for gpio-sim.
# usage: hil/vm/setup_vm.sh [--force]      env: LISSOM_VM_DIR, LISSOM_VM_GPIO_SIM=0 to skip gpio-sim
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
TOP=${LISSOM_VM_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/lissom-vm}
WITH_GPIO_SIM=${LISSOM_VM_GPIO_SIM:-1}
FORCE=0; [ "${1:-}" = "--force" ] && FORCE=1
t0=$SECONDS
say() { echo "[lissom-vm +$((SECONDS - t0))s] $*"; }

want=$(cat "$HERE"/setup_vm.sh "$HERE"/build_initramfs.sh "$HERE"/guest_init.sh "$HERE"/modorder.py \
         "$HERE"/extract_vmlinux.py | sha256sum | cut -c1-16)-gpiosim$WITH_GPIO_SIM
if [ $FORCE = 0 ] && [ -f "$TOP/ready" ] && [ "$(cut -d' ' -f2 "$TOP/ready")" = "$want" ] \
   && [ -f "$TOP/vmlinux" ] && [ -f "$TOP/initrd.img" ]; then
  exit 0
fi

export DEBIAN_FRONTEND=noninteractive
APT=(apt-get -y -q -o APT::Sandbox::User=root)
PKGS=(qemu-system-x86 busybox-static can-utils gpiod iproute2 python3 xz-utils)
[ "$WITH_GPIO_SIM" = 1 ] && PKGS+=(gcc-12 make)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
updated=0
if [ ${#missing[@]} -gt 0 ]; then
  say "apt install ${missing[*]}"
  "${APT[@]}" update >/dev/null; updated=1
  "${APT[@]}" install --no-install-recommends "${missing[@]}" >/dev/null
fi

mkdir -p "$TOP/debs"
cd "$TOP/debs"
IMG=$(apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-/{print $2; exit}')
if [ -z "$IMG" ] && [ $updated = 0 ]; then
  "${APT[@]}" update >/dev/null; updated=1
  IMG=$(apt-cache depends linux-image-amd64 | awk '/Depends: linux-image-/{print $2; exit}')
fi
[ -n "$IMG" ] || { echo "setup_vm: cannot resolve linux-image-amd64 (apt sources?)" >&2; exit 1; }
KVER=${IMG#linux-image-}                                          # e.g. 6.1.0-56-amd64
VER=$(apt-cache policy "$IMG" | awk '/Candidate:/{print $2}')      # e.g. 6.1.192-2
say "kernel $IMG $VER"
ls "${IMG}"_*.deb >/dev/null 2>&1 || "${APT[@]}" download "$IMG" >/dev/null 2>&1
rm -rf "$TOP/kernel"
dpkg -x "${IMG}"_*.deb "$TOP/kernel"
busybox depmod -b "$TOP/kernel" "$KVER"
python3 "$HERE/extract_vmlinux.py" "$TOP/kernel/boot/vmlinuz-$KVER" "$TOP/vmlinux"

rm -f "$TOP/gpiosim/gpio-sim.ko"
if [ "$WITH_GPIO_SIM" = 1 ]; then
  # gpio-sim.c (+ irq_sim.c, which 6.1 does not export to modules) from the matching source package,
  # built against the matching headers package.
  HDR=linux-headers-$KVER
  HDEPS=$(apt-cache depends "$HDR" | awk '/Depends: linux-(headers|kbuild)-/{print $2}')
  SRC=linux-source-$(echo "$KVER" | cut -d. -f1,2)                # linux-source-6.1
  say "gpio-sim: fetch $HDR $HDEPS $SRC=$VER"
  for p in "$HDR" $HDEPS; do ls "${p}"_*.deb >/dev/null 2>&1 || "${APT[@]}" download "$p" >/dev/null 2>&1; done
  ls "${SRC}"_*.deb >/dev/null 2>&1 || "${APT[@]}" download "$SRC=$VER" >/dev/null 2>&1
  rm -rf "$TOP/kh" "$TOP/gpiosim"; mkdir -p "$TOP/kh" "$TOP/gpiosim"
  for p in "$HDR" $HDEPS; do dpkg -x "${p}"_*.deb "$TOP/kh"; done
  KH=$TOP/kh/usr/src/$HDR
  sed -i "s|^include /usr/src/|include $TOP/kh/usr/src/|" "$KH/Makefile"
  say "gpio-sim: unpack 3 source files"
  dpkg-deb --fsys-tarfile "${SRC}"_*.deb | tar -xO "./usr/src/$SRC.tar.xz" |
    tar -xJ -C "$TOP/gpiosim" --strip-components=3 \
      "$SRC/drivers/gpio/gpio-sim.c" "$SRC/drivers/gpio/gpiolib.h" "$SRC/kernel/irq/irq_sim.c"
  mv "$TOP/gpiosim/gpio-sim.c" "$TOP/gpiosim/gpio_sim_main.c"
  # irq_to_desc() is not exported in 6.1: dispatch the simulated interrupt through the exported helper
  sed -i 's/handle_simple_irq(irq_to_desc(irqnum));/generic_handle_irq(irqnum);/' "$TOP/gpiosim/irq_sim.c"
  grep -q 'generic_handle_irq(irqnum)' "$TOP/gpiosim/irq_sim.c" || { echo "setup_vm: irq_sim.c patch failed" >&2; exit 1; }
  printf 'obj-m := gpio-sim.o\ngpio-sim-y := gpio_sim_main.o irq_sim.o\n' > "$TOP/gpiosim/Makefile"
  say "gpio-sim: build"
  make -s -C "$KH" M="$TOP/gpiosim" CC=gcc-12 modules >/dev/null
  mkdir -p "$TOP/kernel/lib/modules/$KVER/extra"
  cp "$TOP/gpiosim/gpio-sim.ko" "$TOP/kernel/lib/modules/$KVER/extra/"
  busybox depmod -b "$TOP/kernel" "$KVER"
  rm -rf "$TOP/kh"                                          # 100+ MB, only needed for the build
  rm -f "$TOP/debs/${SRC}"_*.deb "$TOP/debs/${HDR}"_*.deb     # 150 MB; downloaded again only by --force
  for p in $HDEPS; do rm -f "$TOP/debs/${p}"_*.deb; done
fi

say "initramfs"
LISSOM_VM_DIR=$TOP "$HERE/build_initramfs.sh" >/dev/null
echo "$KVER $want" > "$TOP/ready"
say "ready in $TOP ($(du -sh "$TOP" | cut -f1))"
