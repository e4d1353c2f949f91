#!/usr/bin/env bash
# Runs the libFuzzer targets of tests/fuzz/ (ASan + UBSan, clang-14; docs/reliability.md).
#   scripts/fuzz.sh [SECONDS] [TARGET...]   each target for SECONDS (default 60), one after the other
#   scripts/fuzz.sh --brief                 the test command's stage: every target 5 s (about 30 s in all), known
#                                           classes reported (LSM_FUZZ_KNOWN=report), anything else fails
# Targets: fuzz_gcode_path fuzz_gcode_path_float fuzz_planner fuzz_planner_float fuzz_canopen fuzz_machine.
# Long runs (not --brief) are strict (every check fatal) and go on after a finding (-fork=1 -ignore_crashes=1), so
# that every failing input of the run is kept. Seeds: tests/fuzz/corpus/<kind>/ (read only); inputs found while
# fuzzing: build-fuzz/corpus/<target>/; failing inputs: build-fuzz/findings/<target>/ (crash-*, timeout-*). To keep
# a finding as a regression, copy it to tests/fuzz/regressions/<target>/ once it passes (ctest replays it), or to
# tests/fuzz/known_failing/<target>/ with a line in its README.md while its fix is in progress.
# Ends with "fuzz: N passed, N failed" (a target fails when it found anything).
set -uo pipefail
cd "$(dirname "$0")/.."

brief=0
secs=60
targets=()
for a in "$@"; do
  case "$a" in
    --brief) brief=1; secs=5 ;;
    ''|*[!0-9]*) targets+=("$a") ;;
    *) secs=$a ;;
  esac
done
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_gcode_path fuzz_gcode_path_float fuzz_planner fuzz_planner_float fuzz_canopen
                                     fuzz_machine)

if ! command -v clang-14 >/dev/null; then
  echo "fuzz: clang-14 is missing (scripts/deps.sh installs clang-14 and libclang-rt-14-dev)"
  echo "fuzz: 0 passed, 1 failed"
  exit 1
fi
cmake --preset fuzz >/dev/null || exit 1
cmake --build build-fuzz -j "$(nproc)" --target "${targets[@]}" >build-fuzz/fuzz-build.log 2>&1 || {
  tail -30 build-fuzz/fuzz-build.log; echo "fuzz: 0 passed, 1 failed"; exit 1; }

# the seed corpus (input kind) and the largest useful input of each target
kind_of() { case "$1" in fuzz_gcode_path*) echo gcode_path ;; fuzz_planner*) echo planner ;;
                         fuzz_canopen) echo canopen ;; fuzz_machine) echo machine ;; esac; }
maxlen_of() { case "$1" in fuzz_gcode_path*) echo 4098 ;; fuzz_planner*) echo 2401 ;;
                           fuzz_canopen) echo 4400 ;; fuzz_machine) echo 8192 ;; esac; }

# A unit that took over SLOW_S s of wall time (libFuzzer's slow-unit report, its default) is a finding only if it is
# slow alone too: on a loaded machine a starved fuzzer's units take long in wall time (stop 25: 15 of fuzz_machine's,
# each 0.1-0.3 s when run again). sort_slow_units re-runs every new slow-unit-* of a target once, alone, with the same
# bound: those that pass within it move to FOUND/slow-under-load/ (kept, counted, not failures); the others stay.
SLOW_S=10
sort_slow_units() {  # target found-dir names-before -> prints how many moved
  local t=$1 found=$2 old=$3 n=0 f
  for f in "$found"/slow-unit-*; do
    [ -e "$f" ] || continue
    grep -qxF "$(basename "$f")" <<<"$old" && continue  # from an earlier run: left as it is
    # exit 0 under timeout: it passed within the bound (timeout stops it at SLOW_S and exits 124)
    timeout "$SLOW_S" "build-fuzz/bin/$t" "$f" >/dev/null 2>&1 && mv "$f" "$found/slow-under-load/" && n=$((n + 1))
  done
  echo "$n"
}

passed=0; failed=0
for t in "${targets[@]}"; do
  kind=$(kind_of "$t")
  work=build-fuzz/corpus/$t; found=build-fuzz/findings/$t; log=build-fuzz/$t.log
  mkdir -p "$work" "$found" "$found/slow-under-load"
  before=$(ls "$found" | wc -l); before_names=$(ls "$found")
  opts=(-max_total_time="$secs" -timeout=60 -rss_limit_mb=2048 -max_len="$(maxlen_of "$t")"
        -report_slow_units="$SLOW_S" -artifact_prefix="$found/" -print_final_stats=1)
  if [ $brief -eq 1 ]; then
    export LSM_FUZZ_KNOWN=report
  else
    export LSM_FUZZ_KNOWN=${LSM_FUZZ_KNOWN:-fail}
    opts+=(-fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1)
  fi
  export LSM_FUZZ_KNOWN_LOG="$PWD/build-fuzz/$t.known"
  rm -f "$LSM_FUZZ_KNOWN_LOG"
  seeds=("tests/fuzz/corpus/$kind")
  [ -d "tests/fuzz/regressions/$t" ] && seeds+=("tests/fuzz/regressions/$t")
  "build-fuzz/bin/$t" "${opts[@]}" "$work" "${seeds[@]}" >"$log" 2>&1
  rc=$?
  slow_load=$(sort_slow_units "$t" "$found" "$before_names")
  after=$(ls "$found" | wc -l)
  execs=$(grep -aoE "stat::number_of_executed_units: *[0-9]+" "$log" | grep -oE "[0-9]+$" | awk "{s+=\$1} END {if (NR) print s}")
  [ -n "$execs" ] || execs=$(grep -aoE "#[0-9]+" "$log" | tail -1 | tr -d '#')
  known=$( { cat "$LSM_FUZZ_KNOWN_LOG" 2>/dev/null || true; } | cut -d' ' -f1 | sort | uniq -c | awk '{printf "%s%s %s", (NR > 1 ? ", " : ""), $1, $2}')
  [ -n "$known" ] || known=none
  if [ $rc -eq 0 ] && [ "$after" -eq "$before" ]; then
    passed=$((passed + 1))
    echo "fuzz: $t: ok, ${secs} s, ${execs:-?} runs, corpus $(ls "$work" | wc -l), known-class reports: $known, slow units under load: $slow_load (log $log)"
  else
    failed=$((failed + 1))
    echo "fuzz: $t: FOUND $((after - before)) new failing inputs (exit $rc) in $found (log $log)"
    grep -aE "FUZZ VIOLATION|ERROR: (Address|Undefined|libFuzzer)|runtime error" "$log" | sort | uniq -c | sort -rn | head -8
  fi
done
echo "fuzz: $passed passed, $failed failed"
[ $failed -eq 0 ]
