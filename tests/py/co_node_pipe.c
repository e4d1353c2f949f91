/*
 * co_node_pipe.c: a Lissom CANopen node on stdin/stdout, for interoperability tests with python-canopen
 * (tests/py/test_co_interop.py) without any CAN hardware. Host test tool, not firmware, not the daemon.
 *
 *   co_node_pipe <node_id> <n_axes>
 *
 * Lines in:   F <id hex> <dlc> <data hex>   a frame for the node
 *             E <0|1>                       E-stop input level
 *             B <n>                         lsm_can_bus_event n
 *             Q                             quit
 * Lines out:  F <id hex> <dlc> <data hex>   a frame from the node
 *
 * The application is a toy (not the S-curve engine): each cycle (1 ms of the monotonic clock) an axis
 * moves at most `velocity` counts/s towards its goal (PP set-point target, CSP target, path block end),
 * stops at once when a stop is requested, and reports itself back. Good enough to drive the hand-shakes.
 */
#define _POSIX_C_SOURCE 200809L
#include <inttypes.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "canopen.h"

static lsm_canopen node;
static lsm_can_frame txbuf[256];
static lsm_co_path_block blocks[16];

typedef struct sim_axis {
    int64_t pos;
    int64_t goal;
    uint32_t vel; /* counts/s */
    bool moving;
} sim_axis;

static sim_axis sim[LSM_MAX_AXES];
static bool path_block_active;
static lsm_co_path_block path_block;
static uint32_t path_seq_reported; /* the block being executed, or the last one executed */

static uint32_t now_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint32_t)((uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u);
}

static void emit(void)
{
    lsm_can_frame f;
    while (lsm_canopen_tx_pop(&node, &f)) {
        printf("F %03" PRIX32 " %u ", f.id, f.dlc);
        for (unsigned i = 0; i < f.dlc; i++)
            printf("%02X", f.data[i]);
        printf("\n");
    }
    fflush(stdout);
}

static int hexval(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    return -1;
}

static bool line(char *s, uint32_t t, bool *estop)
{
    if (s[0] == 'Q')
        return false;
    if (s[0] == 'E') {
        *estop = atoi(s + 1) != 0;
    } else if (s[0] == 'B') {
        lsm_canopen_bus_event(&node, (lsm_can_bus_event)atoi(s + 1), t);
    } else if (s[0] == 'F') {
        lsm_can_frame f;
        memset(&f, 0, sizeof f);
        char *p = s + 1;
        f.id = (uint32_t)strtoul(p, &p, 16);
        f.dlc = (uint8_t)strtoul(p, &p, 10);
        while (*p == ' ')
            p++;
        for (unsigned i = 0; i < f.dlc && i < 8; i++) {
            int hi = hexval(p[2 * i]), lo = hexval(p[2 * i + 1]);
            if (hi < 0 || lo < 0)
                break;
            f.data[i] = (uint8_t)(hi * 16 + lo);
        }
        (void)lsm_canopen_rx(&node, &f, t);
    }
    return true;
}

static void step_axis(size_t k, uint32_t dt_us)
{
    sim_axis *s = &sim[k];
    if (!s->moving)
        return;
    int64_t step = (int64_t)s->vel * dt_us / 1000000 + 1;
    int64_t d = s->goal - s->pos;
    if (d > step)
        s->pos += step;
    else if (d < -step)
        s->pos -= step;
    else {
        s->pos = s->goal;
        s->moving = false;
    }
}

