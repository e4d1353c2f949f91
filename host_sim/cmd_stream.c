/*
 * lissom-sim stream: run a G-code program on a Lissom node over SocketCAN (docs/canopen.md path protocol).
 *
 *   lissom-sim stream PROGRAM --iface IFACE --node-id N [--tol-mm T] [--rapid-mm-s V] [--sync-ms P]
 *                     [--sdo-timeout-ms T] [--progress | --no-progress] [--yes]
 *
 * The program is parsed with the firmware's parser (gcode.h); any error stops before anything moves (all of them are
 * listed, as `check` does). Then: NMT start, every axis to OPERATION ENABLED in path mode (-1), and the blocks go to
 * 0x5010 with sequence numbers from the node's last accepted one, with the flow control of docs/canopen.md (free
 * slots 0x5003 from TPDO2 or by SDO; 0x08000020 buffer full: retry; 0x06090031 gap: resend from 0x5004 + 1; a lost
 * answer: the same block again, which the node acknowledges as a duplicate). The path starts once the node's buffer
 * is full (or the program is all sent), so the look-ahead has blocks to work on.
 * Coordinates: the program's machine coordinates are the node's counts / 0x2001 (counts per mm; per degree on A B
 * C); the parser starts where the axes are. Rapids are sent at --rapid-mm-s (default 10000 mm/s: the node caps
 * every block at its axes' limits). G64 P gives the block tolerance, else --tol-mm (0.01); G61 sends 1 µm (the
 * protocol has no exact-stop flag). Arcs with P turns are sent as that many full circles plus the rest.
 * Machine functions (S, M3-M5, M6, M7-M9, G4, M0/M1, ...): the node has no spindle, coolant or tool outputs; the
 * ones that need an exact stop wait until the node has run every block before them, are printed with their line,
 * and G4 waits its seconds; M0/M1 wait for Enter on a terminal (with --yes, or without a terminal, they are logged
 * and the program goes on).
 * Progress (stderr): blocks sent and executed, the line, the feed (0x5006) and the position (TPDO3/TPDO4, the
 * telemetry PDOs the node sends at each SYNC; this tool sends SYNC every --sync-ms, default 20 ms). SDO answers are
 * awaited --sdo-timeout-ms (5000, as the HIL rig: a loaded host answers late); reads are asked again when an answer
 * is lost, and a block download the node's server timed out is sent again (the node stores a block whole or not).
 * Ctrl-C: feed hold (path hold, 0x5000 = 2); Enter resumes; a second Ctrl-C is a quick stop (path clear and CiA 402
 * quick stop on every axis), exit 130.
 * Exit: 0 done; 1 program errors or a block the node refused; 2 usage; 3 the node faulted (its EMCY code and text
 * are printed); 4 no answer from the node or a CAN error; 130 stopped by Ctrl-C.
 */
#include <errno.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "co_master.h"
#include "commands.h"
#include "gcode.h"
#include "pathrun.h"

#define ST_MAX_AXES 6
#define ST_ENABLE_TIMEOUT_MS 2000 /* CiA 402 state changes of a node at rest take a few cycles */
#define ST_PROGRESS_MS 200        /* progress line and feed read period */
#define ST_POLL_MS 5              /* frame wait of one loop turn */
#define ST_BLOCK_RETRIES 20       /* a block download the node's SDO server timed out (0x05040000) is sent again */
#define ST_READ_RETRIES 3         /* reads are idempotent: a lost answer is asked again */

enum { EXIT_PROGRAM = 1, EXIT_USAGE = 2, EXIT_FAULT = 3, EXIT_COMM = 4, EXIT_STOPPED = 130 };

typedef struct st_block {
    uint8_t data[24 + 4 * ST_MAX_AXES];
    uint8_t len;
    uint32_t line;
} st_block;

typedef struct st_event {
    lsm_gcode_event ev;
    size_t before; /* path blocks before it */
} st_event;

typedef struct stream {
    co_master m;
    int n_axes;
    double cpm[ST_MAX_AXES];
    double tol_mm, rapid_mm_s;
    st_block *b;
    size_t nb, capb;
    st_event *e;
    size_t ne, cape;
    /* telemetry */
    bool tpdo2, pos_seen[ST_MAX_AXES];
    uint8_t path_state;
    uint16_t free_slots, capacity;
    uint32_t last_acc, active_seq;
    int32_t pos[ST_MAX_AXES];
    double feed_mm_s;
    /* EMCY */
    bool fault;
    uint16_t emcy_code;
    uint8_t emcy_data[8];
} stream;

