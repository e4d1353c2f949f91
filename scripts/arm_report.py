#!/usr/bin/env python3
"""Markdown report of the Cortex-M4F figures of issue 7 (planner, interpolator, memory) against their goals.

usage: arm_report.py BENCH_LOG CONTOUR_LOG CONTOUR_MAP [--ramp RAMP_LOG] [--gcc VERSION] [--build-type TYPE]
       arm_report.py --json BENCH_LOG CONTOUR_MAP     one JSON object of the issue-12 figures (scripts/arm_bench.sh)

BENCH_LOG: output of lissom-bench.elf ("bench", "size", "note" lines, bench_main.c / bench_planner.c);
CONTOUR_LOG: output of lissom-contour.elf (stack high-water mark, checksum); CONTOUR_MAP: its linker map, whose
core objects (the component archives liblsm_<component>_f.a; with LSM_ARM_LTO also the link-time unit's output, which
holds only core objects) are the flash of the core with a 128-block look-ahead (the image links only what
the planner, the interpolator and the contour program need). RAMP_LOG: output of lissom-bench-ramp.elf (the
planner's ramp sizing and phase evaluation inside appends). scripts/arm_report.sh builds and runs everything
and calls this. Exit 2 if an input is missing or lacks a figure.
"""
import argparse
import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import arm_mapsize  # noqa: E402

GOAL_CYCLE = 600        # instructions per cycle, 3 axes, arc or clothoid
GOAL_APPEND = 20000     # instructions per appended block
GOAL_BLOCK_RAM = 96     # bytes per look-ahead block
GOAL_FLASH = 32 * 1024  # bytes of core flash


def parse_bench(text):
    bench, size, note = {}, {}, {}
    for line in text.splitlines():
        f = line.split()
        if len(f) >= 4 and f[0] == "bench" and f[2] != "NA":
            d = {"value": float(f[2]), "unit": f[3]}
            for kv in f[4:]:
                if "=" in kv:
                    k, v = kv.split("=", 1)
                    d[k] = v
            bench[f[1]] = d
        elif len(f) == 3 and f[0] == "size":
            size[f[1]] = int(f[2])
        elif f and f[0] == "note":
            for kv in f[1:]:
                k, v = kv.split("=", 1)
                note[k] = v
    return bench, size, note


def core_objects(map_path):
    """Flash/RAM per object of the core (liblsm_<component>_f.a), and per other component, in the image of map_path."""
    orig = arm_mapsize.component

    def comp(path):
        m = re.search(r"liblsm_[a-z]+_f\.a\((\S+?)(\.obj|\.o)?\)", path)
        if m:
            return "core:" + m.group(1)
        # LSM_ARM_LTO: the core is compiled for link-time optimisation and nothing else is (the apps and the board
        # support are not), so the link-time unit's output objects (/tmp/ccXXXX.ltrans0.ltrans.o) are the core
        if re.search(r"/cc\w+\.(ltrans\d+\.ltrans|lto)\.o$", path.strip()):
            return "core:(link-time unit)"
        return orig(path)

    arm_mapsize.component = comp
    try:
        return arm_mapsize.parse(map_path)
    finally:
        arm_mapsize.component = orig


def n(x):
    """Thousands separated by a thin space, as in docs/cortex_m.md."""
    return f"{int(round(x)):,}".replace(",", " ")


def status(value, goal):
    if value <= goal:
        return "**met**"
    return f"**missed** (x{value / goal:.1f})"


