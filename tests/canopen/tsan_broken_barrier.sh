#!/usr/bin/env bash
# Shows that the SDO hand-off's ThreadSanitizer test (test_co_sdo_split with LSM_TEST_THREADS, ctest
# co_sdo_split_tsan) catches a broken barrier: for each publishing store of the hand-off (canopen.c), builds the test
# against a copy of the firmware where that one release store is relaxed, and expects TSan to report a data race
# (exit 66). Then the unbroken copy, which must pass. Not part of ctest (a few compilations; run by hand):
#   tests/canopen/tsan_broken_barrier.sh [SEEDS]      (default 3 seeds, 24 scripts each)
set -uo pipefail
cd "$(dirname "$0")/../.."
seeds=${1:-3}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cc=${CC:-cc}
mutations=(
  "none|"
  "request ring (tick -> background)|s/lsm_atomic_put_release(\&l->req_head, head + 1u);/lsm_atomic_put(\&l->req_head, head + 1u);/"
  "access mailbox, the answer (tick -> background)|s/lsm_atomic_put_release(\&l->acc_done, done + 1u);/lsm_atomic_put(\&l->acc_done, done + 1u);/"
  "access mailbox, the request (background -> tick)|s/lsm_atomic_put_release(\&l->acc_posted,/lsm_atomic_put(\&l->acc_posted,/"
  "response ring (background -> tick)|s/lsm_atomic_put_release(\&l->res_head, head + 1u);/lsm_atomic_put(\&l->res_head, head + 1u);/"
)
pass=0; fail=0
for m in "${mutations[@]}"; do
  name=${m%%|*}; expr=${m#*|}
  mkdir -p "$tmp/canopen"
  cp firmware/canopen/*.c firmware/canopen/*.h "$tmp/canopen/"
  if [ -n "$expr" ]; then
    sed -i "$expr" "$tmp/canopen/canopen.c"
    if cmp -s firmware/canopen/canopen.c "$tmp/canopen/canopen.c"; then
      echo "tsan_broken_barrier: $name: the mutation did not apply (canopen.c changed?)"; fail=$((fail + 1)); continue
    fi
  fi
  if ! $cc -std=c11 -fsanitize=thread -g -O1 -DLSM_TEST_THREADS=1 -Ifirmware/base -I"$tmp/canopen" -Itests/common \
      tests/canopen/test_co_sdo_split.c "$tmp"/canopen/*.c firmware/base/*.c -lcmocka -lm -lpthread \
      -o "$tmp/t" 2>"$tmp/cc.log"; then
    echo "tsan_broken_barrier: $name: build failed"; tail -5 "$tmp/cc.log"; fail=$((fail + 1)); continue
  fi
  races=0
  for s in $(seq 1 "$seeds"); do
    TSAN_OPTIONS="halt_on_error=1 exitcode=66" "$tmp/t" "$s" 24 >"$tmp/out" 2>&1
    [ $? -eq 66 ] && races=$((races + 1))
  done
  if [ -z "$expr" ]; then
    [ $races -eq 0 ] && { echo "unbroken: no race in $seeds seeds (ok)"; pass=$((pass + 1)); } \
                     || { echo "unbroken: $races of $seeds seeds report a race (FAIL)"; fail=$((fail + 1)); }
  else
    [ $races -gt 0 ] && { echo "broken $name: race reported in $races of $seeds seeds (caught)"; pass=$((pass + 1)); } \
                     || { echo "broken $name: no race reported (NOT caught)"; fail=$((fail + 1)); }
  fi
done
echo "tsan_broken_barrier: $pass passed, $fail failed"
[ $fail -eq 0 ]