static volatile sig_atomic_t g_interrupts;

static void on_sigint(int sig)
{
    (void)sig;
    g_interrupts++;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* Frames the node sends on its own: TPDO2 (state, free slots, last accepted), TPDO3/4 (positions, active
 * sequence), EMCY. */
static void on_frame(void *ctx, const co_frame *f)
{
    stream *s = ctx;
    const uint32_t id = s->m.node_id;
    if (f->id == 0x280 + id && f->len >= 7) {
        s->tpdo2 = true;
        s->path_state = f->data[0];
        s->free_slots = (uint16_t)(f->data[1] | f->data[2] << 8);
        s->last_acc =
            (uint32_t)f->data[3] | (uint32_t)f->data[4] << 8 | (uint32_t)f->data[5] << 16 | (uint32_t)f->data[6] << 24;
    } else if (f->id == 0x380 + id && f->len >= 8) {
        for (int k = 0; k < 2 && k < s->n_axes; k++) {
            s->pos[k] = (int32_t)((uint32_t)f->data[4 * k] | (uint32_t)f->data[4 * k + 1] << 8 |
                                  (uint32_t)f->data[4 * k + 2] << 16 | (uint32_t)f->data[4 * k + 3] << 24);
            s->pos_seen[k] = true;
        }
    } else if (f->id == 0x480 + id && f->len >= 8 && s->n_axes >= 3) {
        s->pos[2] = (int32_t)((uint32_t)f->data[0] | (uint32_t)f->data[1] << 8 | (uint32_t)f->data[2] << 16 |
                              (uint32_t)f->data[3] << 24);
        s->pos_seen[2] = true;
        s->active_seq =
            (uint32_t)f->data[4] | (uint32_t)f->data[5] << 8 | (uint32_t)f->data[6] << 16 | (uint32_t)f->data[7] << 24;
    } else if (f->id == 0x80 + id && f->len == 8) {
        const uint16_t code = (uint16_t)(f->data[0] | f->data[1] << 8);
        const bool info = code == 0x0000 || code == 0x8110 || code == 0x8120 || code == 0x8140 || code == 0x8210 ||
                          code == 0x8220 || code == 0x8240;
        if (!info && !s->fault) {
            s->fault = true;
            s->emcy_code = code;
            memcpy(s->emcy_data, f->data, 8);
        } else if (info && code != 0) {
            fprintf(stderr, "\nwarning: node %u EMCY 0x%04X: %s\n", (unsigned)id, code, co_emcy_text(code));
        }
    }
}

/* ---------------------------------------------------------------------------------------------------------- */
/* the program as path blocks                                                                                  */

static int push_block(stream *s, const st_block *b)
{
    if (s->nb == s->capb) {
        s->capb = s->capb ? 2 * s->capb : 256;
        st_block *nv = realloc(s->b, s->capb * sizeof *nv);
        if (!nv)
            return -1;
        s->b = nv;
    }
    s->b[s->nb++] = *b;
    return 0;
}

static void put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v, p[1] = (uint8_t)(v >> 8), p[2] = (uint8_t)(v >> 16), p[3] = (uint8_t)(v >> 24);
}

static int32_t counts(const stream *s, int k, double v)
{
    const double u = k >= 3 ? v * 180.0 / LSM_PI : v; /* rotary axes: counts per degree */
    return (int32_t)llround(u * s->cpm[k]);
}

/* One 0x5010 block: a line (type 1) or an arc (2 CW, 3 CCW) ending at end[], centre[] (X Y Z) for arcs. */
static int encode(stream *s, int type, int plane, const lsm_real *end, const lsm_real *centre, double feed_mm_s,
                  double tol_mm, uint32_t line)
{
    st_block b = {{0}, 0, line};
    const uint32_t feed_um = (uint32_t)fmax(1.0, fmin(4e9, llround(feed_mm_s * 1000.0)));
    const uint32_t tol_um = (uint32_t)fmax(1.0, fmin(4e9, llround(tol_mm * 1000.0)));
    b.data[4] = (uint8_t)type;
    b.data[5] = (uint8_t)(type == 1 ? 0 : plane);
    b.data[6] = (uint8_t)s->n_axes;
    put_u32(b.data + 8, feed_um);
    put_u32(b.data + 12, tol_um);
    for (int k = 0; k < s->n_axes; k++)
        put_u32(b.data + 16 + 4 * k, (uint32_t)counts(s, k, end[k]));
    b.len = (uint8_t)(16 + 4 * s->n_axes);
    if (type != 1) {
        static const int pa[3] = {0, 2, 1}, pb[3] = {1, 0, 2};
        put_u32(b.data + b.len, (uint32_t)counts(s, pa[plane], centre[pa[plane]]));
        put_u32(b.data + b.len + 4, (uint32_t)counts(s, pb[plane], centre[pb[plane]]));
        b.len = (uint8_t)(b.len + 8);
    }
    return push_block(s, &b);
}

