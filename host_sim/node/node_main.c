/*
 * node_main.c: lissom-node, the Lissom firmware as a Linux daemon on SocketCAN (see docs/hil.md).
 *
 *   lissom-node [--iface vcan0] [--node-id 1] [--axes N] [--cycle-us 1000] [--machine FILE] [GPIO options]
 *
 * The control cycle runs from the Linux port's timerfd tick: received frames and bus events -> node_app (the
 * CANopen node, CiA 402 axes, path executor, simulated drives) -> frames sent, GPIO outputs driven, a trace row
 * written (--trace). SIGTERM / SIGINT: every axis quick-stops (jerk-limited), the daemon waits for standstill
 * (at most 3 s), sets the outputs inactive, closes the socket and exits 0. A second signal exits at once.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

#include "lsm_port_linux.h"
#include "node_app.h"

#define NODE_VERSION "0.1.0"

typedef struct options {
    const char *iface;
    int node_id, axes, cycle_us, heartbeat_ms, master_id, master_timeout_ms, path_slots, path_exec, lookahead;
    const char *machine;
    const char *trace;
    double run_for_s;
    int rt_prio;
    bool verbose, stats;
    lsm_port_linux_config port;
} options;

typedef struct daemon_state {
    node_app *app;
    options *opt;
    FILE *trace;
    double *row;
    size_t ncols;
    lsm_can_frame pending;
    bool have_pending;
    bool has_estop;
    bool out_enable, out_inpos, outputs_known;
    bool stopping, done;
    uint32_t stop_started_us;
    uint64_t max_cycles;
    uint32_t tx_dropped;
    uint32_t bus_events;
} daemon_state;

static volatile sig_atomic_t g_signals;

static void on_signal(int sig)
{
    (void)sig;
    g_signals++;
    if (g_signals > 1)
        _exit(3);
    lsm_port_linux_wake();
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: lissom-node [options]\n"
            "  -i, --iface NAME           SocketCAN interface (default vcan0; can0 for a real bus)\n"
            "  -n, --node-id N            CANopen node id 1..127 (default 1)\n"
            "  -a, --axes N               number of CiA 402 axes (default: the machine's, 3 built-in)\n"
            "  -c, --cycle-us N           control cycle in us (default: the machine's cycle_s, else 1000)\n"
            "  -m, --machine FILE         machine file (host_sim/machines/*.json): limits and simulated drives\n"
            "      --heartbeat-ms N       heartbeat producer time 0x1017 (default 100, 0 = off)\n"
            "      --master-id N          monitor the heartbeat of node N (0x1016 sub 1; default none)\n"
            "      --master-timeout-ms N  its consumer time (default 0 = not monitored)\n"
            "      --path-slots N         path buffer capacity in blocks (default 64, at most %d)\n"
            "      --lookahead N          planner block storage (default: the machine's lookahead_blocks, 64;\n"
            "                             8..256; a block with a blended corner takes 3)\n"
            "      --path-exec E          planner (default: look-ahead, corner blending) or exact (exact stop\n"
            "                             at every block end)\n"
            "      --gpio-chip NAME       libgpiod chip (gpiochip0, /dev/gpiochip0, label or number)\n"
            "      --estop-line N         E-stop input line offset (active = stop requested)\n"
            "      --estop-active-low     the E-stop input is active when the line reads 0\n"
            "      --estop-bias B         as-is (default), pull-up, pull-down or disable\n"
            "      --enable-line N        drive-enable output line offset\n"
            "      --inpos-line N         in-position output line offset\n"
            "      --outputs-active-low   outputs drive 0 when active\n"
            "      --no-gpio              no GPIO at all (default when --gpio-chip is not given)\n"
            "      --trace FILE           binary per-cycle trace (docs/hil.md; read by lissom_hil.trace)\n"
            "      --run-for S            exit by itself after S seconds (demos)\n"
            "      --rt PRIO              SCHED_FIFO priority PRIO and locked memory (needs privileges)\n"
            "      --stats                print port and node counters on exit\n"
            "  -v, --verbose              log bus events and state changes to stderr\n"
            "  -h, --help                 this text;  --version  the version\n",
            NODE_APP_PATH_SLOTS_MAX);
}

static int parse_int(const char *s, int lo, int hi, const char *what)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 0);
    if (errno != 0 || end == s || *end != '\0' || v < lo || v > hi) {
        fprintf(stderr, "lissom-node: %s: '%s' is not an integer in %d..%d\n", what, s, lo, hi);
        exit(2);
    }
    return (int)v;
}

enum {
    O_HB = 1000,
    O_MASTER,
    O_MASTER_TMO,
    O_SLOTS,
    O_CHIP,
    O_ESTOP,
    O_ESTOP_LOW,
    O_ESTOP_BIAS,
    O_ENABLE,
    O_INPOS,
    O_OUT_LOW,
    O_NO_GPIO,
    O_TRACE,
    O_RUN_FOR,
    O_RT,
    O_STATS,
    O_VERSION,
    O_PATH_EXEC,
    O_LOOKAHEAD
};

static void parse(int argc, char **argv, options *o)
{
    static const struct option longs[] = {{"iface", required_argument, 0, 'i'},
                                          {"node-id", required_argument, 0, 'n'},
                                          {"axes", required_argument, 0, 'a'},
                                          {"cycle-us", required_argument, 0, 'c'},
                                          {"machine", required_argument, 0, 'm'},
                                          {"heartbeat-ms", required_argument, 0, O_HB},
                                          {"master-id", required_argument, 0, O_MASTER},
                                          {"master-timeout-ms", required_argument, 0, O_MASTER_TMO},
                                          {"path-slots", required_argument, 0, O_SLOTS},
                                          {"gpio-chip", required_argument, 0, O_CHIP},
                                          {"path-exec", required_argument, 0, O_PATH_EXEC},
                                          {"lookahead", required_argument, 0, O_LOOKAHEAD},
                                          {"estop-line", required_argument, 0, O_ESTOP},
                                          {"estop-active-low", no_argument, 0, O_ESTOP_LOW},
                                          {"estop-bias", required_argument, 0, O_ESTOP_BIAS},
                                          {"enable-line", required_argument, 0, O_ENABLE},
                                          {"inpos-line", required_argument, 0, O_INPOS},
                                          {"outputs-active-low", no_argument, 0, O_OUT_LOW},
                                          {"no-gpio", no_argument, 0, O_NO_GPIO},
                                          {"trace", required_argument, 0, O_TRACE},
                                          {"run-for", required_argument, 0, O_RUN_FOR},
                                          {"rt", required_argument, 0, O_RT},
                                          {"stats", no_argument, 0, O_STATS},
                                          {"verbose", no_argument, 0, 'v'},
                                          {"help", no_argument, 0, 'h'},
                                          {"version", no_argument, 0, O_VERSION},
                                          {0, 0, 0, 0}};
    memset(o, 0, sizeof *o);
    o->iface = "vcan0";
    o->node_id = 1;
    o->heartbeat_ms = 100;
    o->path_slots = 64;
    o->port = lsm_port_linux_default_config();
    bool no_gpio = false;
    int c;
    while ((c = getopt_long(argc, argv, "i:n:a:c:m:vh", longs, NULL)) != -1) {
        switch (c) {
        case 'i': o->iface = optarg; break;
        case 'n': o->node_id = parse_int(optarg, 1, 127, "--node-id"); break;
        case 'a': o->axes = parse_int(optarg, 1, LSM_MAX_AXES, "--axes"); break;
        case 'c': o->cycle_us = parse_int(optarg, 100, 100000, "--cycle-us"); break;
        case 'm': o->machine = optarg; break;
        case O_HB: o->heartbeat_ms = parse_int(optarg, 0, 65535, "--heartbeat-ms"); break;
        case O_MASTER: o->master_id = parse_int(optarg, 0, 127, "--master-id"); break;
        case O_MASTER_TMO: o->master_timeout_ms = parse_int(optarg, 0, 65535, "--master-timeout-ms"); break;
        case O_SLOTS: o->path_slots = parse_int(optarg, 1, NODE_APP_PATH_SLOTS_MAX, "--path-slots"); break;
        case O_LOOKAHEAD: o->lookahead = parse_int(optarg, 8, NODE_APP_LOOKAHEAD_MAX, "--lookahead"); break;
        case O_PATH_EXEC:
            if (!strcmp(optarg, "planner"))
                o->path_exec = NODE_APP_PATH_PLANNER;
            else if (!strcmp(optarg, "exact"))
                o->path_exec = NODE_APP_PATH_EXACT;
            else {
                fprintf(stderr, "lissom-node: --path-exec: planner or exact\n");
                exit(2);
            }
            break;
        case O_CHIP: o->port.gpio_chip = optarg; break;
        case O_ESTOP: o->port.estop_line = parse_int(optarg, 0, 65535, "--estop-line"); break;
        case O_ESTOP_LOW: o->port.estop_active_low = true; break;
        case O_ESTOP_BIAS:
            if (!strcmp(optarg, "as-is"))
                o->port.estop_bias = 0;
            else if (!strcmp(optarg, "pull-up"))
                o->port.estop_bias = 1;
            else if (!strcmp(optarg, "pull-down"))
                o->port.estop_bias = 2;
            else if (!strcmp(optarg, "disable"))
                o->port.estop_bias = 3;
            else {
                fprintf(stderr, "lissom-node: --estop-bias: as-is, pull-up, pull-down or disable\n");
                exit(2);
            }
            break;
        case O_ENABLE: o->port.enable_line = parse_int(optarg, 0, 65535, "--enable-line"); break;
        case O_INPOS: o->port.inpos_line = parse_int(optarg, 0, 65535, "--inpos-line"); break;
        case O_OUT_LOW: o->port.outputs_active_low = true; break;
        case O_NO_GPIO: no_gpio = true; break;
        case O_TRACE: o->trace = optarg; break;
        case O_RUN_FOR: {
            char *end;
            o->run_for_s = strtod(optarg, &end);
            if (end == optarg || *end || !(o->run_for_s > 0) || !isfinite(o->run_for_s)) {
                fprintf(stderr, "lissom-node: --run-for: a positive number of seconds\n");
                exit(2);
            }
            break;
        }
        case O_RT: o->rt_prio = parse_int(optarg, 1, 99, "--rt"); break;
        case O_STATS: o->stats = true; break;
        case 'v': o->verbose = true; break;
        case 'h': usage(stdout); exit(0);
        case O_VERSION: printf("lissom-node %s\n", NODE_VERSION); exit(0);
        default: usage(stderr); exit(2);
        }
    }
    if (optind < argc) {
        fprintf(stderr, "lissom-node: unexpected argument '%s'\n", argv[optind]);
        usage(stderr);
        exit(2);
    }
    if (no_gpio)
        o->port.gpio_chip = NULL;
    if (o->port.gpio_chip == NULL && (o->port.estop_line >= 0 || o->port.enable_line >= 0 || o->port.inpos_line >= 0)) {
        fprintf(stderr, "lissom-node: GPIO lines given without --gpio-chip\n");
        exit(2);
    }
    o->port.can_ifname = o->iface;
    o->port.consumer = "lissom-node";
}

/* ---- trace ---- */

