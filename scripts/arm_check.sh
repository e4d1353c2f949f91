#!/usr/bin/env bash
# arm_check.sh: the Cortex-M4F check for CI.
#   1. configures and builds the `cortex-m4f` preset (arm-none-eabi-gcc, float core, -Wall -Wextra -Werror);
#   2. prints arm-none-eabi-size of every image;
#   3. fails if an image links a heap allocator (malloc, free, _sbrk, ...) or newlib's stdio (printf family);
#   4. fails if an image links software double-precision routines (__aeabi_d*, __aeabi_f2d, ...); lists, as
#      warnings, every such routine and every double libm call the float core archive refers to;
#   4b. fails if an image uses fused multiply-add (VFMA/VFMS/VFNMA/VFNMS) outside newlib's libm: the core must
#      round as the host does (bit-exact contour check below), with or without link-time optimisation;
#   5. runs lissom-selftest.elf, lissom-contour.elf and lissom-bench.elf under qemu-system-arm -M mps2-an386
#      -icount shift=0 with a timeout and requires exit code 0 and their PASS line; runs lissom-faulttest.elf and
#      requires the HardFault report and exit code 99; boots lissom-controller.elf for 5 s and requires its ready
#      line (it runs until stopped; hil/run_hil_mcu.sh tests it over CAN);
#   6. builds the host twin of the contour program (lissom-contour-host, target of the host build) and requires
#      its report (checksum of every setpoint, end point, planner statistics, sampled setpoints) to equal the
#      image's line for line.
# Ends with "arm_check: PASS" or "arm_check: FAIL (...)"; exit status 0 or 1.
# Environment: LSM_ARM_BUILD_DIR (default <repo>/build-arm), LSM_BUILD_DIR (host build, default <repo>/build;
# it must be configured, e.g. by scripts/build.sh), LSM_QEMU_TIMEOUT (s, default 60).
set -uo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD=${LSM_ARM_BUILD_DIR:-$ROOT/build-arm}
HOST_BUILD=${LSM_BUILD_DIR:-$ROOT/build}
QEMU_TIMEOUT=${LSM_QEMU_TIMEOUT:-60}
IMAGES=(lissom-selftest lissom-contour lissom-bench lissom-faulttest lissom-controller)
FAILS=()
fail() { echo "FAIL: $*"; FAILS+=("$1"); }
finish() {
    if [ ${#FAILS[@]} -eq 0 ]; then
        echo "arm_check: PASS"
        exit 0
    fi
    echo "arm_check: FAIL (${FAILS[*]})"
    exit 1
}

for tool in cmake arm-none-eabi-gcc arm-none-eabi-nm arm-none-eabi-size qemu-system-arm; do
    command -v "$tool" >/dev/null || { fail "missing-$tool"; echo "  install: apt-get install --no-install-recommends gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm cmake ninja-build"; }
done
[ ${#FAILS[@]} -eq 0 ] || finish

echo "== configure + build (preset cortex-m4f -> $BUILD)"
mkdir -p "$BUILD"
if ! cmake --preset cortex-m4f -S "$ROOT" -B "$BUILD" >"$BUILD/arm_check.configure.log" 2>&1; then
    cat "$BUILD/arm_check.configure.log"; fail "configure"; finish
fi
cmake --build "$BUILD" >"$BUILD/arm_check.build.log" 2>&1
build_rc=$?
grep -E "warning|error" "$BUILD/arm_check.build.log" | head -40
if [ $build_rc -ne 0 ]; then
    tail -40 "$BUILD/arm_check.build.log"; fail "build"; finish
fi
echo "ok: built ($(grep -c '^\[' "$BUILD/arm_check.build.log") steps; log: $BUILD/arm_check.build.log)"
# the float core: one archive per component (firmware/<component>/liblsm_<component>_f.a)
mapfile -t CORE < <(ls "$BUILD"/firmware/*/liblsm_*_f.a 2>/dev/null)
[ ${#CORE[@]} -gt 0 ] || { fail "no-core-archive"; finish; }
# the contour program's host twin, built now from the same sources as the images (compared at the end)
if [ ! -f "$HOST_BUILD/CMakeCache.txt" ]; then
    host_built=no-host-build; echo "FAIL: $HOST_BUILD is not configured (scripts/build.sh, or set LSM_BUILD_DIR)"
elif ! cmake --build "$HOST_BUILD" --target lissom-contour-host >"$BUILD/arm_check.host.log" 2>&1; then
    host_built=host-contour-build; tail -20 "$BUILD/arm_check.host.log"
else
    host_built=ok; echo "ok: host twin lissom-contour-host built in $HOST_BUILD"
fi

echo "== sizes"
ELFS=()
for img in "${IMAGES[@]}"; do
    elf=$BUILD/bin/$img.elf
    if [ -f "$elf" ]; then ELFS+=("$elf"); else fail "missing-$img"; fi
done
[ ${#ELFS[@]} -gt 0 ] && arm-none-eabi-size "${ELFS[@]}"
arm-none-eabi-size -t "${CORE[@]}" | tail -1 | awk '{printf "float core archive (all objects): text %s data %s bss %s\n", $1, $2, $3}'
lto=$(sed -n 's/^LSM_ARM_LTO:BOOL=//p' "$BUILD/CMakeCache.txt")
[ "$lto" = ON ] && echo "note: LSM_ARM_LTO=ON: the core is linked with link-time optimisation (fat objects: the archive figures are its plain code; skipped: $(sed -n 's/^LSM_ARM_LTO_SKIP:STRING=//p' "$BUILD/CMakeCache.txt"))"

echo "== no heap, no stdio"
# heap: malloc family and its reentrant forms, sbrk; stdio: the printf family and what it drags in
HEAP_RE='^_?(malloc|free|calloc|realloc|reallocf|memalign|valloc|pvalloc|sbrk|_malloc_r|_free_r|_calloc_r|_realloc_r|_memalign_r|_sbrk_r|__malloc_lock|_malloc_trim_r|_mallinfo_r)$'
STDIO_RE='^_?_?(printf|vprintf|fprintf|vfprintf|sprintf|vsprintf|snprintf|vsnprintf|asprintf|iprintf|fiprintf|siprintf|_printf_r|_vfprintf_r|_svfprintf_r|_vfiprintf_r|_svfiprintf_r|_printf_i|_printf_float|_sprintf_r|_snprintf_r|puts|_puts_r|fputs|_fputs_r|fwrite|_fwrite_r|putchar|_putchar_r|fflush|_fflush_r|__sfp|__sinit|__swsetup_r|__smakebuf_r|__sflush_r|__sfvwrite_r|_write_r)$'
for elf in "${ELFS[@]}"; do
    syms=$(arm-none-eabi-nm "$elf" | awk '{print $NF}')
    bad=$(grep -E "$HEAP_RE|$STDIO_RE" <<<"$syms" | sort -u | tr '\n' ' ')
    if [ -n "$bad" ]; then fail "heap-or-stdio-$(basename "$elf" .elf)"; echo "  $(basename "$elf"): $bad"
    else echo "ok: $(basename "$elf"): no heap or stdio symbols"; fi
done

echo "== no software double precision"
# AEABI double routines (__aeabi_dadd, __aeabi_dmul, __aeabi_d2f, __aeabi_f2d, __aeabi_i2d, ...), the
# libgcc names (__adddf3, __extendsfdf2, ...), and double libm functions (sin, sqrt, ...)
DBL_RE='^(__aeabi_d[a-z0-9]*|__aeabi_[a-z0-9]*2d|__[a-z]+df[0-9]|__extendsfdf2|__truncdfsf2|__fix[a-z]*df[a-z]*|__float[a-z]*df)$'
LIBM_D_RE='^(sin|cos|tan|asin|acos|atan|atan2|sinh|cosh|tanh|exp|exp2|expm1|log|log2|log10|log1p|pow|sqrt|cbrt|hypot|floor|ceil|round|lround|trunc|fmod|remainder|fabs|fmin|fmax|ldexp|frexp|modf|scalbn)$'
for elf in "${ELFS[@]}"; do
    syms=$(arm-none-eabi-nm "$elf" | awk '{print $NF}')
    bad=$(grep -E "$DBL_RE|$LIBM_D_RE" <<<"$syms" | sort -u | tr '\n' ' ')
    if [ -n "$bad" ]; then fail "double-$(basename "$elf" .elf)"; echo "  $(basename "$elf"): $bad"
    else echo "ok: $(basename "$elf"): no double-precision routines"; fi
done
warn=$(arm-none-eabi-nm --target=elf32-littlearm -A "${CORE[@]}" 2>/dev/null | awk 'NF > 1 && $(NF-1)=="U"{print $1" "$NF}' |
       grep -E " ($(sed 's/^\^//;s/\$$//' <<<"$DBL_RE")|$(sed 's/^\^//;s/\$$//' <<<"$LIBM_D_RE"))$" |
       sed -E 's#^.*\(?liblsm_[a-z]+_f\.a:##; s#:$##' | sort -u)
if [ -n "$warn" ]; then
    echo "WARNING: the float core refers to double-precision routines (slow on a single-precision FPU):"
    sed 's/^/  /' <<<"$warn"
else
    echo "ok: float core archive refers to no double-precision routine"
fi
info=$(arm-none-eabi-nm --target=elf32-littlearm -A "${CORE[@]}" 2>/dev/null | awk 'NF > 1 && $(NF-1)=="U"{print $1" "$NF}' |
       grep -E ' __aeabi_(ldivmod|uldivmod|l2f|ul2f|f2lz|f2ulz|llsl|llsr|lasr|lmul)$' |
       sed -E 's#^.*liblsm_[a-z]+_f\.a:##; s#:$##' | sort -u)
[ -n "$info" ] && { echo "note: 64-bit integer helpers (software routines) used by the float core:"; sed 's/^/  /' <<<"$info"; }

echo "== no fused multiply-add outside libm"
# VFMA/VFMS/VFNMA/VFNMS round once where the host rounds twice: the core must not use them (GCC keeps the
# -ffp-contract=off of -std=c11 per function, through link-time optimisation too; the cross build also says it).
# newlib's libm (sinf, cbrtf, ... in the bench) may: its functions are skipped.
LIBM=$(arm-none-eabi-gcc $(sed -n 's/^set(LSM_ARM_CPU_FLAGS "\(.*\)")$/\1/p' "$ROOT/cmake/arm-none-eabi.cmake") \
       -print-file-name=libm.a)
libm_fns=$(arm-none-eabi-nm --defined-only "$LIBM" 2>/dev/null | awk 'NF == 3 && $2 ~ /[TtWw]/ {print $3}' | sort -u)
for elf in "${ELFS[@]}"; do
    fused=$(arm-none-eabi-objdump -d "$elf" | awk '/^[0-9a-f]+ <.*>:$/ {f = substr($2, 2, length($2) - 3)}
                                                    /\tvfn?m[as]\./ {print f}' | sort -u |
            grep -vxF -f <(echo "$libm_fns") | tr '\n' ' ')
    if [ -n "$fused" ]; then fail "fused-fp-$(basename "$elf" .elf)"; echo "  $(basename "$elf"): $fused"
    else echo "ok: $(basename "$elf"): no fused multiply-add outside libm"; fi
done

echo "== QEMU mps2-an386 -icount shift=0 (timeout ${QEMU_TIMEOUT}s)"
run_image() {  # image, the line it must print (regex), expected exit status
    local img=$1 pass_line=$2 want_rc=${3:-0} elf=$BUILD/bin/$1.elf log=$BUILD/$1.qemu.log rc
    [ -f "$elf" ] || return
    local t0=$SECONDS
    timeout "$QEMU_TIMEOUT" qemu-system-arm -M mps2-an386 -cpu cortex-m4 -nographic -monitor none -serial none \
        -semihosting-config enable=on,target=native -icount shift=0 -kernel "$elf" >"$log" 2>&1
    rc=$?
    grep -v '^sample \|^contour_sample \|^check ok' "$log" | sed "s/^/  [$img] /"
    echo "  [$img] exit status $rc after $((SECONDS - t0)) s (full output: $log)"
    if [ $rc -eq 124 ]; then fail "$img-timeout"
    elif [ $rc -ne "$want_rc" ]; then fail "$img-exit-$rc"
    elif ! grep -qxE "$pass_line" "$log"; then fail "$img-no-pass-line"
    fi
}
run_image lissom-selftest "selftest PASS"
run_image lissom-contour "contour PASS"
run_image lissom-bench "bench PASS"
run_image lissom-faulttest "HardFault: pc=0x[0-9a-f]{8} .* bfar=0xf0000000" 99
# the controller image runs until it is stopped (scripts/mcu_node.sh): it must boot and print its ready line
# within 5 s, then it is stopped; the HIL suite (hil/run_hil_mcu.sh) tests it over CAN
if [ -f "$BUILD/bin/lissom-controller.elf" ]; then
    clog=$BUILD/lissom-controller.qemu.log
    timeout 5 qemu-system-arm -M mps2-an386 -cpu cortex-m4 -nographic -monitor none -serial null \
        -semihosting-config enable=on,target=native,arg=--node-id,arg=3 -icount shift=3,sleep=on \
        -kernel "$BUILD/bin/lissom-controller.elf" >"$clog" 2>&1
    sed "s/^/  [lissom-controller] /" "$clog" | grep -v "terminating on signal"
    grep -qE "^lissom-controller: ready node=3 " "$clog" || fail "lissom-controller-no-ready-line"
    ! grep -qE "HardFault|unexpected exception" "$clog" || fail "lissom-controller-fault"
fi

echo "== contour program: image vs host float build (same source, same float core)"
HOST=$HOST_BUILD/bin/lissom-contour-host
CLOG=$BUILD/lissom-contour.qemu.log
if [ "$host_built" != ok ]; then
    fail "$host_built"
elif [ ! -f "$CLOG" ]; then
    fail "contour-no-image-output"
else
    "$HOST" >"$BUILD/lissom-contour-host.log" 2>&1
    hrc=$?
    report() { grep -E '^(contour result=|contour_stats |contour_sample )' "$1"; }
    echo "  image: $(grep -E '^contour result=' "$CLOG")"
    echo "  host:  $(grep -E '^contour result=' "$BUILD/lissom-contour-host.log")"
    if [ $hrc -ne 0 ]; then
        fail "contour-host-exit-$hrc"
    elif [ -z "$(report "$CLOG")" ] || [ -z "$(report "$BUILD/lissom-contour-host.log")" ]; then
        fail "contour-no-report"
    elif ! diff <(report "$CLOG") <(report "$BUILD/lissom-contour-host.log") >"$BUILD/contour.diff"; then
        fail "contour-mismatch"; echo "  the image and the host differ (< image, > host):"; head -20 "$BUILD/contour.diff" | sed 's/^/    /'
    else
        echo "ok: contour report identical on the image and the host ($(report "$CLOG" | wc -l) lines: checksum, end point, stats, samples)"
    fi
fi

finish