def main(argv):
    ap_ = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap_.add_argument("bench_log")
    ap_.add_argument("contour_log")
    ap_.add_argument("contour_map")
    ap_.add_argument("--ramp", help="output of lissom-bench-ramp.elf")
    ap_.add_argument("--gcc", default="?")
    ap_.add_argument("--build-type", default="?")
    ap_.add_argument("--size", help="arm-none-eabi-size line of lissom-contour.elf (text data bss dec hex name)")
    args = ap_.parse_args(argv[1:])
    try:
        bench, size, note = parse_bench(Path(args.bench_log).read_text())
        contour = Path(args.contour_log).read_text()
        ramp = parse_bench(Path(args.ramp).read_text())[0] if args.ramp else {}
    except OSError as e:
        print(f"arm_report: {e}", file=sys.stderr)
        return 2
    objs = core_objects(args.contour_map)
    gcc, btype = args.gcc, args.build_type

    def b(name):
        if name not in bench:
            raise SystemExit(f"arm_report: no figure '{name}' in {args.bench_log}")
        return bench[name]

    m = re.search(r"stack_used_bytes=(\d+)", contour)
    stack = int(m.group(1)) if m else None
    m = re.search(r"^contour result=.*checksum=(0x[0-9a-f]+)", contour, re.M)
    checksum = m.group(1) if m else "?"

    out = []
    p = out.append
    p(f"Cortex-M4F float core, arm-none-eabi-gcc {gcc}, {btype} build, QEMU mps2-an386 `-icount shift=0` "
      "(instructions = 40 x SysTick counts, harness subtracted), 128-block look-ahead, 1 ms cycle. "
      "Instructions, not clock cycles. Regenerate: `scripts/arm_report.sh`.")
    p("")
    p("**Interpolator, per control cycle** (`lsm_interp_step`). Pieces are planned between cycles by "
      "`lsm_interp_prepare` (background work, below); a cycle only evaluates, and takes a prepared piece where "
      "it starts. A cycle that finds none prepared plans it itself: those cycles are counted apart (the last "
      "column; 0 means the cycle never planned). Worst single cycles are read one by one (±40).")
    p("")
    at = {"block_entry": " (block entry)", "piece_switch": " (piece switch)",
          "block_entry_and_piece": " (block entry and piece switch)"}
    p("| block | axes | mean | worst cycle | cycles (of which planned a piece) |")
    p("|---|---:|---:|---:|---:|")
    for kind, axes in (("line", 1), ("line", 3), ("line", 6), ("arc", 3), ("arc", 6), ("clothoid", 3),
                       ("clothoid", 6)):
        a, q = b(f"interp_{kind}_{axes}ax"), b(f"interp_{kind}_{axes}ax_noplan")
        where = at.get(q.get("max_at"), "") if a["calls"] == q["calls"] else " (plans a piece)"
        p(f"| {kind} | {axes} | {n(a['value'])} | {n(int(a['max']))}{where} | "
          f"{a['calls']} ({int(a['calls']) - int(q['calls'])}) |")
    p("")
    p("1 axis: X lines (collinear joins, reversals); 3 axes: the contour program (`firmware/apps/contour`); "
      "6 axes: lines moving all six axes, and the contour with A B C configured (arcs and corner blends are "
      "X Y Z only, so A B C stand still there).")
    p("")
    ap = b("planner_append")
    worst = dict(kv.split(":") for kv in ap.get("max_at", "corner:0,fit:0").split(","))
    wc, wf = int(worst.get("corner", 0)), int(worst.get("fit", 0))
    wmax = int(ap["max"])
    p(f"**Planner, per appended block** (`lsm_planner_append_line` / `_arc`: validation, arc fitting of dense "
      f"polylines, corner smoothing, block set-up and the backward pass of the look-ahead), over "
      f"{ap['calls']} blocks of a dense program (0.1-0.5 mm polyline segments, a zigzag with 0.8 rad corners, "
      f"R 2 half circles joined by lines at 0.3 rad corners), with the buffer kept full:")
    p("")
    p("| part | mean per appended block | in the worst append |")
    p("|---|---:|---:|")
    p(f"| **total** | **{n(ap['value'])}** | **{n(wmax)}** |")
    p(f"| corner smoothing (`lsm_corner_smooth`) | {n(b('planner_append_corner_smoothing')['value'])} | {n(wc)} |")
    p(f"| arc fitting (`lsm_arcfit_fit`) | {n(b('planner_append_arc_fit')['value'])} | {n(wf)} |")
    p(f"| rest: validation, block set-up (bounds, coefficients), **backward pass** | "
      f"{n(b('planner_append_rest')['value'])} | {n(max(wmax - wc - wf, 0))} |")
    if "planner_append_ramp_sizing" in ramp and "planner_append_phase_eval" in ramp:
        rs, pe = ramp["planner_append_ramp_sizing"], ramp["planner_append_phase_eval"]
        si, pv = ramp["scurve_strict_intervals_in_append"], ramp["phase_eval_in_append"]
        nb = int(rs["calls"])
        p(f"| ... of which ramp sizing (`lsm_scurve_strict_intervals`, {int(si['calls']) / nb:.0f} calls of "
          f"{n(si['value'])}) | {n(rs['value'])} | |")
        p(f"| ... of which phase evaluation for ramp verification (`lsm_phase_end` / `_advance`, "
          f"{int(pv['calls']) / nb:.0f} calls of {n(pv['value'])}) | {n(pe['value'])} | |")
        p(f"| ... the rest of the backward pass and block set-up (planner.c's own code) | "
          f"{n(b('planner_append_rest')['value'] - rs['value'] - pe['value'])} | |")
    cats = [("dense polyline point", "planner_append_dense_point"), ("zigzag line (corner)", "planner_append_zigzag_line"),
            ("half circle or the line after it", "planner_append_arc_or_line")]
    if all(k in bench for _, k in cats):
        p("| by item: " + "; ".join(f"{t} {n(b(k)['value'])} (worst {n(int(b(k)['max']))}, {b(k)['calls']} blocks)"
                                     for t, k in cats) + " | | |")
    if ramp:
        p("")
        p("Ramp sizing and phase evaluation come from `lissom-bench-ramp.elf`, the same append run with these "
          "calls wrapped too (separate image: the wrappers would add instructions to the other figures).")
    p("")
    cs, af, pp, fp = b("corner_smooth"), b("arcfit_fit"), b("planner_plan_piece"), b("planner_full_backward_pass")
    p("| call | mean | worst | calls |")
    p("|---|---:|---:|---:|")
    p(f"| `lsm_corner_smooth` | {n(cs['value'])} | {n(int(cs['max']))} | {cs['calls']} |")
    p(f"| `lsm_arcfit_fit` | {n(af['value'])} | {n(int(af['max']))} | {af['calls']} |")
    if "clothoid_step" in bench:
        p(f"| `lsm_clothoid_step` (the clothoid stepper alone, 0.1 mm steps) | {n(b('clothoid_step')['value'])} | "
          f"| {b('clothoid_step')['calls']} |")
    p(f"| `lsm_planner_plan_piece` (per piece: background work of `lsm_interp_prepare`) | {n(pp['value'])} | "
      f"{n(int(pp['max']))} | {pp['calls']} |")
    p(f"| full backward pass, {note.get('full_pass_blocks', '?')} blocks (`full_pass`, `lsm_planner_update`) | "
      f"{n(fp['value'])} | | 1 |")
    p("")
    p(f"Backward pass work per appended block: {note.get('append_bp_nodes_per_block', '?')} node evaluations, "
      f"{note.get('append_checks_per_block', '?')} ramp verifications (planner stats).")
    p("")
    sc = b("scurve_plan")
    p(f"**S-curve plan** (`lsm_scurve_plan`, strict rule, 8 cases): {n(sc['value'])} instructions per plan.")
    p("")
    core = {k[5:]: v for k, v in objs.items() if k.startswith("core:")}
    core_flash = sum(v[0] for v in core.values())
    core_ram = sum(v[1] for v in core.values())
    libm = objs.get("libm.a", [0, 0])[0]
    libc = objs.get("libc_nano.a", [0, 0])[0]
    p("**Memory** (float build):")
    p("")
    p("| item | bytes |")
    p("|---|---:|")
    p(f"| RAM per look-ahead block, `sizeof(lsm_pblock)` | {size.get('lsm_pblock', '?')} |")
    p(f"| `lsm_planner` / `lsm_interp` (of which `lsm_piece`) | {size.get('lsm_planner', '?')} / "
      f"{size.get('lsm_interp', '?')} ({size.get('lsm_piece', '?')}) |")
    p(f"| RAM of a 128-block look-ahead: 128 blocks + planner + interpolator | "
      f"{n(size.get('lookahead_128_blocks', 0))} |")
    p(f"| stack high-water mark of the contour image (main loop + SysTick handler with FPU context) | "
      f"{n(stack) if stack is not None else '?'} |")
    lto = "(link-time unit)" in core
    how = ("; link-time optimised: the link-time unit, which holds only core objects, and the core objects "
           "outside it" if lto else "")
    p(f"| core flash, the core archives (`liblsm_*_f.a`) as linked into `lissom-contour.elf` (`--gc-sections`{how}) "
      f"| **{n(core_flash)}** |")
    p(f"| + newlib libm / libc (`memcpy`, `memset`, `floorf`, `ceilf`, ...) | {n(libm)} / {n(libc)} |")
    p(f"| core static RAM (.data + .bss of the core) | {core_ram} |")
    if args.size:
        f = args.size.split()
        p(f"| whole `lissom-contour.elf` (`arm-none-eabi-size`: text / data / bss; bss = look-ahead, samples, "
          f"port) | {n(int(f[0]))} / {n(int(f[1]))} / {n(int(f[2]))} |")
    p("")
    p("Core flash per object (`lissom-contour.elf`" + (", LTO: its link-time unit is one part; per object: "
                                                        "configure with `-DLSM_ARM_LTO=OFF`" if lto else "") + "): " + ", ".join(
        f"{k} {n(v[0])}" for k, v in sorted(core.items(), key=lambda kv: -kv[1][0])) + ".")
    p("")
    p("**Goals** (issue 7):")
    p("")
    p("| goal | measured | status |")
    p("|---|---|---|")
    for kind in ("arc", "clothoid"):
        q, a = b(f"interp_{kind}_3ax_noplan"), b(f"interp_{kind}_3ax")
        planned = int(a["calls"]) - int(q["calls"])
        p(f"| <= {GOAL_CYCLE} instructions per cycle, 3 axes, {kind} | mean {n(a['value'])}, worst "
          f"{n(int(a['max']))} ({planned} cycles planned a piece) | {status(a['value'], GOAL_CYCLE)} (mean), "
          f"worst x{int(a['max']) / GOAL_CYCLE:.1f} |")
    p(f"| <= {n(GOAL_APPEND)} instructions per appended block | mean {n(ap['value'])}, worst {n(wmax)} | "
      f"{status(ap['value'], GOAL_APPEND)} (mean) |")
    p(f"| <= {GOAL_BLOCK_RAM} B RAM per block | {size.get('lsm_pblock', '?')} B | "
      f"{status(size.get('lsm_pblock', 10 ** 9), GOAL_BLOCK_RAM)} |")
    p(f"| core flash <= 32 KB | {n(core_flash)} B ({core_flash / 1024:.1f} KB), {n(core_flash + libm + libc)} B "
      f"with libm and libc | {status(core_flash, GOAL_FLASH)} |")
    p("")
    p(f"Contour checksum (image = host float build): `{checksum}`.")
    print("\n".join(out))
    return 0


