#!/usr/bin/env bash
# Bit-for-bit comparison of this tree's interval sizing and move planning (firmware/profile/scurve.c, move.c)
# with those of a reference revision, on a large seeded random set (bench/profile_same.c). For refactors of the
# planning speed: a plan that changes is printed with its inputs.
#   scripts/profile_same.sh REF [COUNT [SEED [SHOW]]]     e.g. scripts/profile_same.sh main 200000
# SHOW: how many differing cases to print per family (default 4).
# LSM_BENCH_FLOAT=1 compares the float builds. Both sides are compiled here with the host build's flags.
set -euo pipefail
cd "$(dirname "$0")/.."
ref=${1:?usage: scripts/profile_same.sh REF [COUNT [SEED]]}
shift
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for f in scurve.c scurve.h move.c move.h; do
  git show "$ref:firmware/profile/$f" > "$work/$f"
done
defs=""; [ "${LSM_BENCH_FLOAT:-0}" = 1 ] && defs="-DLSM_REAL_FLOAT=1"
flags="-O2 -std=c11 -fno-math-errno $defs -Ifirmware/base"
syms="$work/syms"
for f in scurve.c move.c; do
  cc $flags -I"$work" -c "$work/$f" -o "$work/ref_${f%.c}.o"
  cc $flags -Ifirmware/profile -c "firmware/profile/$f" -o "$work/new_${f%.c}.o"
done
# rename every global symbol the reference objects define: ref_<name>
nm --defined-only -g "$work"/ref_*.o | awk 'NF == 3 { print $3 " ref_" $3 }' > "$syms"
for f in "$work"/ref_*.o; do objcopy --redefine-syms="$syms" "$f"; done
cc $flags -Ifirmware/profile -Wall -Wextra bench/profile_same.c "$work"/ref_*.o "$work"/new_*.o \
  firmware/base/lsm_math.c -lm -o "$work/profile_same"
"$work/profile_same" "$@"
