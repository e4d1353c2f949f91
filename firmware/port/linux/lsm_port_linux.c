/*
 * lsm_port_linux.c: SocketCAN + timerfd + libgpiod 1.6 implementation of lsm_port.h (see lsm_port_linux.h).
 * Single-threaded: every function is called from the one thread that also runs lsm_port_idle(); only
 * lsm_port_linux_wake() may be called from a signal handler.
 */
#include "lsm_port_linux.h"

#include <errno.h>
#include <fcntl.h>
#include <gpiod.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/eventfd.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#define EVQ_CAP 16u

typedef struct port_state {
    bool configured, up;
    lsm_port_linux_config cfg;
    int can_fd, timer_fd, wake_fd;
    struct gpiod_chip *chip;
    struct gpiod_line *estop, *enable, *inpos;
    bool estop_broken; /* an E-stop line was configured but cannot be used: reads active */
    struct timespec t0;
    lsm_port_tick_fn tick_fn;
    void *tick_ctx;
    uint32_t tick_period_us;
    uint32_t last_dropcount;
    lsm_port_bus_event evq[EVQ_CAP];
    unsigned ev_head, ev_count;
    lsm_port_linux_stats stats;
    char err[160];
} port_state;

/* The port is a singleton by nature (one board): the only file-level state of the project's C code is here. */
static port_state g = {.can_fd = -1, .timer_fd = -1, .wake_fd = -1};

static void set_err(const char *what)
{
    snprintf(g.err, sizeof g.err, "%s: %s", what, strerror(errno));
}

const char *lsm_port_linux_last_error(void)
{
    return g.err;
}

lsm_port_linux_config lsm_port_linux_default_config(void)
{
    lsm_port_linux_config c;
    memset(&c, 0, sizeof c);
    c.estop_line = c.enable_line = c.inpos_line = -1;
    return c;
}

lsm_status lsm_port_linux_configure(const lsm_port_linux_config *cfg)
{
    if (cfg == NULL)
        return LSM_E_NULL;
    if (g.up)
        return LSM_E_STATE;
    g.cfg = *cfg;
    g.configured = true;
    return LSM_OK;
}

static void push_event(lsm_port_bus_event ev)
{
    if (g.ev_count == EVQ_CAP) { /* keep the newest: drop the oldest */
        g.ev_head = (g.ev_head + 1u) % EVQ_CAP;
        g.ev_count--;
    }
    g.evq[(g.ev_head + g.ev_count) % EVQ_CAP] = ev;
    g.ev_count++;
}

bool lsm_port_linux_bus_event(lsm_port_bus_event *ev)
{
    if (ev == NULL || g.ev_count == 0u)
        return false;
    *ev = g.evq[g.ev_head];
    g.ev_head = (g.ev_head + 1u) % EVQ_CAP;
    g.ev_count--;
    return true;
}

static lsm_status open_can(const char *ifname)
{
    int s = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
    if (s < 0) {
        set_err("socket(PF_CAN)");
        return LSM_E_PORT_IO;
    }
    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    if (strlen(ifname) >= sizeof ifr.ifr_name) {
        errno = ENAMETOOLONG;
        set_err(ifname);
        close(s);
        return LSM_E_PORT_IO;
    }
    strcpy(ifr.ifr_name, ifname);
    if (ioctl(s, SIOCGIFINDEX, &ifr) < 0) {
        set_err(ifname);
        close(s);
        return LSM_E_PORT_IO;
    }
    can_err_mask_t mask = CAN_ERR_TX_TIMEOUT | CAN_ERR_CRTL | CAN_ERR_BUSOFF | CAN_ERR_RESTARTED;
    int one = 1;
    if (setsockopt(s, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &mask, sizeof mask) < 0 ||
        setsockopt(s, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one) < 0) {
        set_err("setsockopt");
        close(s);
        return LSM_E_PORT_IO;
    }
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = ifr.ifr_ifindex;
    if (bind(s, (struct sockaddr *)&addr, sizeof addr) < 0) {
        set_err("bind");
        close(s);
        return LSM_E_PORT_IO;
    }
    g.can_fd = s;
    return LSM_OK;
}

static struct gpiod_line *request_line(int offset, bool output, int flags)
{
    if (offset < 0)
        return NULL;
    struct gpiod_line *l = gpiod_chip_get_line(g.chip, (unsigned)offset);
    if (l == NULL) {
        set_err("gpiod_chip_get_line");
        return NULL;
    }
    const char *who = g.cfg.consumer != NULL ? g.cfg.consumer : "lissom-node";
    int rc = output ? gpiod_line_request_output_flags(l, who, flags, 0) : gpiod_line_request_input_flags(l, who, flags);
    if (rc < 0) {
        set_err(output ? "gpiod_line_request_output" : "gpiod_line_request_input");
        return NULL;
    }
    return l;
}