static const char *k_node_cols[] = {"t_s",   "t_real_s",   "cycle",    "nmt",       "estop",    "enable",
                                    "inpos", "path_state", "path_seq", "path_free", "feed_mm_s"};
static const char *k_axis_cols[] = {"set_mm", "act_mm", "v_mm_s", "a_mm_s2", "j_mm_s3",
                                    "err_mm", "sw",     "state",  "mode",    "tgt_mm"};
#define N_NODE_COLS (sizeof k_node_cols / sizeof k_node_cols[0])
#define N_AXIS_COLS (sizeof k_axis_cols / sizeof k_axis_cols[0])

static int trace_open(daemon_state *d)
{
    d->trace = fopen(d->opt->trace, "wb");
    if (d->trace == NULL) {
        fprintf(stderr, "lissom-node: --trace %s: %s\n", d->opt->trace, strerror(errno));
        return -1;
    }
    const node_app *app = d->app;
    d->ncols = N_NODE_COLS + N_AXIS_COLS * app->cfg.n_axes;
    d->row = calloc(d->ncols, sizeof(double));
    if (d->row == NULL)
        return -1;
    fprintf(d->trace, "LSMTRACE1 %zu %.9g\n", d->ncols, app->cycle_s);
    for (size_t i = 0; i < N_NODE_COLS; i++)
        fprintf(d->trace, "%s%s", i ? "," : "", k_node_cols[i]);
    for (unsigned k = 0; k < app->cfg.n_axes; k++)
        for (size_t i = 0; i < N_AXIS_COLS; i++)
            fprintf(d->trace, ",%c_%s", app->machine.axes[k].name, k_axis_cols[i]);
    fputc('\n', d->trace);
    return 0;
}

