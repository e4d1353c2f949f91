/*
 * fuzz_planner: the planner and interpolator API driven by a sequence of operations, in the double
 * (fuzz_planner) or the float build (fuzz_planner_float).
 *
 * Input: byte 0 chooses the machine (fz_path.h); then operations of 12 bytes each:
 *   op % 8 = 0..2  append_line: end = int16 x, y, z / 2^(4..11) (a box of +-2048 .. +-16 mm), feed, tol, rapid
 *            3     append_arc: centre offset (in-plane, int16 / 2^scale) from the last end, end angle, helix,
 *                  plane G17/18/19, direction, turns 0..2 (so the end lies on the circle)
 *            4     feed hold          5  resume
 *            6     override 0 .. 2 (0 holds; the smallest non-zero factor scales the crawl bound)
 *            7     run 1 .. 256 cycles
 * Flags can make the feed or tolerance bad (0, < 0, NaN, inf): the planner must refuse such a block with an
 * error status; a refused block must change nothing. After the last operation the program is finished, resumed
 * at override 1, and run out. Appending stops once the accepted blocks' time bound reaches FZ_MAX_EST_S. Checks (fz_path.h): finite setpoints, axis limits, exact end on the last accepted
 * block, no crawl, no fallback; plus: a block with a bad feed or tolerance is never accepted.
 */
#include <stddef.h>
#include <stdint.h>

#include "fz_path.h"

#define FZ_OP_BYTES 12
#define FZ_MAX_OPS 200

static int16_t rd16(const uint8_t *p)
{
    return (int16_t)(uint16_t)(p[0] | (p[1] << 8));
}

/* a feed from a byte: 0.1 .. ~2500 mm/s, log-spaced; or a bad one when bad is set */
static double feed_of(uint8_t b, int bad)
{
    if (bad) {
        static const double k_bad[4] = {0.0, -1.0, NAN, INFINITY};
        return k_bad[b & 3];
    }
    return 0.1 * pow(10.0, (double)b / 60.0);
}

