#!/usr/bin/env python3
"""Redirect the calls to wrapped functions inside an LTO-linked Cortex-M image to their __wrap_ twins.

usage: arm_lto_wrap.py IMAGE.elf FUNCTION [FUNCTION ...]

Why: the bench images attribute instructions to a few calls of the core (lsm_corner_smooth, lsm_arcfit_fit,
lsm_planner_plan_piece, ...) by linking with -Wl,--wrap=FUNCTION (firmware/apps/cortex-m/bench_planner.c). With
link-time optimisation of the core (LSM_ARM_LTO) the calls between core objects are resolved inside the link-time
unit, so the linker's --wrap never sees them (GCC PR 88643) and the wrappers count nothing. The link still keeps
FUNCTION out of line and global (bench_planner.c refers to __real_FUNCTION), so this script does after the link
what --wrap does before it: every Thumb-2 BL / B.W to FUNCTION outside __wrap_FUNCTION is re-encoded to branch to
__wrap_FUNCTION (same length, nothing moves). It fails (exit 1, image unchanged) if FUNCTION or its wrapper is
missing, if a clone of FUNCTION exists (FUNCTION.constprop.0, .isra.0, .part.0: calls to it would be missed), if
FUNCTION's address is stored as data (a function pointer), if a call is of another form, or if no call reaches
__wrap_FUNCTION (calls from objects outside the link-time unit are wrapped by the linker as usual).
"""
import re
import subprocess
import sys

CLONE_RE = r"\.(constprop|isra|part|cold)\.\d+$"


def run(*cmd):
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def symbols(elf):
    """name -> address (Thumb bit cleared) of the function symbols."""
    out = {}
    for line in run("arm-none-eabi-nm", elf).splitlines():
        f = line.split()
        if len(f) == 3 and f[1] in "tTwW":
            out[f[2]] = int(f[0], 16) & ~1
    return out


def text_section(elf):
    """(vma, file offset, size) of .text."""
    for line in run("arm-none-eabi-objdump", "-h", elf).splitlines():
        f = line.split()
        if len(f) >= 6 and f[1] == ".text":
            return int(f[3], 16), int(f[5], 16), int(f[2], 16)
    raise SystemExit(f"arm_lto_wrap: {elf}: no .text section")


def branch(pc, target, link):
    """Thumb-2 BL (link) or B.W encoding T4 at pc to target, as 4 bytes (two little-endian halfwords)."""
    off = target - (pc + 4)
    if off % 2 or not -(1 << 24) <= off < (1 << 24):
        raise SystemExit(f"arm_lto_wrap: branch 0x{pc:x} -> 0x{target:x} out of range")
    s = (off >> 24) & 1
    i1, i2 = (off >> 23) & 1, (off >> 22) & 1
    j1, j2 = (1 - i1) ^ s, (1 - i2) ^ s
    hi = 0xF000 | (s << 10) | ((off >> 12) & 0x3FF)
    lo = (0xD000 if link else 0x9000) | (j1 << 13) | (j2 << 11) | ((off >> 1) & 0x7FF)
    return hi.to_bytes(2, "little") + lo.to_bytes(2, "little")


def main(argv):
    if len(argv) < 3:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    elf, funcs = argv[1], argv[2:]
    syms = symbols(elf)
    vma, foff, _ = text_section(elf)
    data = bytearray(open(elf, "rb").read())
    dis = run("arm-none-eabi-objdump", "-d", "--no-show-raw-insn", "-j", ".text", elf).splitlines()  # data as .word
    err = []
    patches = []
    for fn in funcs:
        if fn not in syms or "__wrap_" + fn not in syms:
            err.append(f"{fn} or __wrap_{fn} is not a function of the image")
            continue
        clones = [s for s in syms if re.fullmatch(re.escape(fn) + CLONE_RE, s)]
        if clones:
            err.append(f"{fn} has clones {clones}: their calls cannot be redirected")
        addr, wrap = syms[fn], syms["__wrap_" + fn]
        word = re.compile(r"^\s*[0-9a-f]+:\s+\.word\s+0x0*%x$" % (addr | 1))
        if any(word.match(line) for line in dis):
            err.append(f"the address of {fn} is stored as data (a function pointer?)")
        where, n, linked = None, 0, 0
        for line in dis:
            m = re.match(r"^([0-9a-f]+) <(\S+)>:$", line)
            if m:
                where = m.group(2)
                continue
            m = re.match(r"^\s*([0-9a-f]+):\s+(\S+)\s+([0-9a-f]+) <([^>]+)>", line)
            if m and int(m.group(3), 16) == wrap and m.group(4) == "__wrap_" + fn:
                linked += 1  # a call from outside the link-time unit, which --wrap redirected
                continue
            if not m or int(m.group(3), 16) != addr or m.group(4) != fn or where == "__wrap_" + fn:
                continue
            pc, op = int(m.group(1), 16), m.group(2)
            if op not in ("bl", "b.w"):
                err.append(f"0x{pc:x} in {where}: '{op}' to {fn} (only bl and b.w are redirected)")
                continue
            patches.append((pc, branch(pc, wrap, op == "bl")))
            n += 1
        if n + linked == 0:
            err.append(f"no call to {fn} found outside __wrap_{fn}")
        print(f"arm_lto_wrap: {elf.rsplit('/', 1)[-1]}: {n} call(s) of {fn} -> __wrap_{fn} ({linked} by the linker)")
    if err:
        for e in err:
            print(f"arm_lto_wrap: {elf}: {e}", file=sys.stderr)
        return 1
    for pc, code in patches:
        at = foff + pc - vma
        data[at:at + 4] = code
    with open(elf, "wb") as f:
        f.write(data)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
