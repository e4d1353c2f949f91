#!/usr/bin/env bash
# arm_bench.sh: instruction counts and flash/RAM of the float core on Cortex-M4F (QEMU mps2-an386).
# Builds the cortex-m4f preset if needed, runs lissom-bench.elf under qemu -icount shift=0 and prints
#   1. a table: benchmark | instructions | per (plan, cycle, call, block) | calls averaged | max single cycle
#   2. the core's flash/RAM: per object of the component archives liblsm_<component>_f.a (arm-none-eabi-size), and per component as linked
#      into each image (from the linker map, scripts/arm_mapsize.py); lissom-contour.elf is the core with a
#      128-block look-ahead (planner, interpolator and nothing else of the core)
# scripts/arm_report.sh formats the planner/interpolator figures of issue 7 against their goals.
# The tables are markdown, ready for docs/cortex_m.md and the README. Exit 1 if the bench fails.
# Environment: LSM_ARM_BUILD_DIR (default <repo>/build-arm), LSM_QEMU_TIMEOUT (s, default 60).
# With --json, prints only one JSON object (cycle_instructions_line, _arc, _clothoid, append_instructions_mean,
# append_instructions_max, piece_instructions_mean, piece_instructions_max, core_flash_bytes, ram_bytes_per_block;
# scripts/arm_report.py --json) and the build and run messages go to stderr.
set -uo pipefail

JSON=0
[ "${1:-}" = "--json" ] && JSON=1
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD=${LSM_ARM_BUILD_DIR:-$ROOT/build-arm}
QEMU_TIMEOUT=${LSM_QEMU_TIMEOUT:-60}
ELF=$BUILD/bin/lissom-bench.elf


mkdir -p "$BUILD"
if [ ! -f "$BUILD/CMakeCache.txt" ]; then
    cmake --preset cortex-m4f -S "$ROOT" -B "$BUILD" >"$BUILD/arm_bench.configure.log" 2>&1 ||
        { cat "$BUILD/arm_bench.configure.log"; echo "arm_bench: FAIL (configure)"; exit 1; }
fi
cmake --build "$BUILD" >"$BUILD/arm_bench.build.log" 2>&1 ||
    { tail -40 "$BUILD/arm_bench.build.log"; echo "arm_bench: FAIL (build)"; exit 1; }

LOG=$BUILD/lissom-bench.qemu.log
timeout "$QEMU_TIMEOUT" qemu-system-arm -M mps2-an386 -cpu cortex-m4 -nographic -monitor none -serial none \
    -semihosting-config enable=on,target=native -icount shift=0 -kernel "$ELF" >"$LOG" 2>&1
rc=$?
if [ $rc -ne 0 ] || ! grep -qx "bench PASS" "$LOG"; then
    cat "$LOG" >&2; echo "arm_bench: FAIL (exit status $rc)" >&2; exit 1
fi

if [ $JSON -eq 1 ]; then
    python3 "$ROOT/scripts/arm_report.py" --json "$LOG" "$BUILD/bin/lissom-contour.elf.map" || exit 1
    exit 0
fi

BUILD_TYPE=$(sed -n 's/^CMAKE_BUILD_TYPE:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
echo "Instruction counts, Cortex-M4F float core (${BUILD_TYPE:-?} build, arm-none-eabi-gcc $(arm-none-eabi-gcc -dumpversion)),"
echo "QEMU mps2-an386 -icount shift=0, SysTick x 40; harness overhead subtracted."
grep '^calib ' "$LOG" | awk '{printf "%s%s", (NR>1?", ":"calibration: "), $2" -> "$3" "$4} END {print ""}'
echo
echo "| benchmark | instructions | per | calls averaged | max single cycle (±40) | max at |"
echo "|---|---:|---|---:|---:|---|"
awk '$1=="bench" && NF>=4 {
        name=$2; val=$3; unit=$4; calls=""; max=""; at=""; status="";
        for (i = 5; i <= NF; i++) {
            split($i, kv, "=");
            if (kv[1]=="calls") calls=kv[2]; if (kv[1]=="max") max=kv[2];
            if (kv[1]=="max_at") at=kv[2]; if (kv[1]=="status") status=kv[2];
        }
        if (val == "NA") val = "not yet (" status ")";
        printf "| %s | %s | %s | %s | %s | %s |\n", name, val, unit, calls, max, at }' "$LOG"
echo
echo "| type | bytes |"
echo "|---|---:|"
awk '$1=="size" {printf "| %s | %s |\n", $2, $3}' "$LOG"

echo
echo "Float core archive, per object (arm-none-eabi-size; everything compiled, before --gc-sections; with LSM_ARM_LTO"
echo "the plain code of the fat LTO objects, not what the link-time optimisation makes of it):"
echo
echo "| object | text (flash) | data | bss |"
echo "|---|---:|---:|---:|"
arm-none-eabi-size -t "$BUILD"/firmware/*/liblsm_*_f.a | awk 'NR>1 && $6 != "(TOTALS)" {sub(/ \(ex .*$/, "", $6); printf "| %s | %s | %s | %s |\n", $6, $1, $2, $3}
                                    $6 == "(TOTALS)" {printf "| **total** | **%s** | **%s** | **%s** |\n", $1, $2, $3}'
python3 "$ROOT/scripts/arm_mapsize.py" "$BUILD"/bin/lissom-selftest.elf.map "$BUILD"/bin/lissom-contour.elf.map \
    "$BUILD"/bin/lissom-bench.elf.map
echo
echo "Core with a 128-block look-ahead: the liblsm_*_f.a archives in lissom-contour.elf above; per object, RAM per block and"
echo "the goals: scripts/arm_report.sh."
echo "arm_bench: PASS"
