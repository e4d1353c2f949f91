#!/usr/bin/env bash
# Host build (preset `host`): firmware core (double and float), lissom-sim, the cmocka tests. Output in build/.
# Then lissom-sim on the float core (preset `host-float`, build-float/bin/lissom-sim: the Cortex-M4F's numerics).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset host >/dev/null
cmake --build --preset host -j "$(nproc)"
cmake --preset host-float >/dev/null
cmake --build build-float -j "$(nproc)" --target lissom-sim
