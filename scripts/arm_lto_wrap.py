#!/usr/bin/env python3
"""Redirect the calls to wrapped functions inside an LTO-linked Cortex-M image to their __wrap_ twins.

usage: arm_lto_wrap.py IMAGE.elf FUNCTION [FUNCTION ...]

Why: the bench images attribute instructions to a few calls of the core (lsm_corner_smooth, lsm_arcfit_fit,
lsm_planner_plan_piece, ...) by linking with -Wl,--wrap=FUNCTION (firmware/apps/cortex-m/bench_planner.c). With
link-time optimisation of the core (LSM_ARM_LTO) the calls between core objects are resolved inside the link-time
unit, so the linker's --wrap never sees them (GCC PR 88643) and the wrappers count nothing. The link still keeps
FUNCTION out of line and global (bench_planner.c refers to __real_FUNCTION), so this script does after the link
what --wrap does before it: every Thumb-2 BL / B.W to FUNCTION from inside the link-time unit (address ranges from
IMAGE.elf.map) is re-encoded to branch to __wrap_FUNCTION (same length, nothing moves). It fails (exit 1, image unchanged) if FUNCTION or its wrapper is
missing, if a clone of FUNCTION exists (FUNCTION.constprop.0, .isra.0, .part.0: calls to it would be missed), if
FUNCTION's address is stored as data (a function pointer), if a call is of another form, if no call reaches
__wrap_FUNCTION (calls from objects outside the link-time unit are wrapped by the linker as usual), or if FUNCTION
may clobber fewer registers than the AAPCS allows (then its callers, compiled with -fipa-ra, may keep values in
registers the wrapper clobbers: FUNCTION must reach a function outside the link-time unit, or the wrapper must keep
every register but the result's, as the trampolines of bench_planner.c do). Reads IMAGE.elf.map.
"""
import re
import subprocess
import sys

CLONE_RE = r"\.(constprop|isra|part|cold)\.\d+$"
LTRANS_RE = re.compile(r"/cc\w+\.(ltrans\d+\.ltrans|lto)\.o$")


def unit_ranges(map_path):
    """[start, end) of every input section of the link-time unit, from the linker map."""
    out, name_only = [], False
    for line in open(map_path, errors="replace"):
        m = re.match(r"^ (\.\S+)\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S.*)$", line)
        if not m and name_only:
            m = re.match(r"^\s+()0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S.*)$", line)
        name_only = bool(re.match(r"^ \.\S+$", line))
        if m and LTRANS_RE.search(m.group(4).strip()):
            start = int(m.group(2), 16)
            out.append((start, start + int(m.group(3), 16)))
    return out


def keeps_registers(wrapper, dis):
    """True if wrapper starts as the register-keeping trampolines of bench_planner.c (BENCH_LTO_TRAMPOLINES): it
    pushes r1-r3 (and r0 if there is no result), r12 and s0-s15 before anything else, and pops them at its end."""
    body, inside = [], False
    for line in dis:
        if re.match(r"^[0-9a-f]+ <(\S+)>:$", line):
            inside = line.rstrip().endswith(f"<{wrapper}>:")
            continue
        if inside:
            m = re.match(r"^\s*[0-9a-f]+:\s+(.*\S)\s*$", line)
            if m:
                body.append(re.sub(r"\s+", " ", m.group(1)))
    regs = r"\{(r0, )?r1, r2, r3, r4, (r5, )?ip, %s\}"
    return len(body) >= 4 and re.fullmatch(r"(push|stmdb sp!,) " + regs % "lr", body[0]) is not None \
        and body[1] == "vpush {s0-s15}" and "vpop {s0-s15}" in body \
        and any(re.fullmatch(r"(pop|ldmia(\.w)? sp!,) " + regs % "pc", b) for b in body)


def clobbers_all(fn, dis, syms, unit):
    """True if fn surely clobbers every register the AAPCS lets a call clobber: it reaches (through direct calls
    and tail calls) a function outside the link-time unit or an indirect call. Then GCC's interprocedural register
    allocation (-fipa-ra), which lets a caller keep values in the call-clobbered registers its callee does not
    touch, cannot have used a smaller clobber set for fn, and a call of fn may go to another AAPCS function."""
    calls, where = {}, None
    for line in dis:
        m = re.match(r"^([0-9a-f]+) <(\S+)>:$", line)
        if m:
            where = m.group(2)
            calls.setdefault(where, set())
            continue
        if where is None:
            continue
        m = re.match(r"^\s*[0-9a-f]+:\s+(bl|blx|b\.w|b\.n|b|b[a-z]{2}\.w|bx)\s+(\S+)(?: <([^>+]+)>)?", line)
        if not m:
            continue
        op, arg, target = m.group(1), m.group(2), m.group(3)
        if op in ("blx", "bx") and arg != "lr":
            calls[where].add(None)  # indirect: unknown callee
        elif target and target != where and target in syms:
            calls[where].add(target)
    in_unit = lambda f: any(a <= syms[f] < b for a, b in unit)
    seen, todo = set(), [fn]
    while todo:
        f = todo.pop()
        if f in seen:
            continue
        seen.add(f)
        for g in calls.get(f, ()):
            if g is None or not in_unit(g):
                return True
            todo.append(g)
    return False


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
    unit = unit_ranges(elf + ".map")
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
        if any(a <= addr < b for a, b in unit) and not clobbers_all(fn, dis, syms, unit) and \
                not keeps_registers("__wrap_" + fn, dis):
            err.append(f"{fn} may clobber fewer registers than a call may (-fipa-ra): its callers may keep values "
                       "in registers the wrapper clobbers")
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
            if not m or int(m.group(3), 16) != addr or m.group(4) != fn:
                continue
            pc, op = int(m.group(1), 16), m.group(2)
            if not any(a <= pc < b for a, b in unit):
                continue  # a call from outside the link-time unit: the wrapper's own, or one --wrap already saw
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
