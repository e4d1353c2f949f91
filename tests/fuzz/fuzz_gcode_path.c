/*
 * fuzz_gcode_path: G-code text -> the streaming parser -> the look-ahead planner -> the interpolator, in the
 * double (fuzz_gcode_path) or the float build (fuzz_gcode_path_float).
 *
 * Input: byte 0 chooses the machine (fz_path.h, k_fz_machines[b % 4]) and byte 1 the default blend tolerance
 * (0.001 .. 0.256 mm); the rest is the program. The lines stream into the parser; every motion block goes to the
 * planner as it comes, the interpolator stepping a cycle whenever the look-ahead is full. Checks (fz_path.h):
 * finite setpoints, axis v/a/j limits, exact end on the parser's final position, no crawl, no fallback. A parser
 * or planner error ends the program there (a rejected block is not an error of the core); the motion so far
 * must still stop on the last accepted end. Inputs whose time bound exceeds FZ_MAX_EST_S are skipped.
 */
#include <stddef.h>
#include <stdint.h>

#include "fz_path.h"
#include "gcode.h"

#define FZ_MAX_PROGRAM 4096 /* bytes of program text (longer inputs are cut) */

typedef struct fz_gprog {
    lsm_gcode_block b[256];
    double tol[256];
    int n;
    int skip; /* too long or not worth running */
} fz_gprog;

/* Upper bound of an arc's length: the full turns plus one more circle, plus the helix. */
static double arc_len_bound(const lsm_gcode_block *b)
{
    const double r = fmax((double)b->radius_mm, (double)b->radius_end_mm);
    return ((double)b->turns + 1.0) * 2.0 * LSM_PI * r + fabs((double)b->helix_mm);
}

static double block_bound(const fz_machine *m, const lsm_gcode_block *b)
{
    double len = 0;
    for (int k = 0; k < 3; k++)
        len += ((double)b->end[k] - (double)b->start[k]) * ((double)b->end[k] - (double)b->start[k]);
    len = sqrt(len);
    const double feed = b->type == LSM_GCODE_BLOCK_RAPID ? INFINITY : (double)b->feed_mm_s;
    if (b->type == LSM_GCODE_BLOCK_ARC)
        return fz_block_bound_s(m, arc_len_bound(b), feed, fmin((double)b->radius_mm, (double)b->radius_end_mm));
    return fz_block_bound_s(m, len, feed, 0);
}

/* Parses the whole program first (so that its time bound is known before anything runs). */
static void parse(const char *text, size_t len, double def_tol, fz_gprog *p, lsm_real end[3])
{
    lsm_gcode_options go;
    lsm_gcode_default_options(&go);
    go.axis_mask = 7;
    lsm_gcode g;
    if (lsm_gcode_init(&g, &go) != LSM_OK)
        fz_fatal("gcode init");
    static lsm_gcode_result res;
    size_t at = 0;
    for (;;) {
        size_t used = 0;
        const bool fin = at >= len;
        const lsm_status st = fin ? lsm_gcode_finish(&g, &res) : lsm_gcode_feed(&g, text + at, len - at, &used, &res);
        if (!fin && used == 0 && !res.complete)
            fz_fatal("gcode_feed consumed nothing at byte %zu of %zu", at, len);
        at += used;
        if (res.complete) {
            if (st != LSM_OK)
                break; /* the program ends at its first error */
            for (int k = 0; k < res.n_blocks && p->n < 256; k++) {
                p->b[p->n] = res.blocks[k];
                if (res.modal.blend == LSM_GCODE_EXACT_STOP)
                    p->tol[p->n] = 0;
                else
                    p->tol[p->n] = res.modal.blend_tol_mm > 0 ? (double)res.modal.blend_tol_mm : def_tol;
                for (int a = 0; a < 3; a++)
                    end[a] = res.blocks[k].end[a];
                p->n++;
            }
            if (res.end_of_program || p->n >= 256)
                break;
        }
        if (fin)
            break;
    }
}

static lsm_status append(lsm_planner *pl, const lsm_gcode_block *b, double tol)
{
    lsm_planner_move mv;
    memset(&mv, 0, sizeof mv);
    mv.rapid = b->type == LSM_GCODE_BLOCK_RAPID;
    mv.feed_mm_s = b->feed_mm_s;
    mv.tol_mm = (lsm_real)tol;
    mv.seq = b->line;
    if (b->type == LSM_GCODE_BLOCK_ARC)
        return lsm_planner_append_arc(pl, b->end, b->centre, (lsm_geom_plane)b->plane, b->dir, b->turns, &mv);
    return lsm_planner_append_line(pl, b->end, &mv);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 2)
        return 0;
    const fz_machine *m = &k_fz_machines[data[0] % FZ_N_MACHINES];
    const double def_tol = 0.001 * (double)(data[1] + 1);
    const size_t len = size - 2 > FZ_MAX_PROGRAM ? FZ_MAX_PROGRAM : size - 2;
    static fz_gprog p;
    memset(&p, 0, sizeof p);
    lsm_real end[3] = {0, 0, 0};
    parse((const char *)data + 2, len, def_tol, &p, end);
    double est = 0;
    for (int i = 0; i < p.n; i++)
        est += block_bound(m, &p.b[i]);
    if (!(est <= FZ_MAX_EST_S) || est / m->cycle_s > FZ_MAX_EST_CYCLES)
        return 0;

    static fz_run r;
    fz_run_init(&r, m);
    int next = 0;
    lsm_real last_end[3] = {0, 0, 0};
    const long max_cycles = (long)((FZ_CRAWL_FACTOR * est + FZ_CRAWL_SLACK_S) / m->cycle_s) + 10;
    while (next < p.n) {
        const lsm_status st = append(&r.pl, &p.b[next], p.tol[next]);
        if (st == LSM_E_FULL) {
            fz_step(&r);
            if (r.cycles > max_cycles * 21)
                fz_fatal("machine %s: block %d never accepted (planner full for %ld cycles)", m->name, next, r.cycles);
            continue;
        }
        if (st == LSM_OK) {
            for (int a = 0; a < 3; a++)
                last_end[a] = p.b[next].end[a];
        } else if (st != LSM_E_ZERO_LENGTH) {
            break; /* the planner refused it (e.g. a limit it cannot meet): the program ends here */
        }
        next++;
    }
    (void)end;
    while (lsm_planner_finish(&r.pl) == LSM_E_FULL) {
        fz_step(&r);
        if (r.cycles > max_cycles * 21)
            fz_fatal("machine %s: finish never accepted", m->name);
    }
    fz_run_out(&r, est, last_end);
    return 0;
}
