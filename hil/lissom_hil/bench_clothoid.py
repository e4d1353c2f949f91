"""Benchmark: Lissom's clothoid corner smoothing and incremental stepping, against pyclothoids, in one run.

    python -m lissom_hil.bench_clothoid [--sim build/bin/lissom-sim] [--corners 2000] [--seed 1] [--qemu]

Host part. `lissom-sim bench-clothoid` smooths a seeded random set of corners (line-line in 3-D, line-arc,
arc-line, arc-arc; see host_sim/cmd_bench_clothoid.c) and times an incremental clothoid step and a direct
evaluation. It writes, per smoothed corner, the end states of the transition (in its own plane); this script
then times pyclothoids' G1 fit (Clothoid.G1Hermite: one clothoid between two points with given tangents,
Bertolazzi-Frego) on exactly those end states, and pyclothoids' point evaluation, so the figures compare like
with like on the same machine in the same run. Note what differs: the G1 fit solves a smaller problem (no
curvature continuity, no tolerance search) and pays the Python call overhead; Lissom's figure is the whole
G2 corner (geometry, Newton, deviation search).

--qemu: also builds a Cortex-M4F image of the float core with a small benchmark main (embedded below) and runs
it under QEMU mps2-an386 with -icount shift=0 (1 instruction = 1 ns, SysTick counts 40 instructions), like
the project's firmware/port/cortex-m bench: instructions per corner (named cases and a random set per kind:
mean and max) and per incremental step. Needs arm-none-eabi-gcc and qemu-system-arm.

This is a benchmark, not a test: host timings vary from machine to machine; instruction counts are exact for
a given compiler.
"""
import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))


def default_sim():
    return os.environ.get("LISSOM_SIM") or os.path.join(ROOT, "build", "bin", "lissom-sim")