static double tol_of(uint8_t b, int bad)
{
    if (bad) {
        static const double k_bad[4] = {-0.01, NAN, -INFINITY, INFINITY};
        return k_bad[b & 3];
    }
    return b < 40 ? 0.0 : 0.0005 * (double)(b - 39); /* G61 in 40 of 256 */
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    const fz_machine *m = &k_fz_machines[data[0] % FZ_N_MACHINES];
    data++;
    size--;
    size_t nops = size / FZ_OP_BYTES;
    if (nops > FZ_MAX_OPS)
        nops = FZ_MAX_OPS;

    static fz_run r;
    fz_run_init(&r, m);
    lsm_real end[3] = {0, 0, 0};
    double est = 0, min_ovr = 1.0; /* the time bound of the accepted blocks; the smallest override used */
    for (size_t i = 0; i < nops; i++) {
        const uint8_t *o = data + i * FZ_OP_BYTES;
        const int op = o[0] % 8;
        if (op <= 3) {
            const double scale = ldexp(1.0, -(4 + (o[11] & 7))); /* a box of +-2048 .. +-16 mm */
            const int bad_feed = (o[10] & 0xE0) == 0xE0, bad_tol = (o[10] & 0x0F) == 0x0F;
            lsm_planner_move mv;
            memset(&mv, 0, sizeof mv);
            mv.feed_mm_s = (lsm_real)feed_of(o[7], bad_feed);
            mv.tol_mm = (lsm_real)tol_of(o[8], bad_tol);
            mv.rapid = (o[10] & 0x10) != 0;
            mv.seq = (uint32_t)i;
            lsm_real to[LSM_MAX_AXES] = {0}, centre[3] = {0, 0, 0};
            static const lsm_geom_plane k_planes[3] = {LSM_GEOM_PLANE_XY, LSM_GEOM_PLANE_ZX, LSM_GEOM_PLANE_YZ};
            static const int k_e1[3] = {0, 2, 1}, k_e2[3] = {1, 0, 2}, k_n[3] = {2, 1, 0};
            const int pi = o[9] % 3;
            double len = 0, rad = 0;
            if (op < 3) {
                for (int a = 0; a < 3; a++) {
                    to[a] = (lsm_real)((double)rd16(o + 1 + 2 * a) * scale);
                    len += ((double)to[a] - (double)end[a]) * ((double)to[a] - (double)end[a]);
                }
                len = sqrt(len);
            } else {
                const double c1 = (double)rd16(o + 1) * scale, c2 = (double)rd16(o + 3) * scale;
                const double ang = 2.0 * LSM_PI * (double)o[5] / 256.0;
                rad = sqrt(c1 * c1 + c2 * c2);
                for (int a = 0; a < 3; a++)
                    centre[a] = to[a] = end[a];
                centre[k_e1[pi]] = (lsm_real)((double)end[k_e1[pi]] + c1);
                centre[k_e2[pi]] = (lsm_real)((double)end[k_e2[pi]] + c2);
                /* the start is at angle atan2(-c2, -c1) from the centre; the end ang further on */
                const double a0 = atan2(-c2, -c1) + ang;
                to[k_e1[pi]] = (lsm_real)((double)centre[k_e1[pi]] + rad * cos(a0));
                to[k_e2[pi]] = (lsm_real)((double)centre[k_e2[pi]] + rad * sin(a0));
                to[k_n[pi]] = (lsm_real)((double)end[k_n[pi]] + (double)(int8_t)o[6] * scale);
                len = (double)((o[9] >> 4) % 3 + 1) * 2.0 * LSM_PI * rad + fabs((double)(int8_t)o[6] * scale);
            }
            const double blk = fz_block_bound_s(m, len, mv.rapid ? INFINITY : fmax((double)mv.feed_mm_s, 0.1), rad);
            if ((est + blk) / min_ovr > FZ_MAX_EST_S || (est + blk) / min_ovr / m->cycle_s > FZ_MAX_EST_CYCLES)
                continue; /* too slow to be worth running: not appended */
            const lsm_status st = op < 3
                                      ? lsm_planner_append_line(&r.pl, to, &mv)
                                      : lsm_planner_append_arc(&r.pl, to, centre, k_planes[pi], (o[9] & 0x80) ? -1 : 1,
                                                               (uint32_t)((o[9] >> 4) % 3), &mv);
            if (st == LSM_E_FULL) {
                fz_step(&r); /* run a cycle and drop the block (the next op goes on) */
                continue;
            }
            if (st == LSM_OK) {
                est += blk;
                if (bad_feed && !mv.rapid)
                    fz_fatal("op %zu: a block with feed %g was accepted", i, (double)mv.feed_mm_s);
                if (bad_tol)
                    fz_fatal("op %zu: a block with tolerance %g was accepted", i, (double)mv.tol_mm);
                for (int a = 0; a < 3; a++)
                    end[a] = to[a];
            }
        } else if (op == 4) {
            lsm_interp_hold(&r.ip);
        } else if (op == 5) {
            lsm_interp_resume(&r.ip);
        } else if (op == 6) {
            if (o[1] % 9 != 0)
                min_ovr = fmin(min_ovr, (double)(o[1] % 9) / 4.0);
            const lsm_status st = lsm_interp_set_override(&r.ip, (lsm_real)((double)(o[1] % 9) / 4.0));
            if (st != LSM_OK)
                fz_fatal("op %zu: override %g refused: %s", i, (double)(o[1] % 9) / 4.0, lsm_status_str(st));
        } else {
            for (int k = 0; k <= o[1]; k++)
                fz_step(&r);
        }
    }
    est /= min_ovr;
    const long max_cycles = (long)((FZ_CRAWL_FACTOR * est + FZ_CRAWL_SLACK_S) / m->cycle_s) + 10;
    const long c0 = r.cycles;
    lsm_interp_resume(&r.ip);
    (void)lsm_interp_set_override(&r.ip, 1);
    while (lsm_planner_finish(&r.pl) == LSM_E_FULL) {
        fz_step(&r);
        if (r.cycles - c0 > max_cycles * 21)
            fz_fatal("machine %s: finish never accepted", m->name);
    }
    fz_run_out(&r, est, end);
    return 0;
}