static void trace_row(daemon_state *d, uint32_t now_us)
{
    const node_app *app = d->app;
    const lsm_co_path *cp = &app->co.path;
    double *r = d->row;
    size_t i = 0;
    r[i++] = (double)app->cycles * app->cycle_s;
    r[i++] = (double)now_us * 1e-6;
    r[i++] = (double)app->cycles;
    r[i++] = (double)app->co.nmt.state;
    r[i++] = app->estop;
    r[i++] = app->out_enable;
    r[i++] = app->out_inpos;
    r[i++] = cp->state;
    r[i++] = (double)cp->active_seq;
    r[i++] = cp->free_slots;
    r[i++] = (double)cp->feed_um_s / 1000.0;
    for (unsigned k = 0; k < app->cfg.n_axes; k++) {
        const lsm_kin *dm = lsm_motion_demand(&app->mo, k);
        const lsm_cia402 *ax = &app->co.axis[k];
        r[i++] = dm->s_mm;
        r[i++] = app->actual[k];
        r[i++] = dm->v_mm_s;
        r[i++] = dm->a_mm_s2;
        r[i++] = dm->j_mm_s3;
        r[i++] = dm->s_mm - app->actual[k];
        r[i++] = ax->statusword;
        r[i++] = ax->state;
        r[i++] = ax->mode_display;
        r[i++] = (double)ax->target / (double)ax->counts_per_mm;
    }
    fwrite(r, sizeof(double), d->ncols, d->trace);
    if (app->cycles % 64u == 0u)
        fflush(d->trace);
}