/* A parser block as path blocks (an arc with extra turns: that many full circles, then the rest). */
static int add_gcode_block(stream *s, const lsm_gcode_block *g, const lsm_gcode_modal *mo)
{
    const double tol = mo->blend == LSM_GCODE_EXACT_STOP ? 0.001 : mo->blend_tol_mm > 0 ? mo->blend_tol_mm : s->tol_mm;
    if (g->type != LSM_GCODE_BLOCK_ARC)
        return encode(s, 1, 0, g->end, NULL, g->type == LSM_GCODE_BLOCK_RAPID ? s->rapid_mm_s : g->feed_mm_s, tol,
                      g->line);
    const int plane = g->plane == LSM_GCODE_PLANE_XY ? 0 : g->plane == LSM_GCODE_PLANE_ZX ? 1 : 2;
    const int type = g->dir < 0 ? 2 : 3;
    for (uint32_t t = 1; t <= g->turns; t++) {
        /* after t full turns: the plane's point is the start again, the other axes have moved t 2 pi / angle */
        const double f = 2 * LSM_PI * t / g->angle_rad;
        lsm_real e[ST_MAX_AXES];
        for (int k = 0; k < ST_MAX_AXES; k++)
            e[k] = (lsm_real)(g->start[k] + f * (g->end[k] - g->start[k]));
        static const int pa[3] = {0, 2, 1}, pb[3] = {1, 0, 2};
        e[pa[plane]] = g->start[pa[plane]];
        e[pb[plane]] = g->start[pb[plane]];
        if (encode(s, type, plane, e, g->centre, g->feed_mm_s, tol, g->line) != 0)
            return -1;
    }
    return encode(s, type, plane, g->end, g->centre, g->feed_mm_s, tol, g->line);
}

static int push_event(stream *s, const lsm_gcode_event *e, size_t before)
{
    if (s->ne == s->cape) {
        s->cape = s->cape ? 2 * s->cape : 64;
        st_event *nv = realloc(s->e, s->cape * sizeof *nv);
        if (!nv)
            return -1;
        s->e = nv;
    }
    s->e[s->ne++] = (st_event){*e, before};
    return 0;
}

/* Parses the whole program; prints every error. Returns the number of errors (or -1: out of memory). */
static int load_program(stream *s, const char *name, const char *text, size_t len, const double start[ST_MAX_AXES])
{
    lsm_gcode_options go;
    lsm_gcode_default_options(&go);
    go.axis_mask = (uint8_t)((1u << s->n_axes) - 1u);
    lsm_gcode g;
    lsm_real pos[LSM_GCODE_N_AXES] = {0};
    for (int k = 0; k < s->n_axes; k++)
        pos[k] = (lsm_real)start[k];
    if (lsm_gcode_init(&g, &go) != LSM_OK || lsm_gcode_set_position(&g, pos) != LSM_OK) {
        fprintf(stderr, "error: the axes' position is out of the parser's range\n");
        return 1;
    }
    int errors = 0;
    size_t at = 0;
    for (;;) {
        lsm_gcode_result r;
        size_t used = 0;
        const bool fin = at >= len;
        const lsm_status st = fin ? lsm_gcode_finish(&g, &r) : lsm_gcode_feed(&g, text + at, len - at, &used, &r);
        at += used;
        if (r.complete && st != LSM_OK) {
            char why[128];
            fprintf(stderr, "%s:%u:%u: error: %s\n", name, (unsigned)r.err.line, (unsigned)r.err.column,
                    lsm_gcode_error_text(&r.err, why, sizeof why));
            errors++;
        } else if (r.complete && errors == 0) {
            const size_t before_line = s->nb;
            size_t after_block[LSM_GCODE_MAX_BLOCKS + 1];
            after_block[0] = before_line;
            for (int k = 0; k < r.n_blocks; k++) {
                const lsm_gcode_block *b = &r.blocks[k];
                if (b->type == LSM_GCODE_BLOCK_ARC && s->n_axes < 3 && b->plane != LSM_GCODE_PLANE_XY) {
                    fprintf(stderr, "%s:%u: error: an arc in G%d needs a Z axis; the node has %d axes\n", name,
                            (unsigned)b->line, (int)b->plane, s->n_axes);
                    errors++;
                }
                if (add_gcode_block(s, b, &r.modal) != 0)
                    return -1;
                after_block[k + 1] = s->nb;
            }
            for (int k = 0; k < r.n_events; k++)
                if (push_event(s, &r.events[k], after_block[r.events[k].at_block]) != 0)
                    return -1;
        }
        if (fin)
            break;
    }
    return errors;
}

