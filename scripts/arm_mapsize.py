#!/usr/bin/env python3
"""Flash and RAM of an ARM image by component, from its GNU ld map file (-Wl,-Map).

usage: arm_mapsize.py IMAGE.elf.map [...]

Every input section placed in the image is attributed to its archive (liblsm_plan_f.a, libm.a, ...) or object
file; with link-time optimisation (LSM_ARM_LTO) the link-time unit's output, which holds only the core, is one. Flash = .isr_vector + .text (code and constants) + .ARM.exidx + the initial values of .data;
RAM = .data + .bss. Prints one markdown table per image. Exit 2 if a map file cannot be read or parsed.
"""
import re
import sys
from collections import defaultdict
from pathlib import Path

FLASH_SECTIONS = {".isr_vector", ".text", ".ARM.exidx", ".ARM.extab"}
RAM_SECTIONS = {".bss"}
BOTH = {".data"}  # in RAM, and its initial values in flash

OUT_RE = re.compile(r"^(\.[A-Za-z0-9_.]+)\s+0x[0-9a-f]+\s+0x[0-9a-f]+")
IN_ONE_LINE = re.compile(r"^ (\.\S+|COMMON|\*fill\*)\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)(?:\s+(\S.*))?$")
IN_NAME_ONLY = re.compile(r"^ (\.\S+|COMMON)$")
IN_CONTINUED = re.compile(r"^\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S.*)$")


def component(path):
    m = re.search(r"([^/]+\.a)\(", path)
    if m:
        return m.group(1)
    if re.search(r"/cc\w+\.(ltrans\d+\.ltrans|lto)\.o$", path.strip()):
        return "core, link-time unit (LSM_ARM_LTO)"  # GCC's LTO output: only the core is compiled with -flto
    return Path(path.strip()).name


def parse(map_path):
    text = Path(map_path).read_text(errors="replace").splitlines()
    try:
        start = next(i for i, l in enumerate(text) if l.startswith("Linker script and memory map"))
    except StopIteration:
        raise SystemExit(f"arm_mapsize: {map_path}: not a GNU ld map file")
    sizes = defaultdict(lambda: [0, 0])  # component -> [flash, ram]
    out = None
    pending = False
    for line in text[start:]:
        m = OUT_RE.match(line)
        if m:
            out, pending = m.group(1), False
            continue
        if IN_NAME_ONLY.match(line):
            pending = True  # address, size and file follow on the next line
            continue
        m = IN_ONE_LINE.match(line)
        if m:
            size, where = int(m.group(3), 16), (m.group(4) or "")
            comp = "(alignment fill)" if m.group(1) == "*fill*" else component(where)
        else:
            m = IN_CONTINUED.match(line) if pending else None
            pending = False
            if not m:
                continue
            size, comp = int(m.group(2), 16), component(m.group(3))
        pending = False
        if out is None or size == 0:
            continue
        if out in FLASH_SECTIONS:
            sizes[comp][0] += size
        elif out in RAM_SECTIONS:
            sizes[comp][1] += size
        elif out in BOTH:
            sizes[comp][0] += size
            sizes[comp][1] += size
    return sizes


def main(argv):
    if len(argv) < 2:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    for map_path in argv[1:]:
        sizes = parse(map_path)
        name = Path(map_path).name.replace(".map", "")
        print(f"\n{name}: flash and RAM by component (bytes)\n")
        print("| component | flash | RAM |")
        print("|---|---:|---:|")
        tf = tr = 0
        for comp, (f, r) in sorted(sizes.items(), key=lambda kv: -kv[1][0]):
            print(f"| {comp} | {f} | {r} |")
            tf += f
            tr += r
        print(f"| **total** (without stack) | **{tf}** | **{tr}** |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