/* ---- the tick ---- */

static lsm_can_bus_event map_event(lsm_port_bus_event e)
{
    switch (e) {
    case LSM_PORT_BUS_ERROR_PASSIVE: return LSM_CAN_BUS_ERROR_PASSIVE;
    case LSM_PORT_BUS_OFF: return LSM_CAN_BUS_OFF;
    case LSM_PORT_BUS_RX_OVERRUN: return LSM_CAN_BUS_RX_OVERRUN;
    default: return LSM_CAN_BUS_OK; /* back to error active, restarted */
    }
}

static const char *event_name(lsm_port_bus_event e)
{
    switch (e) {
    case LSM_PORT_BUS_ERROR_ACTIVE: return "error active";
    case LSM_PORT_BUS_ERROR_PASSIVE: return "error passive";
    case LSM_PORT_BUS_OFF: return "bus-off";
    case LSM_PORT_BUS_RESTARTED: return "restarted";
    case LSM_PORT_BUS_RX_OVERRUN: return "rx overrun";
    default: return "?";
    }
}

static void send_frames(daemon_state *d)
{
    for (;;) {
        if (!d->have_pending) {
            if (!node_app_tx_pop(d->app, &d->pending))
                return;
            d->have_pending = true;
        }
        lsm_status st = lsm_port_can_send(&d->pending);
        if (st == LSM_E_FULL)
            return; /* the socket queue is full: retry this frame next cycle */
        if (st != LSM_OK)
            d->tx_dropped++; /* interface down / bus-off: the frame is lost (the controller reports the bus state) */
        d->have_pending = false;
    }
}