/* ---------------------------------------------------------------------------------------------------------- */
/* the node                                                                                                    */

/* An SDO read, asked again when the answer is lost (a loaded bus or host). */
static int64_t sdo_read(stream *s, uint16_t index, uint8_t sub, uint32_t *v)
{
    int64_t r = CO_SDO_TIMEOUT;
    for (int k = 0; k < ST_READ_RETRIES && (r == CO_SDO_TIMEOUT || r == 0x05040000); k++)
        r = co_sdo_read(&s->m, index, sub, v);
    return r;
}

static int fail_comm(stream *s, const char *what, int64_t r)
{
    fprintf(stderr, "\nerror: node %u: %s: %s", (unsigned)s->m.node_id, what, co_sdo_abort_text(r));
    if (r > 0)
        fprintf(stderr, " (abort 0x%08llX)", (unsigned long long)r);
    fprintf(stderr, "\n");
    return r == CO_SDO_TIMEOUT || r == CO_SDO_IO ? EXIT_COMM : EXIT_PROGRAM;
}

static int report_fault(const stream *s)
{
    const uint8_t *d = s->emcy_data;
    fprintf(stderr, "\nerror: node %u EMCY 0x%04X: %s (error register 0x%02X, data %02X %02X %02X %02X %02X)\n",
            (unsigned)s->m.node_id, s->emcy_code, co_emcy_text(s->emcy_code), d[2], d[3], d[4], d[5], d[6], d[7]);
    return EXIT_FAULT;
}

/* The number of CiA 402 axes: statuswords answered at 0x6041 + 0x800 k. */
static int count_axes(stream *s)
{
    int n = 0;
    for (int k = 0; k < ST_MAX_AXES; k++) {
        uint32_t v;
        int64_t r = sdo_read(s, (uint16_t)(0x6041 + 0x800 * k), 0, &v);
        if (r != 0) {
            if (k == 0)
                return (int)(r < 0 ? r : -100);
            break;
        }
        n++;
    }
    return n;
}

static int enable_axes(stream *s)
{
    for (int k = 0; k < s->n_axes; k++) {
        const uint16_t base = (uint16_t)(0x800 * k);
        uint32_t sw = 0;
        int64_t r = sdo_read(s, (uint16_t)(0x6041 + base), 0, &sw);
        if (r != 0)
            return fail_comm(s, "statusword", r);
        if ((sw & 0x4F) == 0x08) { /* FAULT: fault reset (refused while the cause, e.g. the E-stop, is active) */
            co_sdo_write_u32(&s->m, (uint16_t)(0x6040 + base), 0, 0x00, 2);
            co_sdo_write_u32(&s->m, (uint16_t)(0x6040 + base), 0, 0x80, 2);
        }
        r = co_sdo_write_u32(&s->m, (uint16_t)(0x6060 + base), 0, 0xFF, 1); /* mode -1: path */
        if (r != 0)
            return fail_comm(s, "mode of operation -1 (path)", r);
        static const uint16_t seq[3] = {0x06, 0x07, 0x0F};
        for (int i = 0; i < 3; i++) {
            r = co_sdo_write_u32(&s->m, (uint16_t)(0x6040 + base), 0, seq[i], 2);
            if (r != 0)
                return fail_comm(s, "controlword", r);
        }
        const double end = now_s() + ST_ENABLE_TIMEOUT_MS * 1e-3;
        for (;;) {
            r = sdo_read(s, (uint16_t)(0x6041 + base), 0, &sw);
            if (r != 0)
                return fail_comm(s, "statusword", r);
            if ((sw & 0x6F) == 0x27)
                break;
            if (now_s() > end || s->fault) {
                if (s->fault)
                    return report_fault(s);
                fprintf(stderr, "error: node %u axis %d does not reach OPERATION ENABLED (statusword 0x%04X)\n",
                        (unsigned)s->m.node_id, k, (unsigned)sw);
                return EXIT_FAULT;
            }
            co_poll(&s->m, 5);
        }
    }
    return 0;
}