def lissom_bench(sim, corners, seed, csv_path):
    out = subprocess.run([sim, "bench-clothoid", "--corners", str(corners), "--seed", str(seed), "--corners-out",
                          csv_path, "--json"], check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def pyclothoids_bench(csv_path, repeat=3):
    from pyclothoids import Clothoid
    rows = []
    with open(csv_path, newline="") as f:
        for r in csv.DictReader(f):
            rows.append(tuple(float(r[k]) for k in ("x0", "y0", "theta0", "x1", "y1", "theta1")))
    best = float("inf")
    ok = 0
    for _ in range(repeat):
        t0 = time.perf_counter()
        for x0, y0, t0_, x1, y1, t1 in rows:
            Clothoid.G1Hermite(x0, y0, t0_, x1, y1, t1)
        best = min(best, (time.perf_counter() - t0) / max(len(rows), 1))
    # how close the single G1 clothoid comes to the end points (sanity: the problem is the same)
    for x0, y0, t0_, x1, y1, t1 in rows[:200]:
        c = Clothoid.G1Hermite(x0, y0, t0_, x1, y1, t1)
        if abs(c.XEnd - x1) < 1e-6 and abs(c.YEnd - y1) < 1e-6:
            ok += 1
    # point evaluation of a clothoid (pyclothoids: one call per coordinate)
    c = Clothoid.StandardParams(0.0, 0.0, 0.3, 0.02, 0.004, 200.0)
    n = 20000
    t0 = time.perf_counter()
    for i in range(n):
        s = 0.01 * i
        c.X(s), c.Y(s)
    t_eval = (time.perf_counter() - t0) / n
    return {"corners": len(rows), "ns_per_g1_fit": best * 1e9, "g1_fits_checked": min(len(rows), 200),
            "g1_fits_reaching_end": ok, "ns_per_point_eval": t_eval * 1e9}


ARM_MAIN = r'''
#include <stdint.h>
#include "cm_board.h"
#include "cm_out.h"
#include "cm_semihost.h"
#include "clothoid.h"
#include "corner.h"
#include "lsm_math.h"

static inline uint32_t now(void) { return CM_SYST_CVR; }
static uint32_t counts(uint32_t t0, uint32_t t1) { return (t0 - t1) & CM_SYST_MAX_RELOAD; }
static lsm_corner_result g_res;
static volatile int g_st;
static void out(const char *name, uint32_t insns_x10, const char *unit)
{
    cm_out_str("bench "); cm_out_str(name); cm_out_char(' ');
    cm_out_fixed((int32_t)insns_x10, 1); cm_out_char(' '); cm_out_str(unit); cm_out_char('\n');
}
static uint32_t g_seed = 12345u;
static float rnd(float a, float b) { g_seed = g_seed * 1664525u + 1013904223u; return a + (b - a) * (float)(g_seed >> 8) * (1.0f / 16777216.0f); }
static void line(lsm_geom *g, float x0, float y0, float x1, float y1)
{
    lsm_real p[6] = {x0, y0, 0, 0, 0, 0}, q[6] = {x1, y1, 0, 0, 0, 0};
    (void)lsm_geom_line_init(g, p, q);
}
/* arc through (vx, vy) with tangent angle a there, radius r, turning t; ending there if at_end */
static void arc(lsm_geom *g, float vx, float vy, float a, float r, float t, int at_end)
{
    const float s = t > 0 ? 1.0f : -1.0f;
    const float cx = vx - s * r * lsm_math_sinf(a), cy = vy + s * r * lsm_math_cosf(a);
    const float a0 = lsm_math_atan2f(vy - cy, vx - cx), a1 = at_end ? a0 - t : a0 + t;
    lsm_real v[3] = {vx, vy, 0}, o[3] = {cx + r * lsm_math_cosf(a1), cy + r * lsm_math_sinf(a1), 0}, c[3] = {cx, cy, 0};
    if (at_end) (void)lsm_geom_arc_init(g, o, v, c, LSM_GEOM_PLANE_XY, t > 0 ? 1 : -1, 0);
    else (void)lsm_geom_arc_init(g, v, o, c, LSM_GEOM_PLANE_XY, t > 0 ? 1 : -1, 0);
}
static uint32_t one(const lsm_geom *b1, const lsm_geom *b2, float eps)
{
    lsm_corner_params p = {eps, 0, 0};
    const uint32_t t0 = now();
    g_st = lsm_corner_smooth(b1, b2, &p, &g_res);
    return counts(t0, now());
}
int main(void)
{
    CM_SYST_RVR = CM_SYST_MAX_RELOAD; CM_SYST_CVR = 0; CM_SYST_CSR = CM_SYST_CSR_ENABLE | CM_SYST_CSR_CLKSOURCE;
    const uint32_t c0 = counts(now(), now()); /* reading overhead, in counts (0 or 1) */
    (void)c0;
    lsm_geom b1, b2;
    /* named cases */
    line(&b1, 0, 0, 10, 0); line(&b2, 10, 0, 10, 10);
    out("corner_line_line_90deg", one(&b1, &b2, 0.01f) * 400u, "corner");
    arc(&b2, 10, 0, 0, 10, 1.5f, 0);
    out("corner_line_arc_tangent", one(&b1, &b2, 0.01f) * 400u, "corner");
    arc(&b2, 10, 0, 0.785f, 7, 1.5f, 0);
    out("corner_line_arc_45deg", one(&b1, &b2, 0.01f) * 400u, "corner");
    arc(&b1, 10, 0, 0, 5, -1.5f, 1); arc(&b2, 10, 0, 0, 5, 1.5f, 0);
    out("corner_arc_arc_s_tangent", one(&b1, &b2, 0.01f) * 400u, "corner");
    /* random sets per kind: deflection 1..179 deg, radii 2..200 mm, tolerance 0.002..0.2 mm */
    static const char *names[4] = {"random_line_line", "random_line_arc", "random_arc_line", "random_arc_arc"};
    for (int kind = 0; kind < 4; kind++) {
        uint64_t sum = 0; uint32_t mx = 0, n = 0, fails = 0;
        for (int i = 0; i < 64; i++) {
            const float a = rnd(-3.1f, 3.1f), d = rnd(0.0175f, 3.12f) * (rnd(0, 1) < 0.5f ? -1.0f : 1.0f);
            const float r1 = rnd(2, 200), r2 = rnd(2, 200), l1 = rnd(2, 40), l2 = rnd(2, 40);
            const float eps = rnd(0.002f, 0.2f);
            const float t1 = (rnd(0, 1) < 0.5f ? -1.0f : 1.0f) * (l1 / r1 < 2 ? l1 / r1 : 2);
            const float t2 = (rnd(0, 1) < 0.5f ? -1.0f : 1.0f) * (l2 / r2 < 2 ? l2 / r2 : 2);
            if (kind >= 2) arc(&b1, 0, 0, a, r1, t1, 1);
            else line(&b1, -l1 * lsm_math_cosf(a), -l1 * lsm_math_sinf(a), 0, 0);
            if (kind == 1 || kind == 3) arc(&b2, 0, 0, a + d, r2, t2, 0);
            else line(&b2, 0, 0, l2 * lsm_math_cosf(a + d), l2 * lsm_math_sinf(a + d));
            const uint32_t c = one(&b1, &b2, eps);
            if (g_st != LSM_OK) { fails++; continue; }
            sum += c; n++; if (c > mx) mx = c;
        }
        out(names[kind], n ? (uint32_t)(sum * 400u / n) : 0u, "corner_mean");
        cm_out_str("   max "); cm_out_u32(mx * 40u); cm_out_str(" failed "); cm_out_u32(fails); cm_out_char('\n');
    }
    /* incremental step and direct evaluation */
    lsm_clothoid cl; lsm_clothoid_init(&cl, 0, 0, 0.3f, 0.02f, 0.004f, 1000.0f);
    static lsm_clothoid_stepper sp; lsm_clothoid_stepper_init(&sp, &cl, 0, 256);
    lsm_clothoid_state s;
    uint32_t t0 = now();
    for (int k = 0; k < 2000; k++) lsm_clothoid_step(&sp, 0.05f, &s);
    out("clothoid_step_anchor_256", counts(t0, now()) * 400u / 2000u, "step");
    lsm_clothoid_stepper_init(&sp, &cl, 0, 0);
    t0 = now();
    for (int k = 0; k < 2000; k++) lsm_clothoid_step(&sp, 0.05f, &s);
    out("clothoid_step_no_anchor", counts(t0, now()) * 400u / 2000u, "step");
    t0 = now();
    for (int k = 0; k < 256; k++) lsm_clothoid_eval(&cl, 0.05f * (float)k, &s);
    out("clothoid_eval", counts(t0, now()) * 400u / 256u, "call");
    cm_out_str("sizeof lsm_geom "); cm_out_u32((uint32_t)sizeof(lsm_geom));
    cm_out_str(" lsm_corner_result "); cm_out_u32((uint32_t)sizeof(lsm_corner_result));
    cm_out_str(" lsm_clothoid_stepper "); cm_out_u32((uint32_t)sizeof(lsm_clothoid_stepper)); cm_out_char('\n');
    cm_out_str("bench PASS\n");
    cm_out_flush();
    cm_semihost_exit(0);
}
'''


def arm_bench(timeout=120):
    gcc, qemu = shutil.which("arm-none-eabi-gcc"), shutil.which("qemu-system-arm")
    if not gcc or not qemu:
        return {"error": "arm-none-eabi-gcc or qemu-system-arm not found"}
    fw = os.path.join(ROOT, "firmware")
    cm = os.path.join(fw, "port", "cortex-m")
    cf = ["-mcpu=cortex-m4", "-mthumb", "-mfloat-abi=hard", "-mfpu=fpv4-sp-d16", "-Os", "-ffreestanding",
          "-ffunction-sections", "-fdata-sections", "-DLSM_REAL_FLOAT=1", "-std=c11", "-Wall",
          "-Werror=implicit-function-declaration", "-I" + fw, "-I" + cm]
    srcs = [os.path.join(fw, f + ".c") for f in ("clothoid", "corner", "geom", "status", "lsm_math")]
    srcs += [os.path.join(cm, f + ".c") for f in ("startup", "cm_semihost", "cm_out")]
    with tempfile.TemporaryDirectory() as d:
        main = os.path.join(d, "bench_clothoid_main.c")
        with open(main, "w") as f:
            f.write(ARM_MAIN)
        elf = os.path.join(d, "bench.elf")
        cmd = [gcc, *cf, "-nostartfiles", "--specs=nano.specs", "-T", os.path.join(cm, "mps2_an386.ld"),
               "-Wl,--gc-sections", main, *srcs, "-lm", "-o", elf]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0:
            return {"error": "build failed: " + p.stderr[-2000:]}
        p = subprocess.run([qemu, "-M", "mps2-an386", "-cpu", "cortex-m4", "-nographic", "-monitor", "none",
                            "-serial", "none", "-semihosting-config", "enable=on,target=native", "-icount",
                            "shift=0", "-kernel", elf], capture_output=True, text=True, timeout=timeout)
        text = p.stdout + p.stderr
        res = {"raw": text.strip().splitlines()}
        for line in text.splitlines():
            w = line.split()
            if len(w) >= 4 and w[0] == "bench":
                res[w[1]] = float(w[2])
        res["ok"] = "bench PASS" in text
        return res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sim", default=default_sim())
    ap.add_argument("--corners", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--qemu", action="store_true", help="also count Cortex-M4F instructions under QEMU")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "corners.csv")
        lis = lissom_bench(a.sim, a.corners, a.seed, path)
        try:
            pyc = pyclothoids_bench(path)
        except ImportError:
            pyc = {"error": "pyclothoids not installed"}
    res = {"lissom": lis, "pyclothoids": pyc}
    if a.qemu:
        res["cortex_m4f"] = arm_bench()
    if a.json:
        print(json.dumps(res, indent=1))
        return 0
    print(f"{lis['corners']} random corners (seed {a.seed}), host:")
    print(f"  Lissom G2 corner (whole smoothing)      {lis['ns_per_corner']:10.0f} ns per corner")
    for k in ("line_line", "line_arc", "arc_line", "arc_arc"):
        print(f"    {k:10s}                            {lis['ns_per_corner_' + k]:10.0f} ns")
    if "error" not in pyc:
        print(f"  pyclothoids G1Hermite (same end states) {pyc['ns_per_g1_fit']:10.0f} ns per fit"
              f"  ({pyc['g1_fits_reaching_end']}/{pyc['g1_fits_checked']} checked reach the end point)")
    print(f"  Lissom incremental step                 {lis['ns_per_step']:10.1f} ns per step")
    print(f"  Lissom direct evaluation                {lis['ns_per_eval']:10.1f} ns per point")
    if "error" not in pyc:
        print(f"  pyclothoids X(s), Y(s)                  {pyc['ns_per_point_eval']:10.1f} ns per point")
    if a.qemu:
        arm = res["cortex_m4f"]
        if "error" in arm:
            print("Cortex-M4F: " + arm["error"])
        else:
            print("Cortex-M4F (QEMU mps2-an386, -icount shift=0), instructions:")
            for line in arm["raw"]:
                print("  " + line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
