#!/usr/bin/env bash
# Planning time of lsm_move_plan / lsm_scurve_plan against Ruckig's calculate, in one process on the same random
# cases (bench/ruckig_vs_move.cpp; issue 12 item 6). A benchmark, not a test; Ruckig is not a project dependency.
#   scripts/bench_ruckig.sh RUCKIG_SRC [CASES [SECONDS_PER_ROW [SEED]]]
# RUCKIG_SRC: a checkout of github.com/pantor/ruckig (built here with CMake into RUCKIG_SRC/build-lissom).
# Uses the host build's double core (build/, scripts/build.sh first); LSM_BENCH_FLOAT=1 for the float core.
set -euo pipefail
cd "$(dirname "$0")/.."
src=${1:?usage: scripts/bench_ruckig.sh RUCKIG_SRC [CASES [SECONDS [SEED]]]}
shift
[ -f "$src/include/ruckig/ruckig.hpp" ] || { echo "bench_ruckig: no Ruckig sources in $src" >&2; exit 2; }
rb="$src/build-lissom"
if [ ! -f "$rb/libruckig.a" ]; then
  cmake -S "$src" -B "$rb" -DCMAKE_BUILD_TYPE=Release -DBUILD_SHARED_LIBS=OFF -DBUILD_TESTS=OFF \
    -DBUILD_EXAMPLES=OFF -DBUILD_CLOUD_CLIENT=OFF >/dev/null
  cmake --build "$rb" -j2 --target ruckig >/dev/null
fi
suffix=""; [ "${LSM_BENCH_FLOAT:-0}" = 1 ] && suffix="_f"
cmake --build build -j2 --target "lsm_profile$suffix" "lsm_base$suffix" >/dev/null
defs=""; [ -n "$suffix" ] && defs="-DLSM_REAL_FLOAT=1"
out=build/bench_ruckig_vs_move$suffix
g++ -O2 -std=c++17 $defs -Ifirmware/base -Ifirmware/profile -Ibuild/firmware/base -I"$src/include" \
  bench/ruckig_vs_move.cpp build/firmware/profile/liblsm_profile$suffix.a build/firmware/base/liblsm_base$suffix.a \
  "$rb/libruckig.a" -lm -o "$out"
"$out" "$@"
