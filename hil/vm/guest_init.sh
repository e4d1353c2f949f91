#!/bin/busybox sh
# /init of the HIL guest (PID 1, from the initramfs built by build_initramfs.sh).
#  1. loads the modules listed in /modules.list (virtio, 9p, overlay, CAN, vcan, configfs, gpio-sim)
#  2. mounts the host's / (9p tag "hostroot", read-only) under a tmpfs overlay: a writable root that looks
#     like the host, so the host's build tree and venv run unchanged
#  3. mounts the host directories named by lsm.rw=D1,D2,... (9p tags rw0, rw1, ...) read-write at the same paths
#  4. runs lsm.run=DIR/cmd.sh in a chroot of that root (cwd lsm.cwd), stores its exit code in DIR/rc,
#     prints LSM_VM_EXIT=N and powers off. Without lsm.run: an interactive shell.
/bin/busybox --install -s /bin
export PATH=/bin
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
while read -r m; do
  insmod "/lib/modules/$m" 2>/dev/null || echo "lsm-init: insmod $m failed"
done < /modules.list

RW=; RUN=; CWD=/; MODS=
for arg in $(cat /proc/cmdline); do
  case "$arg" in
    lsm.rw=*) RW=${arg#lsm.rw=} ;;
    lsm.run=*) RUN=${arg#lsm.run=} ;;
    lsm.cwd=*) CWD=${arg#lsm.cwd=} ;;
    lsm.mods=*) MODS=${arg#lsm.mods=} ;;
  esac
done
halt_now() { sync; poweroff -f; sleep 5; echo o > /proc/sysrq-trigger; }
fail() { echo "lsm-init: $*"; echo "LSM_VM_EXIT=255"; halt_now; }

O="trans=virtio,version=9p2000.L,msize=512000"
mount -t 9p -o "$O,ro,cache=loose" hostroot /host || fail "cannot mount the host root"
mount -t tmpfs -o size=75% tmpfs /tmp
mkdir -p /tmp/up /tmp/work /tmp/root
R=/tmp/root
if ! mount -t overlay overlay -o lowerdir=/host,upperdir=/tmp/up,workdir=/tmp/work $R 2>/dev/null; then
  echo "lsm-init: no overlay; read-only host root with tmpfs on /tmp /run /var/tmp"
  R=/host
  for d in /tmp /run /var/tmp; do mount -t tmpfs tmpfs $R$d; done
fi
i=0
for d in $(echo "$RW" | tr , ' '); do
  mkdir -p "$R$d" 2>/dev/null
  mount -t 9p -o "$O" "rw$i" "$R$d" || fail "cannot mount rw$i on $d"
  i=$((i + 1))
done
mount -t proc proc $R/proc
mount -t sysfs sysfs $R/sys
mount -t devtmpfs devtmpfs $R/dev
mkdir -p $R/dev/pts $R/dev/shm
mount -t devpts devpts $R/dev/pts
mount -t tmpfs tmpfs $R/dev/shm
mount -t configfs configfs $R/sys/kernel/config 2>/dev/null
# the guest kernel's modules (for `busybox modprobe` inside the guest)
if [ -n "$MODS" ] && [ -d "$R$MODS" ] && mkdir -p $R/lib/modules 2>/dev/null; then
  mount --bind "$R$MODS" $R/lib/modules
fi
ip link set lo up
hostname lissom-hil

export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin HOME=/root TERM=dumb
if [ -n "$RUN" ]; then
  chroot $R /bin/sh -c "cd '$CWD' && exec '$RUN/cmd.sh'" < /dev/null > /dev/console 2>&1
  rc=$?
  echo $rc > "$R$RUN/rc"
  echo "LSM_VM_EXIT=$rc"
else
  setsid cttyhack chroot $R /bin/bash -l
fi
halt_now
