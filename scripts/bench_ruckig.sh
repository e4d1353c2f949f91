#!/usr/bin/env bash
# Planning time of lsm_move_plan / lsm_scurve_plan against Ruckig's calculate, in one process on the same random
# cases (bench/ruckig_vs_move.cpp; issue 12 item 6). A benchmark, not a test; Ruckig is not a project dependency.
#   scripts/bench_ruckig.sh RUCKIG_SRC [CASES [SECONDS_PER_ROW [SEED]]]
# RUCKIG_SRC: a checkout of github.com/pantor/ruckig (built here with CMake into RUCKIG_SRC/build-lissom).
# Uses the host build's double core (build/, scripts/build.sh first); LSM_BENCH_FLOAT=1 for the float core.
# LSM_BENCH_REF=REV times firmware/profile/scurve.c and move.c of git revision REV instead (the "before" of a
# change, measured in the same period as the "after").
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
ref_objs=()
if [ -n "${LSM_BENCH_REF:-}" ]; then
  refdir=$(mktemp -d)
  trap 'rm -rf "$refdir"' EXIT
  for f in scurve.c scurve.h move.c move.h; do git show "$LSM_BENCH_REF:firmware/profile/$f" > "$refdir/$f"; done
  for f in scurve move; do
    cc -O2 -g -DNDEBUG -std=c11 $defs -I"$refdir" -Ifirmware/base -c "$refdir/$f.c" -o "$refdir/$f.o"
    ref_objs+=("$refdir/$f.o")
  done
  out=$refdir/bench
fi
g++ -O2 -std=c++17 $defs -Ifirmware/base -Ifirmware/profile -Ibuild/firmware/base -I"$src/include" \
  bench/ruckig_vs_move.cpp "${ref_objs[@]}" build/firmware/profile/liblsm_profile$suffix.a \
  build/firmware/base/liblsm_base$suffix.a "$rb/libruckig.a" -lm -o "$out"
"$out" "$@"