static void tick(void *ctx)
{
    daemon_state *d = ctx;
    node_app *app = d->app;
    const uint32_t now = lsm_port_time_us();
    lsm_port_bus_event ev;
    while (lsm_port_linux_bus_event(&ev)) {
        d->bus_events++;
        if (d->opt->verbose)
            fprintf(stderr, "lissom-node: bus event: %s\n", event_name(ev));
        node_app_bus_event(app, map_event(ev), now);
    }
    lsm_can_frame f;
    for (int n = 0; n < 512 && lsm_port_can_recv(&f) == LSM_OK; n++)
        (void)node_app_rx(app, &f, now);
    bool estop = false;
    if (d->has_estop && lsm_port_gpio_read(LSM_GPIO_IN_ESTOP, &estop) != LSM_OK)
        estop = true; /* fail-safe */
    if (g_signals > 0 && !d->stopping) {
        d->stopping = true;
        d->stop_started_us = now;
        node_app_stop_all(app);
    }
    node_app_cycle(app, estop, now);
    if (!d->outputs_known || app->out_enable != d->out_enable) {
        (void)lsm_port_gpio_write(LSM_GPIO_OUT_DRIVE_ENABLE, app->out_enable);
        d->out_enable = app->out_enable;
    }
    if (!d->outputs_known || app->out_inpos != d->out_inpos) {
        (void)lsm_port_gpio_write(LSM_GPIO_OUT_IN_POSITION, app->out_inpos);
        d->out_inpos = app->out_inpos;
    }
    d->outputs_known = true;
    send_frames(d);
    if (d->trace != NULL)
        trace_row(d, now);
    if (d->stopping && (node_app_at_rest(app) || (uint32_t)(now - d->stop_started_us) > 3000000u))
        d->done = true;
    if (d->max_cycles != 0u && app->cycles >= d->max_cycles)
        d->done = true;
}