static int path_command(stream *s, uint8_t cmd, const char *what)
{
    int64_t r = co_sdo_write_u32(&s->m, 0x5000, 0, cmd, 1);
    return r == 0 ? 0 : fail_comm(s, what, r);
}

/* ---------------------------------------------------------------------------------------------------------- */

typedef struct run_state {
    size_t next;   /* next block to send */
    uint32_t seq0; /* sequence of block 0 */
    size_t ei;     /* next event */
    bool started, held;
    int free_est; /* free slots as this master counts them */
    double t_sync, t_progress, t0, t_check;
    int sync_ms;
    bool progress, tty_in, yes;
    int interrupts_seen;
} run_state;

/* Frames, SYNC and the interrupt count, each loop turn. */
static int service(stream *s, run_state *st)
{
    const double t = now_s();
    if (st->sync_ms > 0 && t >= st->t_sync) {
        if (co_sync(&s->m) != 0)
            return EXIT_COMM;
        st->t_sync = t + st->sync_ms * 1e-3;
    }
    if (co_poll(&s->m, ST_POLL_MS) < 0)
        return EXIT_COMM;
    if (s->fault)
        return report_fault(s);
    if (g_interrupts != st->interrupts_seen) {
        st->interrupts_seen = g_interrupts;
        if (g_interrupts >= 2) {
            fprintf(stderr, "\nquick stop\n");
            co_sdo_write_u32(&s->m, 0x5000, 0, 4, 1);
            for (int k = 0; k < s->n_axes; k++)
                co_sdo_write_u32(&s->m, (uint16_t)(0x6040 + 0x800 * k), 0, 0x02, 2);
            return EXIT_STOPPED;
        }
        if (st->started) {
            int rc = path_command(s, 2, "feed hold");
            if (rc)
                return rc;
        }
        st->held = true;
        fprintf(stderr, "\nfeed hold: Enter resumes, Ctrl-C again is a quick stop\n");
    }
    if (st->held) {
        struct pollfd p = {0, POLLIN, 0};
        if (st->tty_in && poll(&p, 1, 0) > 0) {
            char buf[256];
            if (read(0, buf, sizeof buf) > 0) {
                st->held = false;
                g_interrupts = st->interrupts_seen = 0;
                if (st->started) {
                    int rc = path_command(s, 3, "resume");
                    if (rc)
                        return rc;
                }
                fprintf(stderr, "resumed\n");
            }
        }
    }
    return 0;
}

static void print_progress(stream *s, run_state *st, bool final)
{
    const double t = now_s();
    if (!st->progress || (!final && t < st->t_progress))
        return;
    st->t_progress = t + ST_PROGRESS_MS * 1e-3;
    uint32_t v;
    if (!final && sdo_read(s, 0x5006, 0, &v) == 0)
        s->feed_mm_s = v * 1e-3;
    const uint32_t done = s->active_seq >= st->seq0 ? s->active_seq - st->seq0 + 1 : 0;
    const uint32_t line = done > 0 && done <= s->nb ? s->b[done - 1].line : 0;
    fprintf(stderr, "\r  sent %zu/%zu  running %u  line %u  F %.0f mm/min ", st->next, s->nb, (unsigned)done,
            (unsigned)line, s->feed_mm_s * 60.0);
    static const char axis[ST_MAX_AXES] = {'X', 'Y', 'Z', 'A', 'B', 'C'};
    for (int k = 0; k < s->n_axes && k < 3; k++)
        if (s->pos_seen[k])
            fprintf(stderr, " %c %.3f", axis[k], s->pos[k] / s->cpm[k]);
    fprintf(stderr, "%s %s", st->held ? "  [hold]" : "", final ? "\n" : "\x1b[K");
    fflush(stderr);
}

/* True when the node has run every block sent so far and rests (SDO: 0x5005, 0x5003, statusword bit 10). */
static int node_done(stream *s, run_state *st, bool *done)
{
    *done = false;
    if (st->next == 0) {
        *done = true;
        return 0;
    }
    const double t = now_s();
    if (t < st->t_check)
        return 0;
    st->t_check = t + 0.02; /* SDO polls at most every 20 ms */
    uint32_t active, fr, sw;
    int64_t r = sdo_read(s, 0x5005, 0, &active);
    if (r == 0)
        r = sdo_read(s, 0x5003, 0, &fr);
    if (r == 0)
        r = sdo_read(s, 0x6041, 0, &sw);
    if (r != 0)
        return fail_comm(s, "progress", r);
    s->active_seq = active;
    *done = active == st->seq0 + st->next - 1 && fr == s->capacity && (sw & 0x0400);
    return 0;
}

