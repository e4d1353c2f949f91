/* co_master.c: a small CANopen master on SocketCAN (see co_master.h). */
#define _DEFAULT_SOURCE /* struct ifreq, IFNAMSIZ */
#include "co_master.h"

#include <errno.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#define SDO_TX 0x600u
#define SDO_RX 0x580u

int co_master_open(co_master *m, const char *iface, uint8_t node_id)
{
    memset(m, 0, sizeof *m);
    m->fd = -1;
    m->node_id = node_id;
    m->sdo_timeout_ms = 1000;
    if (strlen(iface) >= IFNAMSIZ) {
        snprintf(m->err, sizeof m->err, "interface name too long: %s", iface);
        return -1;
    }
    int fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    if (fd < 0) {
        snprintf(m->err, sizeof m->err, "CAN socket: %s (does this kernel have SocketCAN?)", strerror(errno));
        return -1;
    }
    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    snprintf(ifr.ifr_name, sizeof ifr.ifr_name, "%s", iface);
    if (ioctl(fd, SIOCGIFINDEX, &ifr) < 0) {
        snprintf(m->err, sizeof m->err, "interface %s: %s", iface, strerror(errno));
        close(fd);
        return -1;
    }
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = ifr.ifr_ifindex;
    if (bind(fd, (struct sockaddr *)&addr, sizeof addr) < 0) {
        snprintf(m->err, sizeof m->err, "bind %s: %s", iface, strerror(errno));
        close(fd);
        return -1;
    }
    m->fd = fd;
    return 0;
}

void co_master_close(co_master *m)
{
    if (m->fd >= 0)
        close(m->fd);
    m->fd = -1;
}

int co_send(co_master *m, uint32_t id, const uint8_t *data, uint8_t len)
{
    struct can_frame f;
    memset(&f, 0, sizeof f);
    f.can_id = id & CAN_SFF_MASK;
    f.can_dlc = len;
    if (len)
        memcpy(f.data, data, len);
    for (int tries = 0; tries < 100; tries++) {
        if (write(m->fd, &f, sizeof f) == (ssize_t)sizeof f)
            return 0;
        if (errno != ENOBUFS && errno != EAGAIN && errno != EINTR)
            break;
        struct timespec ts = {0, 1000000}; /* TX queue full: wait for the bus (1 ms) */
        nanosleep(&ts, NULL);
    }
    snprintf(m->err, sizeof m->err, "CAN send: %s", strerror(errno));
    return -1;
}

/* Reads one frame if one is ready within timeout_ms: 1 got one, 0 none, -1 error (EINTR counts as none). */
static int recv_frame(co_master *m, co_frame *out, int timeout_ms)
{
    struct pollfd p = {m->fd, POLLIN, 0};
    int r = poll(&p, 1, timeout_ms);
    if (r < 0)
        return errno == EINTR ? 0 : -1;
    if (r == 0)
        return 0;
    struct can_frame f;
    ssize_t n = read(m->fd, &f, sizeof f);
    if (n != (ssize_t)sizeof f)
        return errno == EINTR ? 0 : -1;
    if (f.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG))
        return 0;
    out->id = f.can_id & CAN_SFF_MASK;
    out->len = f.can_dlc > 8 ? 8 : f.can_dlc;
    memcpy(out->data, f.data, out->len);
    return 1;
}

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

int co_poll(co_master *m, int timeout_ms)
{
    int handled = 0;
    const double end = now_ms() + timeout_ms;
    for (;;) {
        const double left = end - now_ms();
        co_frame f;
        int r = recv_frame(m, &f, left > 0 ? (int)left : 0);
        if (r < 0)
            return -1;
        if (r == 0)
            return handled;
        if (m->on_frame)
            m->on_frame(m->ctx, &f);
        handled++;
    }
}

int co_nmt(co_master *m, uint8_t command)
{
    const uint8_t d[2] = {command, m->node_id};
    return co_send(m, 0x000, d, 2);
}

int co_sync(co_master *m)
{
    return co_send(m, 0x080, NULL, 0);
}

/* Sends an SDO request and waits for the server's answer to (index, sub); other frames go to on_frame. */
static int64_t sdo_xfer(co_master *m, const uint8_t req[8], uint16_t index, uint8_t sub, bool check_mux,
                        uint8_t resp[8])
{
    if (co_send(m, SDO_TX + m->node_id, req, 8) != 0)
        return CO_SDO_IO;
    const double end = now_ms() + m->sdo_timeout_ms;
    for (;;) {
        const double left = end - now_ms();
        if (left <= 0)
            return CO_SDO_TIMEOUT;
        co_frame f;
        int r = recv_frame(m, &f, (int)left + 1);
        if (r < 0)
            return CO_SDO_IO;
        if (r == 0)
            continue;
        if (f.id != SDO_RX + m->node_id || f.len != 8) {
            if (m->on_frame)
                m->on_frame(m->ctx, &f);
            continue;
        }
        const uint16_t idx = (uint16_t)(f.data[1] | f.data[2] << 8);
        if (f.data[0] == 0x80) { /* abort */
            if (idx != index || f.data[3] != sub)
                continue; /* a late abort of an earlier transfer */
            return (int64_t)((uint32_t)f.data[4] | (uint32_t)f.data[5] << 8 | (uint32_t)f.data[6] << 16 |
                             (uint32_t)f.data[7] << 24);
        }
        if (check_mux && (idx != index || f.data[3] != sub))
            continue;
        memcpy(resp, f.data, 8);
        return 0;
    }
}