static lsm_status open_gpio(void)
{
    g.chip = gpiod_chip_open_lookup(g.cfg.gpio_chip);
    if (g.chip == NULL) {
        set_err(g.cfg.gpio_chip);
        return LSM_E_PORT_IO;
    }
    int in_flags = g.cfg.estop_active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
    switch (g.cfg.estop_bias) {
    case 1: in_flags |= GPIOD_LINE_REQUEST_FLAG_BIAS_PULL_UP; break;
    case 2: in_flags |= GPIOD_LINE_REQUEST_FLAG_BIAS_PULL_DOWN; break;
    case 3: in_flags |= GPIOD_LINE_REQUEST_FLAG_BIAS_DISABLE; break;
    default: break;
    }
    int out_flags = g.cfg.outputs_active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
    g.estop = request_line(g.cfg.estop_line, false, in_flags);
    g.estop_broken = g.cfg.estop_line >= 0 && g.estop == NULL;
    g.enable = request_line(g.cfg.enable_line, true, out_flags);
    g.inpos = request_line(g.cfg.inpos_line, true, out_flags);
    if ((g.cfg.enable_line >= 0 && g.enable == NULL) || (g.cfg.inpos_line >= 0 && g.inpos == NULL) || g.estop_broken)
        return LSM_E_PORT_IO;
    return LSM_OK;
}

void lsm_port_linux_close(void)
{
    if (g.enable != NULL)
        (void)gpiod_line_set_value(g.enable, 0);
    if (g.inpos != NULL)
        (void)gpiod_line_set_value(g.inpos, 0);
    if (g.chip != NULL)
        gpiod_chip_close(g.chip); /* releases the lines */
    g.chip = NULL;
    g.estop = g.enable = g.inpos = NULL;
    g.estop_broken = false;
    if (g.can_fd >= 0)
        close(g.can_fd);
    if (g.timer_fd >= 0)
        close(g.timer_fd);
    if (g.wake_fd >= 0)
        close(g.wake_fd);
    g.can_fd = g.timer_fd = g.wake_fd = -1;
    g.tick_fn = NULL;
    g.up = false;
}

lsm_status lsm_port_init(void)
{
    if (g.up)
        lsm_port_linux_close();
    if (!g.configured) {
        g.cfg = lsm_port_linux_default_config();
        g.configured = true;
    }
    memset(&g.stats, 0, sizeof g.stats);
    g.ev_head = g.ev_count = 0u;
    g.last_dropcount = 0u;
    g.err[0] = '\0';
    clock_gettime(CLOCK_MONOTONIC, &g.t0);
    g.wake_fd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    g.timer_fd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    if (g.wake_fd < 0 || g.timer_fd < 0) {
        set_err("timerfd/eventfd");
        lsm_port_linux_close();
        return LSM_E_PORT_IO;
    }
    g.up = true;
    if (g.cfg.can_ifname != NULL && open_can(g.cfg.can_ifname) != LSM_OK) {
        char keep[sizeof g.err];
        memcpy(keep, g.err, sizeof keep);
        lsm_port_linux_close();
        memcpy(g.err, keep, sizeof keep);
        return LSM_E_PORT_IO;
    }
    if (g.cfg.gpio_chip != NULL && open_gpio() != LSM_OK) {
        char keep[sizeof g.err];
        memcpy(keep, g.err, sizeof keep);
        lsm_port_linux_close();
        memcpy(g.err, keep, sizeof keep);
        return LSM_E_PORT_IO;
    }
    return LSM_OK;
}

lsm_status lsm_port_can_send(const lsm_can_frame *frame)
{
    if (frame == NULL)
        return LSM_E_NULL;
    if (!g.up || g.can_fd < 0)
        return LSM_E_STATE;
    bool ext = (frame->flags & LSM_CAN_FLAG_EXT) != 0u;
    if (frame->dlc > LSM_CAN_MAX_DLC || frame->id > (ext ? LSM_CAN_EXT_ID_MAX : LSM_CAN_STD_ID_MAX))
        return LSM_E_ARG;
    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    cf.can_id = frame->id | (ext ? CAN_EFF_FLAG : 0u) | ((frame->flags & LSM_CAN_FLAG_RTR) ? CAN_RTR_FLAG : 0u);
    cf.len = frame->dlc;
    if (!(frame->flags & LSM_CAN_FLAG_RTR))
        memcpy(cf.data, frame->data, frame->dlc);
    ssize_t n = write(g.can_fd, &cf, sizeof cf);
    if (n == (ssize_t)sizeof cf) {
        g.stats.tx_frames++;
        return LSM_OK;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS)) {
        g.stats.tx_full++;
        return LSM_E_FULL;
    }
    g.stats.tx_errors++;
    set_err("write(can)");
    return LSM_E_PORT_IO;
}