def json_figures(bench_log, contour_map):
    """The issue-12 cost figures as one JSON object: per-cycle instructions (3 axes: line, arc, clothoid), per
    appended block and per prepared piece on the dense benchmark (mean, max), core flash as linked into
    lissom-contour.elf, RAM per look-ahead block."""
    import json
    try:
        bench, size, _ = parse_bench(Path(bench_log).read_text())
    except OSError as e:
        print(f"arm_report: {e}", file=sys.stderr)
        return 2
    objs = core_objects(contour_map)

    def b(name, key="value"):
        if name not in bench or (key != "value" and key not in bench[name]):
            raise SystemExit(f"arm_report: no figure '{name}' ({key}) in {bench_log}")
        v = bench[name][key]
        return round(float(v), 1)

    out = {
        "cycle_instructions_line": b("interp_line_3ax"),
        "cycle_instructions_arc": b("interp_arc_3ax"),
        "cycle_instructions_clothoid": b("interp_clothoid_3ax"),
        "append_instructions_mean": b("planner_append"),
        "append_instructions_max": b("planner_append", "max"),
        "piece_instructions_mean": b("planner_plan_piece"),
        "piece_instructions_max": b("planner_plan_piece", "max"),
        "core_flash_bytes": sum(v[0] for k, v in objs.items() if k.startswith("core:")),
        "ram_bytes_per_block": size.get("lsm_pblock"),
    }
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "--json":
        sys.exit(json_figures(sys.argv[2], sys.argv[3]))
    sys.exit(main(sys.argv))
