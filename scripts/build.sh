#!/usr/bin/env bash
# Host build (preset `host`): firmware core (double and float), lissom-sim, the cmocka tests. Output in build/.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset host >/dev/null
cmake --build --preset host -j "$(nproc)"
