#!/usr/bin/env bash
# Replays every input of tests/fuzz/known_failing/<target>/ (build/ replay binaries, plain compiler) and says
# which still fail and which now pass: those can move to tests/fuzz/regressions/<target>/ (ctest replays them).
# Usage: tests/fuzz/check_known.sh        (exit 0; the list is the output)
cd "$(dirname "$0")/../.."
cmake --build build --target fuzz_gcode_path_replay fuzz_gcode_path_float_replay fuzz_planner_replay \
      fuzz_planner_float_replay fuzz_canopen_replay fuzz_machine_replay >/dev/null || exit 1
for d in tests/fuzz/known_failing/*/; do
  t=$(basename "$d")
  for f in "$d"*; do
    [ -f "$f" ] || continue
    msg=$(timeout 600 "build/bin/${t}_replay" "$f" 2>&1 | grep -E "VIOLATION|ERROR|runtime error" | head -1 | cut -c1-160)
    if [ -n "$msg" ]; then echo "still failing  $t/$(basename "$f"): $msg"
    else echo "NOW PASSES     $t/$(basename "$f"): move it to tests/fuzz/regressions/$t/"; fi
  done
done