/* Sends block st->next with the flow control of docs/canopen.md. */
static int send_next(stream *s, run_state *st)
{
    if (st->free_est <= 0 && s->tpdo2) {
        /* TPDO2 of the last SYNC: its free slots, less the blocks accepted since (its last accepted is older) */
        const uint32_t sent_last = st->seq0 + (uint32_t)st->next - 1u;
        st->free_est = (int)s->free_slots - (int)(int32_t)(sent_last - s->last_acc);
        if (st->free_est <= 0)
            return 0; /* wait for the next SYNC's TPDO2 */
    } else if (st->free_est <= 0) {
        uint32_t fr;
        int64_t r = sdo_read(s, 0x5003, 0, &fr);
        if (r != 0)
            return fail_comm(s, "free slots", r);
        st->free_est = (int)fr;
        if (fr == 0)
            return 0;
    }
    st_block *b = &s->b[st->next];
    put_u32(b->data, st->seq0 + (uint32_t)st->next);
    int64_t r = co_sdo_write(&s->m, 0x5010, 0, b->data, b->len);
    /* the node's SDO server gave up between segments (0x05040000, a loaded host), or the transfer was garbled: the
     * block was not stored (whole or nothing), send it again */
    for (int k = 0;
         k < ST_BLOCK_RETRIES && (r == 0x05040000 || r == 0x05030000 || r == 0x05040001 || r == CO_SDO_PROTOCOL); k++)
        r = co_sdo_write(&s->m, 0x5010, 0, b->data, b->len);
    if (r == 0) {
        st->next++;
        st->free_est--;
        return 0;
    }
    if (r == 0x08000020) { /* full: wait for a free slot */
        st->free_est = 0;
        return 0;
    }
    if (r == CO_SDO_TIMEOUT)
        return 0;          /* the same block again: a duplicate is acknowledged, not stored twice */
    if (r == 0x06090031) { /* gap: resend from the node's last accepted + 1 */
        uint32_t last;
        int64_t r2 = sdo_read(s, 0x5004, 0, &last);
        if (r2 != 0)
            return fail_comm(s, "last accepted sequence", r2);
        st->next = (size_t)(last + 1u - st->seq0);
        return 0;
    }
    fprintf(stderr, "\nerror: node %u refused the block of line %u: %s (abort 0x%08llX)\n", (unsigned)s->m.node_id,
            (unsigned)b->line, co_sdo_abort_text(r), (unsigned long long)r);
    return r < 0 ? EXIT_COMM : EXIT_PROGRAM;
}

/* Waits `seconds` while serving the bus (a dwell). */
static int wait_serving(stream *s, run_state *st, double seconds)
{
    const double end = now_s() + seconds;
    while (now_s() < end) {
        int rc = service(s, st);
        if (rc)
            return rc;
    }
    return 0;
}

/* Runs machine function e (the node has run every block before it if it needs an exact stop). */
static int run_event(stream *s, run_state *st, const lsm_gcode_event *e)
{
    const lsm_gcode_event_kind k = e->kind;
    printf("line %u: %s %s", (unsigned)e->line,
           k == LSM_GCODE_EV_END && e->tool == 30 ? "M30" : lsm_gcode_event_code(k), lsm_gcode_event_name(k));
    if (k == LSM_GCODE_EV_SPINDLE_SPEED || k == LSM_GCODE_EV_SPINDLE_CW || k == LSM_GCODE_EV_SPINDLE_CCW)
        printf(" %.0f rpm", (double)e->value);
    if (k == LSM_GCODE_EV_TOOL_SELECT || k == LSM_GCODE_EV_TOOL_CHANGE || k == LSM_GCODE_EV_TOOL_LENGTH)
        printf(" %d", (int)e->tool);
    if (k == LSM_GCODE_EV_DWELL)
        printf(" %.3f s", (double)e->value);
    printf("\n");
    fflush(stdout);
    if (k == LSM_GCODE_EV_DWELL)
        return wait_serving(s, st, (double)e->value);
    if (k == LSM_GCODE_EV_PAUSE || k == LSM_GCODE_EV_OPTIONAL_PAUSE) {
        if (!st->tty_in || st->yes) {
            printf("line %u: resumed (no operator: %s)\n", (unsigned)e->line,
                   st->yes ? "--yes" : "stdin is not a terminal");
            return 0;
        }
        fprintf(stderr, "\nprogram paused at line %u (%s): Enter resumes\n", (unsigned)e->line,
                lsm_gcode_event_code(k));
        st->held = true;
        while (st->held) {
            int rc = service(s, st);
            if (rc)
                return rc;
        }
    }
    return 0;
}

