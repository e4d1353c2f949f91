#!/bin/bash
# Inside the HIL guest (started by hil/run_hil.sh through vm_run.sh): create vcan0, report how long the guest
# took to come up, and run the given command (the pytest suite). gpio-sim was loaded by the guest's init.
set -u
ip link add dev vcan0 type vcan && ip link set up vcan0 || { echo "guest: cannot create vcan0"; exit 2; }
# vcan1: the node's side of the lossy bridge (hil/lissom_hil/bridge.py, test_faults.py)
ip link add dev vcan1 type vcan && ip link set up vcan1 || echo "guest: cannot create vcan1 (bridge tests skip)"
echo "[hil] guest up: $(cut -d' ' -f1 /proc/uptime) s since its kernel started; vcan0 ready"
exec "$@"
