#!/usr/bin/env bash
# Builds $LISSOM_VM_DIR/initrd.img: a static busybox, hil/vm/guest_init.sh as /init, and the kernel modules
# the guest needs before it can see the host's files (virtio-pci, 9p, overlay) plus CAN (can, can-raw,
# can-bcm for python-can's periodic SYNC, vcan), configfs and gpio-sim (if it was built).
# Needs busybox-static, python3 and the kernel unpacked by setup_vm.sh.
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
TOP=${LISSOM_VM_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/lissom-vm}
KDIR=$TOP/kernel
KVER=$(ls "$KDIR/lib/modules" | head -n1)
MODDIR=$KDIR/lib/modules/$KVER
[ -f "$MODDIR/modules.dep" ] || busybox depmod -b "$KDIR" "$KVER"

W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
mkdir -p "$W"/bin "$W"/proc "$W"/sys "$W"/dev "$W"/host "$W"/tmp "$W"/lib/modules
cp /bin/busybox "$W/bin/busybox"
: > "$W/modules.list"
WANT=(virtio_pci 9pnet_virtio 9p overlay can can_raw can_bcm vcan configfs)
[ -f "$MODDIR/extra/gpio-sim.ko" ] && WANT+=(gpio_sim)
for m in $(python3 "$HERE/modorder.py" "$MODDIR" "${WANT[@]}"); do
  cp "$MODDIR/$m" "$W/lib/modules/"
  basename "$m" >> "$W/modules.list"
done
install -m 755 "$HERE/guest_init.sh" "$W/init"
(cd "$W" && find . | busybox cpio -o -H newc 2>/dev/null | gzip -1 > "$TOP/initrd.img")
ls -l "$TOP/initrd.img"