static int stream_run(stream *s, run_state *st)
{
    for (;;) {
        int rc = service(s, st);
        if (rc)
            return rc;
        print_progress(s, st, false);
        if (st->held)
            continue;
        const bool event_due = st->ei < s->ne && s->e[st->ei].before <= st->next;
        if (event_due && s->e[st->ei].ev.kind != LSM_GCODE_EV_END) {
            const st_event *ev = &s->e[st->ei];
            if (ev->ev.exact_stop) {
                if (!st->started && st->next > 0) {
                    if ((rc = path_command(s, 1, "start")) != 0)
                        return rc;
                    st->started = true;
                }
                bool done;
                if ((rc = node_done(s, st, &done)) != 0)
                    return rc;
                if (!done)
                    continue;
            }
            if ((rc = run_event(s, st, &ev->ev)) != 0)
                return rc;
            st->ei++;
            continue;
        }
        if (st->next < s->nb) {
            if ((rc = send_next(s, st)) != 0)
                return rc;
            if (!st->started && (st->free_est <= 0 || st->next == s->nb)) {
                if ((rc = path_command(s, 1, "start")) != 0)
                    return rc;
                st->started = true;
            }
            continue;
        }
        bool done;
        if ((rc = node_done(s, st, &done)) != 0)
            return rc;
        if (done) {
            for (; st->ei < s->ne; st->ei++) /* the end of the program (M2/M30) */
                run_event(s, st, &s->e[st->ei].ev);
            return 0;
        }
    }
}

static int setup_node(stream *s, double start_mm[ST_MAX_AXES])
{
    co_nmt(&s->m, 0x01); /* start remote node: PDOs flow */
    co_poll(&s->m, 50);
    const int n = count_axes(s);
    if (n <= 0)
        return fail_comm(s, "no answer (is the node on this interface, with this id?)", n < 0 ? n : CO_SDO_TIMEOUT);
    s->n_axes = n;
    for (int k = 0; k < n; k++) {
        uint32_t v;
        int64_t r = sdo_read(s, (uint16_t)(0x2001 + 0x800 * k), 0, &v);
        if (r != 0)
            return fail_comm(s, "position units per mm (0x2001)", r);
        s->cpm[k] = v ? v : 1;
        r = sdo_read(s, (uint16_t)(0x6062 + 0x800 * k), 0, &v);
        if (r != 0)
            return fail_comm(s, "position demand (0x6062)", r);
        s->pos[k] = (int32_t)v;
        start_mm[k] = (double)(int32_t)v / s->cpm[k] * (k >= 3 ? LSM_PI / 180.0 : 1.0);
    }
    uint32_t v;
    int64_t r = sdo_read(s, 0x5007, 0, &v);
    if (r != 0)
        return fail_comm(s, "path buffer capacity (0x5007)", r);
    s->capacity = (uint16_t)v;
    r = sdo_read(s, 0x5002, 0, &v);
    if (r != 0)
        return fail_comm(s, "path state (0x5002)", r);
    if (v != 0) {
        fprintf(stderr, "error: node %u: the path is busy (state %u, not idle): another program runs\n",
                (unsigned)s->m.node_id, (unsigned)v);
        return EXIT_PROGRAM;
    }
    return 0;
}

