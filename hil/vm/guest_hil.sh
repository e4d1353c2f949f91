#!/bin/bash
# Inside the HIL guest (started by hil/run_hil.sh through vm_run.sh): create vcan0, report how long the guest
# took to come up, and run the given command (the pytest suite). gpio-sim was loaded by the guest's init.
set -u
ip link add dev vcan0 type vcan && ip link set up vcan0 || { echo "guest: cannot create vcan0"; exit 2; }
echo "[hil] guest up: $(cut -d' ' -f1 /proc/uptime) s since its kernel started; vcan0 ready"
exec "$@"
