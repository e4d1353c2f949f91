# CMake toolchain file: bare-metal Cortex-M4F (arm-none-eabi-gcc, newlib-nano, hard float).
# Used by the `cortex-m4f` preset (build-arm/). The top CMakeLists.txt sees CMAKE_CROSSCOMPILING and then
# skips host_sim and the tests and builds the float core `lsm_core_f`, the port template and the images of
# firmware/port/cortex-m (QEMU mps2-an386).
#
# Flags: Cortex-M4 with the single-precision FPU (fpv4-sp-d16), hard-float ABI, Thumb-2; each function and
# object in its own section so that --gc-sections drops what an image does not use. No -ffreestanding:
# the core uses <math.h> (sqrtf, sinf ...) and we want GCC to inline sqrtf/fabsf as VSQRT/VABS.
# -ffp-contract=off: no fused multiply-add (VFMA rounds once, the host twice), as -std=c11 already implies; said
# here so that it holds for every object and through link-time optimisation (LSM_ARM_LTO,
# firmware/apps/cortex-m/CMakeLists.txt; scripts/arm_check.sh checks the images). gcc-ar / gcc-ranlib: the
# archives of an LTO build hold LTO objects, which need the LTO plugin for their symbol index.
# Images link with -nostartfiles (our own startup code in firmware/port/cortex-m/startup.c) and
# newlib-nano's libc/libm; scripts/arm_check.sh verifies that no heap or stdio gets linked.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_ASM_COMPILER arm-none-eabi-gcc)
set(CMAKE_AR arm-none-eabi-gcc-ar CACHE FILEPATH "archiver")
set(CMAKE_RANLIB arm-none-eabi-gcc-ranlib CACHE FILEPATH "ranlib")
set(CMAKE_OBJCOPY arm-none-eabi-objcopy CACHE FILEPATH "objcopy")
set(CMAKE_SIZE arm-none-eabi-size CACHE FILEPATH "size")

# try_compile cannot link a bare-metal executable without a linker script: test with a static library.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(LSM_ARM_CPU_FLAGS "-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16")
set(CMAKE_C_FLAGS_INIT "${LSM_ARM_CPU_FLAGS} -ffunction-sections -fdata-sections -ffp-contract=off")
set(CMAKE_ASM_FLAGS_INIT "${LSM_ARM_CPU_FLAGS}")
set(CMAKE_EXE_LINKER_FLAGS_INIT "-nostartfiles --specs=nano.specs -Wl,--gc-sections")

# Look for programs on the host, for libraries and headers only in the target root.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
