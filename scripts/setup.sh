#!/usr/bin/env bash
# Quick start, command 1 of 2 (Debian 12, as root): installs everything (apt packages, the Python venv, the
# CMake build) and runs the main job, the host_sim demo: a sin² S-curve move planned by the firmware code,
# with a summary on stdout and out/demo/{scurve.csv,scurve.png} (J, A, V and S against time).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh
scripts/build.sh
exec build/bin/lissom-sim demo --out out/demo