/* One error frame (linux/can/error.h) -> bus events. */
static void error_frame(const struct can_frame *cf)
{
    g.stats.error_frames++;
    canid_t id = cf->can_id;
    if (id & CAN_ERR_BUSOFF)
        push_event(LSM_PORT_BUS_OFF);
    if ((id & CAN_ERR_CRTL) && cf->len >= 2u) {
        uint8_t c = cf->data[1];
        if (c & (CAN_ERR_CRTL_RX_OVERFLOW | CAN_ERR_CRTL_TX_OVERFLOW))
            push_event(LSM_PORT_BUS_RX_OVERRUN);
        if (c & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE))
            push_event(LSM_PORT_BUS_ERROR_PASSIVE);
        if (c & CAN_ERR_CRTL_ACTIVE)
            push_event(LSM_PORT_BUS_ERROR_ACTIVE);
    }
    if (id & CAN_ERR_RESTARTED)
        push_event(LSM_PORT_BUS_RESTARTED);
}

lsm_status lsm_port_can_recv(lsm_can_frame *frame)
{
    if (frame == NULL)
        return LSM_E_NULL;
    if (!g.up || g.can_fd < 0)
        return LSM_E_STATE;
    for (;;) {
        struct can_frame cf;
        struct iovec iov = {.iov_base = &cf, .iov_len = sizeof cf};
        char ctrl[CMSG_SPACE(sizeof(uint32_t))];
        struct msghdr msg;
        memset(&msg, 0, sizeof msg);
        msg.msg_iov = &iov;
        msg.msg_iovlen = 1;
        msg.msg_control = ctrl;
        msg.msg_controllen = sizeof ctrl;
        ssize_t n = recvmsg(g.can_fd, &msg, 0);
        if (n < 0) {
            if (errno == EAGAIN || errno == EWOULDBLOCK)
                return LSM_E_EMPTY;
            if (errno == EINTR)
                continue;
            set_err("recvmsg(can)");
            return LSM_E_PORT_IO;
        }
        for (struct cmsghdr *c = CMSG_FIRSTHDR(&msg); c != NULL; c = CMSG_NXTHDR(&msg, c)) {
            if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
                uint32_t drops;
                memcpy(&drops, CMSG_DATA(c), sizeof drops);
                if (drops != g.last_dropcount) {
                    g.stats.rx_dropped += drops - g.last_dropcount;
                    g.last_dropcount = drops;
                    push_event(LSM_PORT_BUS_RX_OVERRUN);
                }
            }
        }
        if (n != (ssize_t)sizeof cf)
            continue; /* not a classic frame (CAN FD is not enabled on this socket): ignore */
        if (cf.can_id & CAN_ERR_FLAG) {
            error_frame(&cf);
            continue;
        }
        memset(frame, 0, sizeof *frame);
        if (cf.can_id & CAN_EFF_FLAG) {
            frame->id = cf.can_id & CAN_EFF_MASK;
            frame->flags |= LSM_CAN_FLAG_EXT;
        } else {
            frame->id = cf.can_id & CAN_SFF_MASK;
        }
        if (cf.can_id & CAN_RTR_FLAG)
            frame->flags |= LSM_CAN_FLAG_RTR;
        frame->dlc = cf.len > LSM_CAN_MAX_DLC ? (uint8_t)LSM_CAN_MAX_DLC : cf.len;
        if (!(cf.can_id & CAN_RTR_FLAG))
            memcpy(frame->data, cf.data, frame->dlc);
        g.stats.rx_frames++;
        return LSM_OK;
    }
}

lsm_status lsm_port_gpio_read(lsm_gpio_in in, bool *active)
{
    if (active == NULL)
        return LSM_E_NULL;
    if ((unsigned)in >= (unsigned)LSM_GPIO_IN_COUNT)
        return LSM_E_ARG;
    *active = true; /* fail-safe default for every error below */
    if (!g.up)
        return LSM_E_STATE;
    if (g.estop_broken)
        return LSM_E_PORT_IO;
    if (g.estop == NULL)
        return LSM_E_PORT_UNSUPPORTED;
    int v = gpiod_line_get_value(g.estop);
    if (v < 0) {
        set_err("gpiod_line_get_value");
        return LSM_E_PORT_IO;
    }
    *active = v != 0;
    return LSM_OK;
}