int64_t co_sdo_read(co_master *m, uint16_t index, uint8_t sub, uint32_t *value)
{
    uint8_t req[8] = {0x40, (uint8_t)index, (uint8_t)(index >> 8), sub, 0, 0, 0, 0}, resp[8];
    int64_t r = sdo_xfer(m, req, index, sub, true, resp);
    if (r != 0)
        return r;
    if ((resp[0] & 0xE3) != 0x43) /* expedited upload response with the size */
        return CO_SDO_PROTOCOL;
    const int n = 4 - ((resp[0] >> 2) & 3);
    uint32_t v = 0;
    for (int k = 0; k < n; k++)
        v |= (uint32_t)resp[4 + k] << (8 * k);
    *value = v;
    return 0;
}

int64_t co_sdo_write(co_master *m, uint16_t index, uint8_t sub, const uint8_t *data, size_t len)
{
    uint8_t req[8] = {0, (uint8_t)index, (uint8_t)(index >> 8), sub, 0, 0, 0, 0}, resp[8];
    if (len >= 1 && len <= 4) {
        req[0] = (uint8_t)(0x23 | ((4 - len) << 2));
        memcpy(req + 4, data, len);
        int64_t r = sdo_xfer(m, req, index, sub, true, resp);
        if (r != 0)
            return r;
        return resp[0] == 0x60 ? 0 : CO_SDO_PROTOCOL;
    }
    req[0] = 0x21; /* segmented, size indicated */
    req[4] = (uint8_t)len, req[5] = (uint8_t)(len >> 8), req[6] = (uint8_t)(len >> 16), req[7] = (uint8_t)(len >> 24);
    int64_t r = sdo_xfer(m, req, index, sub, true, resp);
    if (r != 0)
        return r;
    if (resp[0] != 0x60)
        return CO_SDO_PROTOCOL;
    uint8_t toggle = 0;
    for (size_t at = 0; at < len; toggle ^= 1) {
        const size_t n = len - at > 7 ? 7 : len - at;
        uint8_t seg[8] = {0};
        seg[0] = (uint8_t)(toggle << 4 | (7 - n) << 1 | (at + n == len ? 1 : 0));
        memcpy(seg + 1, data + at, n);
        at += n;
        r = sdo_xfer(m, seg, index, sub, false, resp);
        if (r != 0)
            return r;
        if ((resp[0] & 0xEF) != 0x20 || ((resp[0] >> 4) & 1) != toggle)
            return CO_SDO_PROTOCOL;
    }
    return 0;
}

int64_t co_sdo_write_u32(co_master *m, uint16_t index, uint8_t sub, uint32_t value, size_t len)
{
    const uint8_t d[4] = {(uint8_t)value, (uint8_t)(value >> 8), (uint8_t)(value >> 16), (uint8_t)(value >> 24)};
    return co_sdo_write(m, index, sub, d, len);
}

const char *co_sdo_abort_text(int64_t code)
{
    switch (code) {
    case CO_SDO_TIMEOUT: return "no SDO answer (time-out)";
    case CO_SDO_IO: return "CAN I/O error";
    case CO_SDO_PROTOCOL: return "unexpected SDO answer";
    case 0x05030000: return "toggle bit not alternated";
    case 0x05040000: return "SDO protocol timed out";
    case 0x05040001: return "command specifier not valid";
    case 0x06010001: return "attempt to read a write-only object";
    case 0x06010002: return "attempt to write a read-only object";
    case 0x06020000: return "object does not exist";
    case 0x06070010: return "data type does not match";
    case 0x06070012: return "data too long";
    case 0x06070013: return "data too short";
    case 0x06090011: return "sub-index does not exist";
    case 0x06090030: return "invalid value (path block: bad type, plane, axis count or geometry)";
    case 0x06090031: return "value too high (path block: sequence gap)";
    case 0x06090032: return "value too low (path block: zero feed or tolerance)";
    case 0x08000020: return "cannot be stored now (path buffer full)";
    case 0x08000022: return "not allowed in the present device state";
    default: return "SDO abort";
    }
}

const char *co_emcy_text(uint16_t code)
{
    switch (code) {
    case 0x0000: return "error reset";
    case 0x8100: return "communication error (bus-off)";
    case 0x8110: return "CAN overrun (frames lost)";
    case 0x8120: return "CAN error passive";
    case 0x8130: return "heartbeat of the master lost";
    case 0x8140: return "recovered from bus-off";
    case 0x8210: return "PDO not processed (length)";
    case 0x8220: return "PDO length exceeded";
    case 0x8240: return "SYNC with unexpected length";
    case 0x8611: return "following error";
    case 0x9000: return "E-stop";
    case 0xFF01: return "the node's planner refused a path block";
    default: return "device fault";
    }
}
