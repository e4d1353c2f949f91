#!/usr/bin/env bash
# Starts the controller image lissom-controller.elf (Cortex-M4F, QEMU mps2-an386) with its CAN bus on a TCP port:
# UART 0 speaks slcan (the Lawicel protocol of USB-CAN adapters) on 127.0.0.1:PORT, so a CANopen master connects
# with  canopen.Network().connect(interface="slcan", channel="socket://127.0.0.1:PORT", bitrate=1000000)
# (or Linux slcand through a serial port). Runs until stopped (SIGTERM / SIGINT / Ctrl-C).
#
#   scripts/mcu_node.sh --tcp PORT --node-id N [--axes A] [--elf FILE]
#
# The image is built first if it is missing (preset cortex-m4f, build-arm/; LSM_ARM_BUILD_DIR overrides).
# QEMU options (docs/cortex_m.md, "Controller image"): -icount shift=3,align=on,sleep=on: an instruction is 8 ns
# of virtual time, the 168,000-instruction tick 1.344 ms; align=on holds virtual time to the host's real time, so
# the node's clock runs at 1/1.344 of real time (a 1 ms cycle every 1.344 ms) as long as QEMU keeps up (it warns
# "The guest is now late" when it does not). The image prints one "lissom-controller: ready ..." line on stderr.
set -euo pipefail
cd "$(dirname "$0")/.."
port="" node_id=1 axes=3 elf=""
usage() { sed -n '2,8p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }
while [ $# -gt 0 ]; do
  case "$1" in
    --tcp) port=${2:-}; shift 2 ;;
    --node-id) node_id=${2:-}; shift 2 ;;
    --axes) axes=${2:-}; shift 2 ;;
    --elf) elf=${2:-}; shift 2 ;;
    -h|--help) usage ;;
    *) echo "mcu_node.sh: unknown option $1" >&2; usage ;;
  esac
done
[[ "$port" =~ ^[0-9]+$ ]] && [ "$port" -ge 1 ] && [ "$port" -le 65535 ] || { echo "mcu_node.sh: --tcp PORT (1..65535) is required" >&2; exit 2; }
[[ "$node_id" =~ ^[0-9]+$ ]] && [ "$node_id" -ge 1 ] && [ "$node_id" -le 127 ] || { echo "mcu_node.sh: --node-id must be 1..127" >&2; exit 2; }
[[ "$axes" =~ ^[0-9]+$ ]] && [ "$axes" -ge 1 ] && [ "$axes" -le 6 ] || { echo "mcu_node.sh: --axes must be 1..6" >&2; exit 2; }
if [ -z "$elf" ]; then
  bdir=${LSM_ARM_BUILD_DIR:-build-arm}
  elf=$bdir/bin/lissom-controller.elf
  if [ ! -f "$elf" ]; then
    { [ -f "$bdir/CMakeCache.txt" ] || cmake --preset cortex-m4f >/dev/null; } >&2
    cmake --build "$bdir" --target lissom-controller >&2
  fi
fi
[ -f "$elf" ] || { echo "mcu_node.sh: no image $elf" >&2; exit 1; }
command -v qemu-system-arm >/dev/null || { echo "mcu_node.sh: qemu-system-arm not found (apt-get install qemu-system-arm)" >&2; exit 1; }
exec qemu-system-arm -M mps2-an386 -cpu cortex-m4 -nographic -monitor none \
  -serial "tcp:127.0.0.1:$port,server=on,wait=off" \
  -semihosting-config "enable=on,target=native,arg=--node-id,arg=$node_id,arg=--axes,arg=$axes" \
  -icount shift=3,sleep=on -kernel "$elf"
