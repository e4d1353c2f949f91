#include "slcan.h"

#include <string.h>

/* Version reported by V: hardware 1.0, software 1.3 ("V1013"), two decimal digits each as adapters do. */
static const char k_version[] = "V1013\r";
/* Serial number reported by N (four characters). */
static const char k_serial[] = "NLSM1\r";
static const char k_hex[] = "0123456789ABCDEF";

lsm_status lsm_slcan_init(lsm_slcan *s)
{
    if (s == NULL)
        return LSM_E_NULL;
    memset(s, 0, sizeof *s);
    s->bitrate_code = 8u;
    return LSM_OK;
}

static int hex_value(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    return -1;
}

/* n hex digits of p into *v; false on a non-hex digit. */
static bool parse_hex(const char *p, unsigned n, uint32_t *v)
{
    uint32_t x = 0u;
    for (unsigned i = 0u; i < n; i++) {
        const int d = hex_value(p[i]);
        if (d < 0)
            return false;
        x = (x << 4) | (uint32_t)d;
    }
    *v = x;
    return true;
}

/* A t/T/r/R line (without CR) into *f; false when malformed. */
static bool parse_frame(const char *l, unsigned len, lsm_can_frame *f)
{
    const bool ext = l[0] == 'T' || l[0] == 'R';
    const bool rtr = l[0] == 'r' || l[0] == 'R';
    const unsigned id_digits = ext ? 8u : 3u;
    uint32_t id, dlc;
    if (len < 1u + id_digits + 1u || !parse_hex(l + 1, id_digits, &id))
        return false;
    const char d = l[1u + id_digits];
    if (d < '0' || d > '8')
        return false;
    dlc = (uint32_t)(d - '0');
    if (id > (ext ? LSM_CAN_EXT_ID_MAX : LSM_CAN_STD_ID_MAX))
        return false;
    const unsigned data_digits = rtr ? 0u : 2u * dlc;
    if (len != 2u + id_digits + data_digits)
        return false;
    memset(f, 0, sizeof *f);
    f->id = id;
    f->dlc = (uint8_t)dlc;
    f->flags = (uint8_t)((ext ? LSM_CAN_FLAG_EXT : 0u) | (rtr ? LSM_CAN_FLAG_RTR : 0u));
    for (unsigned i = 0u; i < data_digits / 2u; i++) {
        uint32_t b;
        if (!parse_hex(l + 2u + id_digits + (size_t)2u * i, 2u, &b))
            return false;
        f->data[i] = (uint8_t)b;
    }
    return true;
}

static void put_reply(char *reply, const char *text)
{
    size_t n = strlen(text);
    memcpy(reply, text, n + 1u);
}

/* The reply to a complete command line (not a frame). */
static void command(lsm_slcan *s, const char *l, unsigned len, char *reply)
{
    const char bel[2] = {LSM_SLCAN_BEL, '\0'};
    const char cr[2] = {LSM_SLCAN_CR, '\0'};
    uint32_t v;
    put_reply(reply, bel);
    if (len == 0u) {
        put_reply(reply, cr);
        return;
    }
    switch (l[0]) {
    case 'O':
    case 'L':
        if (len != 1u)
            return;
        s->open = true;
        s->listen_only = l[0] == 'L';
        break;
    case 'C':
        if (len != 1u)
            return;
        s->open = false;
        s->listen_only = false;
        break;
    case 'S':
        if (len != 2u || l[1] < '0' || l[1] > '8')
            return;
        s->bitrate_code = (uint8_t)(l[1] - '0');
        break;
    case 's':
        if (len != 5u || !parse_hex(l + 1, 4u, &v))
            return;
        s->bitrate_code = 0xFFu;
        break;
    case 'V':
        if (len == 1u)
            put_reply(reply, k_version);
        return;
    case 'N':
        if (len == 1u)
            put_reply(reply, k_serial);
        return;
    case 'F':
        if (len != 1u)
            return;
        reply[0] = 'F';
        reply[1] = k_hex[(s->status_flags >> 4) & 0xFu];
        reply[2] = k_hex[s->status_flags & 0xFu];
        reply[3] = LSM_SLCAN_CR;
        reply[4] = '\0';
        s->status_flags = 0u;
        return;
    case 'Z':
        if (len != 2u || l[1] != '0')
            return;
        break;
    case 'M':
    case 'm':
        if (len != 9u || !parse_hex(l + 1, 8u, &v))
            return;
        break;
    default: return;
    }
    put_reply(reply, cr);
}

/* A complete line: a frame for the bus or a command. */
static lsm_slcan_event line_done(lsm_slcan *s, lsm_can_frame *frame, char *reply)
{
    const char *l = s->line;
    const unsigned len = s->len;
    const bool overlong = s->overlong;
    s->len = 0u;
    s->overlong = false;
    reply[0] = LSM_SLCAN_BEL;
    reply[1] = '\0';
    if (overlong) {
        s->refused++;
        return LSM_SLCAN_EV_REPLY;
    }
    if (len > 0u && (l[0] == 't' || l[0] == 'T' || l[0] == 'r' || l[0] == 'R')) {
        if (!s->open || s->listen_only || !parse_frame(l, len, frame)) {
            s->refused++;
            return LSM_SLCAN_EV_REPLY;
        }
        reply[0] = (frame->flags & LSM_CAN_FLAG_EXT) != 0u ? 'Z' : 'z';
        reply[1] = LSM_SLCAN_CR;
        reply[2] = '\0';
        s->frames_down++;
        return LSM_SLCAN_EV_FRAME;
    }
    command(s, l, len, reply);
    if (reply[0] == LSM_SLCAN_BEL)
        s->refused++;
    return LSM_SLCAN_EV_REPLY;
}

lsm_slcan_event lsm_slcan_feed(lsm_slcan *s, char c, lsm_can_frame *frame, char *reply)
{
    if (c == LSM_SLCAN_CR)
        return line_done(s, frame, reply);
    if (c == '\n' || c == '\0')
        return LSM_SLCAN_EV_NONE;
    if (s->len < LSM_SLCAN_LINE_MAX)
        s->line[s->len++] = c;
    else
        s->overlong = true;
    return LSM_SLCAN_EV_NONE;
}

size_t lsm_slcan_encode(const lsm_can_frame *f, char *out)
{
    const bool ext = (f->flags & LSM_CAN_FLAG_EXT) != 0u;
    const bool rtr = (f->flags & LSM_CAN_FLAG_RTR) != 0u;
    if (f->dlc > LSM_CAN_MAX_DLC || f->id > (ext ? LSM_CAN_EXT_ID_MAX : LSM_CAN_STD_ID_MAX))
        return 0u;
    size_t n = 0u;
    out[n++] = ext ? (rtr ? 'R' : 'T') : (rtr ? 'r' : 't');
    for (int shift = ext ? 28 : 8; shift >= 0; shift -= 4)
        out[n++] = k_hex[(f->id >> shift) & 0xFu];
    out[n++] = (char)('0' + f->dlc);
    if (!rtr) {
        for (unsigned i = 0u; i < f->dlc; i++) {
            out[n++] = k_hex[f->data[i] >> 4];
            out[n++] = k_hex[f->data[i] & 0xFu];
        }
    }
    out[n++] = LSM_SLCAN_CR;
    out[n] = '\0';
    return n;
}
