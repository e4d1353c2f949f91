#!/usr/bin/env bash
# arm_report.sh: the Cortex-M4F figures of issue 7 as markdown (for docs/cortex_m.md and the README): the
# interpolator's instructions per cycle (1, 3, 6 axes; line, arc, clothoid), the planner's instructions per
# appended block with its breakdown (corner smoothing, arc fitting, backward pass), the S-curve plan, RAM per
# look-ahead block, the RAM of a 128-block look-ahead, the stack high-water mark, the core's flash, and the goals.
# Builds the cortex-m4f preset (incrementally), runs lissom-bench.elf, lissom-bench-ramp.elf and lissom-contour.elf under
# qemu-system-arm -M mps2-an386 -icount shift=0 and formats with scripts/arm_report.py. Re-runnable: refresh the
# figures after a change of the core with `scripts/arm_report.sh > /tmp/figures.md`.
# With --update-docs, also replaces the block between "<!-- arm_report begin -->" and "<!-- arm_report end -->"
# in docs/cortex_m.md with the new figures.
# Exit 1 if the build or an image fails. Environment: LSM_ARM_BUILD_DIR (default <repo>/build-arm),
# LSM_QEMU_TIMEOUT (s, default 120).
set -uo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD=${LSM_ARM_BUILD_DIR:-$ROOT/build-arm}
QEMU_TIMEOUT=${LSM_QEMU_TIMEOUT:-120}
UPDATE_DOCS=0
[ "${1:-}" = "--update-docs" ] && UPDATE_DOCS=1

mkdir -p "$BUILD"
if [ ! -f "$BUILD/CMakeCache.txt" ]; then
    cmake --preset cortex-m4f -S "$ROOT" -B "$BUILD" >"$BUILD/arm_report.configure.log" 2>&1 ||
        { cat "$BUILD/arm_report.configure.log" >&2; echo "arm_report: FAIL (configure)" >&2; exit 1; }
fi
cmake --build "$BUILD" --target lissom-bench lissom-bench-ramp lissom-contour >"$BUILD/arm_report.build.log" 2>&1 ||
    { tail -40 "$BUILD/arm_report.build.log" >&2; echo "arm_report: FAIL (build)" >&2; exit 1; }

run() {  # image, its PASS line
    local log=$BUILD/$1.report.log
    timeout "$QEMU_TIMEOUT" qemu-system-arm -M mps2-an386 -cpu cortex-m4 -nographic -monitor none -serial none \
        -semihosting-config enable=on,target=native -icount shift=0 -kernel "$BUILD/bin/$1.elf" >"$log" 2>&1
    local rc=$?
    if [ $rc -ne 0 ] || ! grep -qx "$2" "$log"; then
        cat "$log" >&2; echo "arm_report: FAIL ($1 exit status $rc)" >&2; exit 1
    fi
}
run lissom-bench "bench PASS"
run lissom-bench-ramp "bench PASS"
run lissom-contour "contour PASS"

BUILD_TYPE=$(sed -n 's/^CMAKE_BUILD_TYPE:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
REPORT=$BUILD/arm_report.md
python3 "$ROOT/scripts/arm_report.py" "$BUILD/lissom-bench.report.log" "$BUILD/lissom-contour.report.log" \
    "$BUILD/bin/lissom-contour.elf.map" --ramp "$BUILD/lissom-bench-ramp.report.log" \
    --gcc "$(arm-none-eabi-gcc -dumpversion)" --build-type "${BUILD_TYPE:-?}" \
    --size "$(arm-none-eabi-size "$BUILD/bin/lissom-contour.elf" | tail -1)" >"$REPORT" ||
    { echo "arm_report: FAIL (format)" >&2; exit 1; }
cat "$REPORT"
if [ $UPDATE_DOCS -eq 1 ]; then
    python3 - "$ROOT/docs/cortex_m.md" "$REPORT" <<'PY' || { echo "arm_report: FAIL (update docs)" >&2; exit 1; }
import sys
doc, rep = sys.argv[1], open(sys.argv[2]).read().strip()
text = open(doc).read()
b, e = "<!-- arm_report begin -->", "<!-- arm_report end -->"
if b not in text or e not in text:
    sys.exit(f"{doc}: markers {b} / {e} missing")
head, rest = text.split(b, 1)
_, tail = rest.split(e, 1)
open(doc, "w").write(head + b + "\n" + rep + "\n" + e + tail)
print(f"arm_report: updated {doc}", file=sys.stderr)
PY
fi
