#!/usr/bin/env bash
# Runs one command in a fresh QEMU guest (Debian's kernel: vcan, can-raw, can-bcm, gpio-sim) and returns its
# exit code. The guest sees the host's / read-only under a tmpfs overlay (writes vanish at power-off) and
# the directories given with -r read-write at the same paths.
#
# usage: hil/vm/vm_run.sh [-r DIR]... [-C CWD] [-e NAME=VALUE]... [-i] -- CMD [ARG...]
#   -r DIR         share DIR read-write (repeatable)       -C CWD   working directory of CMD (default $PWD)
#   -e NAME=VALUE  environment for CMD (repeatable)         -i       interactive shell instead of CMD
# env: LISSOM_VM_DIR (from setup_vm.sh), LSM_VM_ACCEL=tcg|kvm (default tcg), LSM_VM_MEM (MiB, 1024),
#      LSM_VM_SMP (vCPUs, default 1), LSM_VM_TIMEOUT (s, 900)
# The guest console (CMD's stdout and stderr) goes to stdout. Exit code: CMD's, or 255 if the guest did not
# report one (boot failure, timeout).
set -uo pipefail
TOP=${LISSOM_VM_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/lissom-vm}
KERNEL=$TOP/vmlinux
INITRD=$TOP/initrd.img
[ -f "$KERNEL" ] && [ -f "$INITRD" ] || { echo "vm_run: run hil/vm/setup_vm.sh first ($TOP)" >&2; exit 255; }
RW=(); CWD=$PWD; INTER=0; ENVS=()
while [ $# -gt 0 ]; do
  case "$1" in
    -r) RW+=("$(realpath "$2")"); shift 2 ;;
    -C) CWD=$(realpath "$2"); shift 2 ;;
    -e) ENVS+=("$2"); shift 2 ;;
    -i) INTER=1; shift ;;
    --) shift; break ;;
    *) break ;;
  esac
done
mkdir -p "$TOP/runs"
RUNDIR=$(mktemp -d "$TOP/runs/run.XXXXXX")
trap 'rm -rf "$RUNDIR"' EXIT
{
  echo '#!/bin/bash'
  for e in "${ENVS[@]}"; do printf 'export %q\n' "$e"; done
  printf '%q ' "$@"; echo
} > "$RUNDIR/cmd.sh"
chmod +x "$RUNDIR/cmd.sh"
RW=("$TOP/runs" "${RW[@]}")

DEVS=(-fsdev local,id=hostroot,path=/,security_model=none,readonly=on,multidevs=remap
      -device virtio-9p-pci,fsdev=hostroot,mount_tag=hostroot)
LIST=
for i in "${!RW[@]}"; do
  DEVS+=(-fsdev "local,id=rw$i,path=${RW[$i]},security_model=none,multidevs=remap"
         -device "virtio-9p-pci,fsdev=rw$i,mount_tag=rw$i")
  LIST+="${LIST:+,}${RW[$i]}"
done
# no_timer_check: on a loaded host the emulated (TCG) guest's timer check at boot can fail and panic the kernel
# ("IO-APIC + timer doesn't work!", seen with a CPU hog beside the test command); the timer itself works
APPEND="console=ttyS0 quiet loglevel=3 panic=-1 no_timer_check ${LSM_VM_KARGS:-} lsm.rw=$LIST lsm.cwd=$CWD lsm.mods=$TOP/kernel/lib/modules"
[ $INTER = 1 ] || APPEND+=" lsm.run=$RUNDIR"
case ${LSM_VM_ACCEL:-tcg} in
  kvm) ACCEL=(-accel kvm -cpu host) ;;
  *) ACCEL=(-accel tcg,thread=multi -cpu max) ;;
esac
IN=/dev/null; [ $INTER = 1 ] && IN=/dev/stdin
timeout "${LSM_VM_TIMEOUT:-900}" qemu-system-x86_64 "${ACCEL[@]}" -m "${LSM_VM_MEM:-1024}" -smp "${LSM_VM_SMP:-1}" \
  -nographic -no-reboot -net none -kernel "$KERNEL" -initrd "$INITRD" -append "$APPEND" "${DEVS[@]}" < $IN
qrc=$?
if [ -f "$RUNDIR/rc" ]; then
  exit "$(cat "$RUNDIR/rc")"
fi
echo "vm_run: the guest reported no exit code (qemu exit $qrc)" >&2
exit 255