lsm_status lsm_port_gpio_write(lsm_gpio_out out, bool active)
{
    if ((unsigned)out >= (unsigned)LSM_GPIO_OUT_COUNT)
        return LSM_E_ARG;
    if (!g.up)
        return LSM_E_STATE;
    struct gpiod_line *l = out == LSM_GPIO_OUT_DRIVE_ENABLE ? g.enable : g.inpos;
    if (l == NULL)
        return LSM_E_PORT_UNSUPPORTED;
    if (gpiod_line_set_value(l, active ? 1 : 0) < 0) {
        set_err("gpiod_line_set_value");
        return LSM_E_PORT_IO;
    }
    return LSM_OK;
}

static uint32_t elapsed_us(const struct timespec *a, const struct timespec *b)
{
    int64_t ns = (int64_t)(b->tv_sec - a->tv_sec) * 1000000000LL + (b->tv_nsec - a->tv_nsec);
    return (uint32_t)(uint64_t)(ns / 1000);
}

lsm_status lsm_port_tick_start(uint32_t period_us, lsm_port_tick_fn fn, void *ctx)
{
    if (fn == NULL)
        return LSM_E_NULL;
    if (period_us == 0u || period_us > 10000000u)
        return LSM_E_ARG;
    if (!g.up)
        return LSM_E_STATE;
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    struct itimerspec its;
    memset(&its, 0, sizeof its);
    its.it_interval.tv_sec = period_us / 1000000u;
    its.it_interval.tv_nsec = (long)(period_us % 1000000u) * 1000L;
    its.it_value = now;
    its.it_value.tv_sec += its.it_interval.tv_sec;
    its.it_value.tv_nsec += its.it_interval.tv_nsec;
    if (its.it_value.tv_nsec >= 1000000000L) {
        its.it_value.tv_sec++;
        its.it_value.tv_nsec -= 1000000000L;
    }
    g.tick_fn = fn;
    g.tick_ctx = ctx;
    g.tick_period_us = period_us;
    if (timerfd_settime(g.timer_fd, TFD_TIMER_ABSTIME, &its, NULL) < 0) {
        set_err("timerfd_settime");
        g.tick_fn = NULL;
        return LSM_E_PORT_IO;
    }
    return LSM_OK;
}

lsm_status lsm_port_tick_stop(void)
{
    if (!g.up)
        return LSM_OK;
    struct itimerspec its;
    memset(&its, 0, sizeof its);
    (void)timerfd_settime(g.timer_fd, 0, &its, NULL);
    g.tick_fn = NULL;
    return LSM_OK;
}

uint32_t lsm_port_tick_overruns(void)
{
    return g.stats.overruns;
}

uint32_t lsm_port_time_us(void)
{
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return elapsed_us(&g.t0, &now);
}

void lsm_port_idle(void)
{
    if (!g.up)
        return;
    struct pollfd p[2] = {{.fd = g.timer_fd, .events = POLLIN}, {.fd = g.wake_fd, .events = POLLIN}};
    int rc = poll(p, 2, g.tick_fn != NULL ? -1 : 10);
    if (rc <= 0)
        return; /* timeout or signal */
    if (p[1].revents & POLLIN) {
        uint64_t v;
        (void)read(g.wake_fd, &v, sizeof v);
    }
    if (p[0].revents & POLLIN) {
        uint64_t expirations = 0;
        if (read(g.timer_fd, &expirations, sizeof expirations) != (ssize_t)sizeof expirations || expirations == 0u)
            return;
        if (expirations > 1u)
            g.stats.overruns += (uint32_t)(expirations - 1u);
        if (g.tick_fn != NULL) {
            struct timespec a, b;
            clock_gettime(CLOCK_MONOTONIC, &a);
            g.tick_fn(g.tick_ctx);
            clock_gettime(CLOCK_MONOTONIC, &b);
            uint32_t d = elapsed_us(&a, &b);
            if (d > g.stats.tick_max_us)
                g.stats.tick_max_us = d;
            g.stats.ticks++;
        }
    }
}

void lsm_port_linux_wake(void)
{
    if (g.wake_fd >= 0) {
        uint64_t one = 1;
        ssize_t r = write(g.wake_fd, &one, sizeof one);
        (void)r;
    }
}

bool lsm_port_linux_has_gpio(void)
{
    return g.chip != NULL;
}

bool lsm_port_linux_has_estop(void)
{
    return g.estop != NULL || g.estop_broken;
}

void lsm_port_linux_get_stats(lsm_port_linux_stats *out)
{
    if (out != NULL)
        *out = g.stats;
}