int main(int argc, char **argv)
{
    static options opt;
    static node_app app;
    static sim_machine machine;
    parse(argc, argv, &opt);

    const sim_machine *mp = NULL;
    if (opt.machine != NULL) {
        char err[256];
        sim_machine_status ms = sim_machine_load_file(opt.machine, &machine, err, sizeof err);
        if (ms != SIM_MACHINE_OK) {
            fprintf(stderr, "lissom-node: %s\n", err);
            return 2;
        }
        mp = &machine;
    }
    int axes = opt.axes;
    if (axes == 0)
        axes = mp != NULL ? mp->n_axes : 3;
    if (mp != NULL && axes > mp->n_axes) {
        fprintf(stderr, "lissom-node: --axes %d but the machine has %d axes\n", axes, mp->n_axes);
        return 2;
    }
    int cycle_us = opt.cycle_us;
    if (cycle_us == 0)
        cycle_us = mp != NULL ? (int)lround(mp->cycle_s * 1e6) : 1000;
    node_app_config cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.node_id = (uint8_t)opt.node_id;
    cfg.n_axes = (uint8_t)axes;
    cfg.cycle_us = (uint32_t)cycle_us;
    cfg.heartbeat_ms = (uint16_t)opt.heartbeat_ms;
    cfg.master_id = (uint8_t)opt.master_id;
    cfg.master_timeout_ms = (uint16_t)opt.master_timeout_ms;
    cfg.path_slots = (uint16_t)opt.path_slots;
    cfg.path_exec = (uint8_t)opt.path_exec;
    cfg.lookahead_blocks = (uint16_t)opt.lookahead;
    cfg.machine = mp;

    if (lsm_port_linux_configure(&opt.port) != LSM_OK || lsm_port_init() != LSM_OK) {
        fprintf(stderr, "lissom-node: port: %s\n", lsm_port_linux_last_error());
        return 1;
    }
    lsm_status st = node_app_init(&app, &cfg, lsm_port_time_us());
    if (st != LSM_OK) {
        fprintf(stderr, "lissom-node: init: %s\n", lsm_status_str(st));
        lsm_port_linux_close();
        return 2;
    }
    if (opt.rt_prio > 0) {
        struct sched_param sp = {.sched_priority = opt.rt_prio};
        if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0 || mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
            fprintf(stderr, "lissom-node: --rt %d: %s (running without)\n", opt.rt_prio, strerror(errno));
    }
    static daemon_state d;
    d.app = &app;
    d.opt = &opt;
    d.has_estop = lsm_port_linux_has_estop();
    if (opt.run_for_s > 0)
        d.max_cycles = (uint64_t)ceil(opt.run_for_s / app.cycle_s);
    if (opt.trace != NULL && trace_open(&d) != 0) {
        lsm_port_linux_close();
        return 1;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);

    send_frames(&d); /* the boot-up frame */
    if (lsm_port_tick_start((uint32_t)cycle_us, tick, &d) != LSM_OK) {
        fprintf(stderr, "lissom-node: tick: %s\n", lsm_port_linux_last_error());
        lsm_port_linux_close();
        return 1;
    }
    printf("lissom-node: ready iface=%s node=%d axes=%d cycle_us=%d machine=%s path=%s gpio=%s estop=%s\n", opt.iface,
           opt.node_id, axes, cycle_us, app.machine.name, opt.path_exec == NODE_APP_PATH_EXACT ? "exact" : "planner",
           lsm_port_linux_has_gpio() ? opt.port.gpio_chip : "none", d.has_estop ? "yes" : "no");
    fflush(stdout);
    while (!d.done)
        lsm_port_idle();
    (void)lsm_port_tick_stop();
    (void)lsm_port_gpio_write(LSM_GPIO_OUT_DRIVE_ENABLE, false);
    (void)lsm_port_gpio_write(LSM_GPIO_OUT_IN_POSITION, false);
    lsm_port_linux_stats ps;
    lsm_port_linux_get_stats(&ps);
    lsm_port_linux_close();
    if (d.trace != NULL)
        fclose(d.trace);
    free(d.row);
    if (opt.stats || opt.verbose)
        fprintf(stderr,
                "lissom-node: exit: cycles %llu, ticks %u, overruns %u, longest tick %u us, rx %u, tx %u "
                "(socket full %u, lost %u), error frames %u, rx dropped %u, frames refused %u, malformed %u\n",
                (unsigned long long)app.cycles, ps.ticks, ps.overruns, ps.tick_max_us, ps.rx_frames, ps.tx_frames,
                ps.tx_full, d.tx_dropped, ps.error_frames, ps.rx_dropped, app.rx_errors, app.co.malformed);
    if (opt.stats || opt.verbose)
        fprintf(stderr,
                "lissom-node: path: planner blocks %u, refused %u, restarts %u, underrun restarts %u, stuck %u; "
                "exact-stop blocks %u\n",
                app.mo.feed.appended, app.mo.feed.rejected, app.mo.feed.restarts, app.mo.feed.underrun_restarts,
                app.mo.feed.stuck, app.mo.path.blocks_done);
    return 0;
}
