#!/usr/bin/env bash
# Soak benchmark (docs/reliability.md): the seeded randomized test programs at large counts, in chunks with
# distinct seeds, double and float, each chunk a separate process (run J at a time):
#   test_scurve_props[_float] SEED N   N velocity changes + N/8 moves (limits, exact ends, stepgen = closed form)
#   test_scurve_props[_float] SEED 0 M M moves alone (--moves)
#   test_planner[_float] SEED N        12 x N random paths through the planner and interpolator (limits, deviation,
#                                      exact end, no stall, no fallback)
#   test_sim_fixstep SEED N            N moves on the integer-only evaluator against the double reference
#   test_planner_undo[_float] SEED N   5 x N random paths: 3 x N override paths with the first switch search of
#                                      each failed on purpose (undo, restore, retries) and 2 x N slowly fed paths
#                                      with every append while moving made an exact stop on purpose (restore;
#                                      tests/plan/test_planner.c, --undo)
# Usage: scripts/soak.sh [--vc N] [--moves N] [--paths N] [--fixstep N] [--undo N] [--jobs J] [--seed S]
#                        [--only double|float]
#   defaults: the issue's goal, --vc 10000000 --paths 1000000 --fixstep 1000000 (many CPU hours: pass smaller
#   counts on a shared machine), --moves 0 (moves beyond the vc chunks' N/8), --undo 0; --jobs 1; --seed 1000.
# Writes out/soak/<program>-<seed>.log per chunk and out/soak/summary.txt; ends with "soak: N passed, N failed"
# (chunks). A failing chunk prints its seed: rerun it alone with the same SEED and its count.
set -uo pipefail
cd "$(dirname "$0")/.."

vc=10000000; moves=0; paths=1000000; fix=1000000; undo=0; jobs=1; seed=1000; only=""
while [ $# -gt 0 ]; do
  case "$1" in
    --vc) vc=$2; shift 2 ;;
    --moves) moves=$2; shift 2 ;;
    --paths) paths=$2; shift 2 ;;
    --fixstep) fix=$2; shift 2 ;;
    --undo) undo=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --only) only=$2; shift 2 ;;
    *) echo "usage: scripts/soak.sh [--vc N] [--moves N] [--paths N] [--fixstep N] [--undo N] [--jobs J] [--seed S] [--only double|float]"
       exit 2 ;;
  esac
done

VC_CHUNK=200000      # velocity changes per process (and 25 000 moves; about 20 s of CPU)
MOVE_CHUNK=25000     # moves per process of --moves (about 15 s of CPU)
PATH_CHUNK=120       # random paths per process (12 scenarios x 10; about 0.5 s of CPU)
FIX_CHUNK=20000      # fixstep moves per process
UNDO_CHUNK=120       # forced-undo and forced-stop paths per process (5 scenarios x 24; about 2 s of CPU)

cmake --preset host >/dev/null || exit 1
cmake --build build -j "$jobs" --target test_scurve_props test_scurve_props_float test_planner test_planner_float \
      test_planner_undo test_planner_undo_float test_sim_fixstep >/dev/null || exit 1
out=${SOAK_OUT:-out/soak} # (SOAK_OUT: another directory, for two soaks at once from one build)
mkdir -p "$out"
jobsfile=$(mktemp)

# plan(PROGRAM TOTAL CHUNK DIV [MOVES]): chunk lines "PROGRAM SEED COUNT" (COUNT = chunk / DIV: the program's own
# unit); with MOVES, "PROGRAM SEED 0 COUNT" (moves alone, seeds from SEED + MOVE_SEEDS: a vc chunk of the same
# seed draws the same first moves).
MOVE_SEEDS=100000
plan() {
  local prog=$1 total=$2 chunk=$3 div=$4 mv=${5:-} done_=0 n s=$seed
  [ -n "${5:-}" ] && s=$((seed + MOVE_SEEDS))
  while [ "$done_" -lt "$total" ]; do
    n=$((total - done_ < chunk ? total - done_ : chunk))
    if [ -n "$mv" ]; then echo "$prog $s 0 $n" >>"$jobsfile"; else echo "$prog $s $(( (n + div - 1) / div ))" >>"$jobsfile"; fi
    done_=$((done_ + n)); s=$((s + 1))
  done
}
variants=("" "_float")
[ "$only" = double ] && variants=("")
[ "$only" = float ] && variants=("_float")
for v in "${variants[@]}"; do
  [ "$vc" -gt 0 ] && plan "test_scurve_props$v" "$vc" $VC_CHUNK 1
  [ "$moves" -gt 0 ] && plan "test_scurve_props$v" "$moves" $MOVE_CHUNK 1 moves
  [ "$paths" -gt 0 ] && plan "test_planner$v" "$paths" $PATH_CHUNK 12
  [ "$undo" -gt 0 ] && plan "test_planner_undo$v" "$undo" $UNDO_CHUNK 5
done
[ "$fix" -gt 0 ] && [ "$only" != float ] && plan test_sim_fixstep "$fix" $FIX_CHUNK 1

t0=$(date +%s)
# each chunk: its log, then "PASS|FAIL program seed count [moves]"
xargs -P "$jobs" -L 1 sh -c 'build/bin/$0 $1 $2 $3 >'"$out"'/$0-$1.log 2>&1 && echo "PASS $0 $1 $2 $3" || echo "FAIL $0 $1 $2 $3"' \
  <"$jobsfile" >"$out/results.txt"
t1=$(date +%s)
rm -f "$jobsfile"

npass=$(grep -c '^PASS' "$out/results.txt"); nfail=$(grep -c '^FAIL' "$out/results.txt")
{
  echo "soak $(date -u +%Y-%m-%dT%H:%MZ), $(git rev-parse --short HEAD), $((t1 - t0)) s wall, $jobs jobs"
  for v in "${variants[@]}"; do
    name=double; [ -n "$v" ] && name=float
    for p in test_scurve_props test_planner test_planner_undo; do
      [ "$p" = test_planner_undo ] && [ "$undo" -eq 0 ] && continue
      c=$(awk -v p="$p$v" '$1=="PASS" && $2==p {s+=$4} END {print s+0}' "$out/results.txt")
      f=$(awk -v p="$p$v" '$1=="FAIL" && $2==p {n++} END {print n+0}' "$out/results.txt")
      if [ "$p" = test_scurve_props ]; then
        m=$(awk -v p="$p$v" '$1=="PASS" && $2==p {s+=(NF>=5 ? $5 : int($4/8))} END {print s+0}' "$out/results.txt")
        echo "  $name: $c velocity changes and $m moves passed, $f failing chunks"
      else
        progs=$(cat "$out"/$p$v-*.log 2>/dev/null | grep -oE ": [0-9]+ programs" | grep -oE "[0-9]+" | awk '{s+=$1} END {print s+0}')
        k=12; [ "$p" = test_planner_undo ] && k=5
        echo "  $name: $progs random paths passed ($p: count $c x $k scenarios), $f failing chunks"
      fi
    done
  done
  if [ "$only" != float ]; then
    c=$(awk '$1=="PASS" && $2=="test_sim_fixstep" {s+=$4} END {print s+0}' "$out/results.txt")
    echo "  integer-only evaluator: $c moves passed"
  fi
  grep '^FAIL' "$out/results.txt" | sed 's/^/  /'
} | tee "$out/summary.txt"
echo "soak: $npass passed, $nfail failed"
[ "$nfail" -eq 0 ]