int cmd_stream(int argc, char **argv)
{
    cli_args a;
    cli_init(&a, argc, argv);
    const char *iface = cli_opt(&a, "iface");
    double node_id = 0, tol = 0.01, rapid = 10000, sync_ms = 20, sdo_ms = 5000;
    if (cli_num_req(&a, "node-id", &node_id) < 0 || cli_num(&a, "tol-mm", &tol) < 0 ||
        cli_num(&a, "rapid-mm-s", &rapid) < 0 || cli_num(&a, "sync-ms", &sync_ms) < 0 ||
        cli_num(&a, "sdo-timeout-ms", &sdo_ms) < 0)
        return EXIT_USAGE;
    const bool prog_on = cli_flag(&a, "progress"), prog_off = cli_flag(&a, "no-progress"), yes = cli_flag(&a, "yes");
    const char *program = cli_positional(&a, 0);
    if (cli_check_unused(&a, "stream"))
        return EXIT_USAGE;
    if (!program || !iface) {
        fprintf(stderr, "usage: lissom-sim stream PROGRAM --iface IFACE --node-id N [--tol-mm T] [--rapid-mm-s V] "
                        "[--sync-ms P] [--sdo-timeout-ms T] [--progress | --no-progress] [--yes]\n");
        return EXIT_USAGE;
    }
    if (!(node_id >= 1 && node_id <= 127 && node_id == floor(node_id)) || !(tol >= 0.001 && tol <= 1000) ||
        !(rapid > 0 && rapid <= 1e6) || !(sync_ms >= 0 && sync_ms <= 1000) || !(sdo_ms >= 10 && sdo_ms <= 60000)) {
        fprintf(stderr, "error: --node-id 1..127, --tol-mm 0.001..1000, --rapid-mm-s (0, 1e6], --sync-ms 0..1000, "
                        "--sdo-timeout-ms 10..60000\n");
        return EXIT_USAGE;
    }
    size_t len = 0;
    char *text = sim_read_file(program, &len);
    if (!text) {
        fprintf(stderr, "error: cannot read %s\n", program);
        return EXIT_USAGE;
    }
    stream s;
    memset(&s, 0, sizeof s);
    s.tol_mm = tol;
    s.rapid_mm_s = rapid;
    int rc = 0;
    { /* the program first, before the bus is touched (all six axes; the node's axes are checked again below) */
        stream pre;
        memset(&pre, 0, sizeof pre);
        pre.n_axes = ST_MAX_AXES;
        pre.tol_mm = tol;
        pre.rapid_mm_s = rapid;
        for (int k = 0; k < ST_MAX_AXES; k++)
            pre.cpm[k] = 1;
        const double zero[ST_MAX_AXES] = {0};
        const int errors = load_program(&pre, program, text, len, zero);
        free(pre.b);
        free(pre.e);
        if (errors != 0) {
            fprintf(stderr, errors < 0 ? "error: out of memory\n" : "%s: %d error(s): nothing was sent\n", program,
                    errors);
            free(text);
            return EXIT_PROGRAM;
        }
    }
    if (co_master_open(&s.m, iface, (uint8_t)node_id) != 0) {
        fprintf(stderr, "error: %s\n", s.m.err);
        free(text);
        return EXIT_COMM;
    }
    s.m.on_frame = on_frame;
    s.m.sdo_timeout_ms = (int)sdo_ms;
    s.m.ctx = &s;
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    sigaction(SIGINT, &sa, NULL);
    double start[ST_MAX_AXES] = {0};
    rc = setup_node(&s, start);
    if (rc == 0) {
        const int errors = load_program(&s, program, text, len, start);
        if (errors != 0) {
            fprintf(stderr, errors < 0 ? "error: out of memory\n" : "%s: %d error(s): nothing was sent\n", program,
                    errors);
            rc = EXIT_PROGRAM;
        }
    }
    run_state st;
    memset(&st, 0, sizeof st);
    st.sync_ms = (int)sync_ms;
    st.tty_in = isatty(0) != 0;
    st.yes = yes;
    st.progress = prog_on || (isatty(2) && !prog_off);
    st.t0 = now_s();
    if (rc == 0) {
        uint32_t last;
        int64_t r = sdo_read(&s, 0x5004, 0, &last);
        rc = r != 0 ? fail_comm(&s, "last accepted sequence (0x5004)", r) : enable_axes(&s);
        st.seq0 = last + 1u;
    }
    if (rc == 0) {
        printf("%s: %zu blocks, %zu machine functions to node %u on %s (%d axes)\n", program, s.nb, s.ne,
               (unsigned)node_id, iface, s.n_axes);
        fflush(stdout);
        rc = stream_run(&s, &st);
        print_progress(&s, &st, true);
    }
    if (rc == 0) {
        path_command(&s, 4, "clear"); /* at rest: back to idle, ready for the next program */
        printf("done: %zu blocks in %.2f s, at", s.nb, now_s() - st.t0);
        static const char axis[ST_MAX_AXES] = {'X', 'Y', 'Z', 'A', 'B', 'C'};
        for (int k = 0; k < s.n_axes; k++) {
            uint32_t v = 0;
            sdo_read(&s, (uint16_t)(0x6062 + 0x800 * k), 0, &v);
            printf(" %c %.4f", axis[k], (double)(int32_t)v / s.cpm[k]);
        }
        printf("\n");
    }
    co_master_close(&s.m);
    free(s.b);
    free(s.e);
    free(text);
    return rc;
}