static void application(uint32_t dt_us)
{
    lsm_co_path *path = lsm_canopen_path(&node);
    lsm_co_path_motion pm = lsm_co_path_get_motion(path);
    for (size_t k = 0; k < node.n_axes; k++) {
        lsm_cia402 *ax = lsm_canopen_axis(&node, k);
        sim_axis *s = &sim[k];
        if (lsm_cia402_stop_request(ax, NULL) != LSM_CIA402_STOP_NONE) {
            s->moving = false; /* a toy: stops at once */
        } else if (ax->mode_display == LSM_CIA402_MODE_PP) {
            lsm_cia402_setpoint sp;
            if (lsm_cia402_pp_fetch(ax, &sp) != LSM_CIA402_SP_NONE) {
                s->goal = sp.target;
                s->vel = sp.velocity;
                s->moving = true;
            }
            bool was = s->moving;
            step_axis(k, dt_us);
            if (was && !s->moving)
                lsm_cia402_pp_done(ax);
        } else if (ax->mode_display == LSM_CIA402_MODE_CSP) {
            int32_t t;
            if (lsm_cia402_csp_fetch(ax, &t)) {
                s->goal = t;
                s->vel = 1000000000u;
                s->moving = true;
            }
            step_axis(k, dt_us);
        }
    }
    /* path: one block at a time, each axis straight to the block's end at the block's feed */
    if (pm == LSM_CO_PATH_MOTION_RUN) {
        if (!path_block_active && lsm_co_path_pop(path, &path_block) == LSM_OK) {
            path_block_active = true;
            path_seq_reported = path_block.seq;
            for (size_t k = 0; k < node.n_axes; k++) {
                sim[k].goal = path_block.end[k];
                sim[k].vel = path_block.feed_um_s;
                sim[k].moving = true;
            }
        }
        if (path_block_active) {
            bool any = false;
            for (size_t k = 0; k < node.n_axes; k++) {
                step_axis(k, dt_us);
                any = any || sim[k].moving;
            }
            if (!any)
                path_block_active = false;
        }
    } else if (pm != LSM_CO_PATH_MOTION_IDLE) {
        for (size_t k = 0; k < node.n_axes; k++)
            sim[k].moving = false;
    }
    bool rest = true;
    for (size_t k = 0; k < node.n_axes; k++) {
        lsm_cia402 *ax = lsm_canopen_axis(&node, k);
        lsm_cia402_feedback fb = {(int32_t)sim[k].pos, (int32_t)sim[k].pos, sim[k].moving ? (int32_t)sim[k].vel : 0,
                                  !sim[k].moving};
        lsm_cia402_update(ax, &fb, now_us());
        rest = rest && !sim[k].moving;
    }
    lsm_co_path_report rep = {path_seq_reported, path_block_active ? path_block.feed_um_s : 0u, rest,
                              pm == LSM_CO_PATH_MOTION_RUN && !path_block_active && lsm_co_path_count(path) == 0};
    lsm_co_path_update(path, &rep);
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: co_node_pipe <node_id> <n_axes>\n");
        return 2;
    }
    lsm_canopen_config c = lsm_canopen_default_config();
    c.node_id = (uint8_t)strtoul(argv[1], NULL, 0);
    c.n_axes = (uint8_t)strtoul(argv[2], NULL, 0);
    c.heartbeat_ms = 0;
    c.tx_storage = txbuf;
    c.tx_cap = sizeof txbuf / sizeof txbuf[0];
    c.path_storage = blocks;
    c.path_cap = sizeof blocks / sizeof blocks[0];
    uint32_t t = now_us();
    if (lsm_canopen_init(&node, &c, t) != LSM_OK)
        return 1;
    emit();
    char buf[4096];
    size_t used = 0;
    bool estop = false, running = true;
    uint32_t last = t;
    while (running) {
        struct pollfd pfd = {0, POLLIN, 0};
        int r = poll(&pfd, 1, 1);
        t = now_us();
        if (r > 0 && (pfd.revents & (POLLIN | POLLHUP))) {
            ssize_t n = read(0, buf + used, sizeof buf - used - 1);
            if (n <= 0)
                break;
            used += (size_t)n;
            buf[used] = '\0';
            char *start = buf, *nl;
            while (running && (nl = strchr(start, '\n')) != NULL) {
                *nl = '\0';
                running = line(start, t, &estop);
                start = nl + 1;
                emit();
            }
            used -= (size_t)(start - buf);
            memmove(buf, start, used);
        }
        lsm_canopen_estop(&node, estop, t);
        lsm_canopen_process(&node, t);
        if ((int32_t)(t - last) >= 1000) {
            application(t - last);
            last = t;
        }
        emit();
    }
    return 0;
}
