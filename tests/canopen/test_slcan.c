/*
 * test_slcan.c: the slcan (Lawicel) adapter side: every command and its reply, frames refused while closed or
 * listen-only, malformed lines (bad hex, dlc, length, id range, overlong) answered with BEL without changing
 * anything, CR LF tolerated, and a seeded round trip (random frames encoded as the host sends them, fed back
 * character by character, equal; and every frame the board sends up parsed back the way python-can does).
 * `test_slcan [seed] [count]`.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "lsm_test_rng.h"
#include "slcan.h"

static unsigned long long g_seed = 1, g_count = 20000;

/* Feeds a whole string; returns the last event and keeps the last reply / frame. */
static lsm_slcan_event feed(lsm_slcan *s, const char *text, lsm_can_frame *f, char *reply)
{
    lsm_slcan_event ev = LSM_SLCAN_EV_NONE;
    for (const char *p = text; *p != '\0'; p++) {
        lsm_slcan_event e = lsm_slcan_feed(s, *p, f, reply);
        if (e != LSM_SLCAN_EV_NONE)
            ev = e;
    }
    return ev;
}

static void test_commands(void **state)
{
    (void)state;
    lsm_slcan s;
    lsm_can_frame f;
    char r[LSM_SLCAN_REPLY_MAX + 1];
    assert_int_equal(lsm_slcan_init(NULL), LSM_E_NULL);
    assert_int_equal(lsm_slcan_init(&s), LSM_OK);
    assert_int_equal(s.bitrate_code, 8);
    assert_int_equal(feed(&s, "\r", &f, r), LSM_SLCAN_EV_REPLY);
    assert_string_equal(r, "\r");
    assert_int_equal(feed(&s, "S6\r", &f, r), LSM_SLCAN_EV_REPLY);
    assert_string_equal(r, "\r");
    assert_int_equal(s.bitrate_code, 6);
    assert_int_equal(feed(&s, "S9\r", &f, r), LSM_SLCAN_EV_REPLY);
    assert_string_equal(r, "\a");
    assert_int_equal(s.bitrate_code, 6);
    assert_int_equal(feed(&s, "s031C\r", &f, r), LSM_SLCAN_EV_REPLY);
    assert_string_equal(r, "\r");
    assert_int_equal(s.bitrate_code, 0xFF);
    assert_int_equal(feed(&s, "s03XC\r", &f, r), LSM_SLCAN_EV_REPLY);
    assert_string_equal(r, "\a");
    feed(&s, "V\r", &f, r);
    assert_string_equal(r, "V1013\r");
    feed(&s, "N\r", &f, r);
    assert_string_equal(r, "NLSM1\r");
    s.status_flags = LSM_SLCAN_F_OVERRUN | LSM_SLCAN_F_TX_FULL;
    feed(&s, "F\r", &f, r);
    assert_string_equal(r, "F0A\r");
    feed(&s, "F\r", &f, r); /* read clears */
    assert_string_equal(r, "F00\r");
    feed(&s, "Z0\r", &f, r);
    assert_string_equal(r, "\r");
    feed(&s, "Z1\r", &f, r);
    assert_string_equal(r, "\a");
    feed(&s, "M00000000\r", &f, r);
    assert_string_equal(r, "\r");
    feed(&s, "mFFFFFFFF\r", &f, r);
    assert_string_equal(r, "\r");
    feed(&s, "P\r", &f, r);
    assert_string_equal(r, "\a");
    feed(&s, "d1238\r", &f, r); /* CAN FD: not offered */
    assert_string_equal(r, "\a");
    feed(&s, "OX\r", &f, r);
    assert_string_equal(r, "\a");
    assert_false(s.open);
    /* frames only while open, and not listen-only */
    assert_int_equal(feed(&s, "t1230\r", &f, r), LSM_SLCAN_EV_REPLY);
    assert_string_equal(r, "\a");
    feed(&s, "L\r", &f, r);
    assert_true(s.open && s.listen_only);
    assert_int_equal(feed(&s, "t1230\r", &f, r), LSM_SLCAN_EV_REPLY);
    assert_string_equal(r, "\a");
    feed(&s, "C\r", &f, r);
    assert_false(s.open);
    feed(&s, "O\r", &f, r);
    assert_string_equal(r, "\r");
    assert_true(s.open && !s.listen_only);
    assert_int_equal(feed(&s, "t60184000100000000000\r\n", &f, r), LSM_SLCAN_EV_FRAME);
    assert_string_equal(r, "z\r");
    assert_int_equal(f.id, 0x601);
    assert_int_equal(f.dlc, 8);
    assert_int_equal(f.flags, 0);
    assert_int_equal(f.data[0], 0x40);
    assert_int_equal(f.data[2], 0x10);
    assert_int_equal(feed(&s, "T1ABCDEF02aa55\r", &f, r), LSM_SLCAN_EV_FRAME);
    assert_string_equal(r, "Z\r");
    assert_int_equal(f.id, 0x1ABCDEF0);
    assert_int_equal(f.flags, LSM_CAN_FLAG_EXT);
    assert_int_equal(f.dlc, 2);
    assert_int_equal(f.data[0], 0xAA);
    assert_int_equal(f.data[1], 0x55);
    assert_int_equal(feed(&s, "r7005\r", &f, r), LSM_SLCAN_EV_FRAME);
    assert_int_equal(f.flags, LSM_CAN_FLAG_RTR);
    assert_int_equal(f.dlc, 5);
    assert_int_equal(feed(&s, "R000001230\r", &f, r), LSM_SLCAN_EV_FRAME);
    assert_int_equal(f.flags, LSM_CAN_FLAG_EXT | LSM_CAN_FLAG_RTR);
    assert_int_equal(s.frames_down, 4);
}

static void test_malformed(void **state)
{
    (void)state;
    static const char *const bad[] = {
        "t12\r",                                       /* too short */
        "t1239\r",                                     /* dlc 9 */
        "t12381122\r",                                 /* dlc 8, 2 bytes */
        "t123211223\r",                                /* one digit too many */
        "t12G0\r",                                     /* bad hex in the id */
        "t8000\r",                                     /* id > 0x7FF */
        "T200000000\r",                                /* 29-bit id out of range */
        "t1231X1\r",                                   /* bad hex in the data */
        "r1239\r",                                     /* remote dlc 9 */
        "r12311\r",                                    /* remote with data */
        "t1238000000000000000000000000000000000000\r", /* overlong */
    };
    lsm_slcan s;
    lsm_can_frame f;
    char r[LSM_SLCAN_REPLY_MAX + 1];
    lsm_slcan_init(&s);
    feed(&s, "O\r", &f, r);
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        assert_int_equal(feed(&s, bad[i], &f, r), LSM_SLCAN_EV_REPLY);
        assert_string_equal(r, "\a");
    }
    assert_int_equal(s.refused, sizeof bad / sizeof bad[0]);
    assert_int_equal(s.frames_down, 0);
    /* the line after an overlong one is served normally */
    assert_int_equal(feed(&s, "t0010\r", &f, r), LSM_SLCAN_EV_FRAME);
    assert_int_equal(f.id, 1);
}

static void test_encode(void **state)
{
    (void)state;
    char out[LSM_SLCAN_FRAME_MAX + 1];
    lsm_can_frame f = {.id = 0x181, .dlc = 3, .flags = 0, .data = {0x37, 0x02, 0x01}};
    assert_int_equal(lsm_slcan_encode(&f, out), 12);
    assert_string_equal(out, "t1813370201\r");
    f = (lsm_can_frame){.id = 0x1FFFFFFF, .dlc = 8, .flags = LSM_CAN_FLAG_EXT, .data = {1, 2, 3, 4, 5, 6, 7, 0xFF}};
    assert_int_equal(lsm_slcan_encode(&f, out), LSM_SLCAN_FRAME_MAX);
    assert_string_equal(out, "T1FFFFFFF801020304050607FF\r");
    f = (lsm_can_frame){.id = 0x700, .dlc = 0, .flags = LSM_CAN_FLAG_RTR};
    lsm_slcan_encode(&f, out);
    assert_string_equal(out, "r7000\r");
    f = (lsm_can_frame){.id = 0x800, .dlc = 0};
    assert_int_equal(lsm_slcan_encode(&f, out), 0);
    f = (lsm_can_frame){.id = 0x100, .dlc = 9};
    assert_int_equal(lsm_slcan_encode(&f, out), 0);
}

/* What python-can's slcan reader does with a line (can/interfaces/slcan.py, _recv_internal). */
static void host_parse(const char *l, lsm_can_frame *f)
{
    memset(f, 0, sizeof *f);
    unsigned idd = (l[0] == 'T' || l[0] == 'R') ? 8u : 3u;
    char buf[9] = {0};
    memcpy(buf, l + 1, idd);
    f->id = (uint32_t)strtoul(buf, NULL, 16);
    f->dlc = (uint8_t)(l[1 + idd] - '0');
    f->flags = (uint8_t)((idd == 8u ? LSM_CAN_FLAG_EXT : 0u) | ((l[0] == 'r' || l[0] == 'R') ? LSM_CAN_FLAG_RTR : 0u));
    if ((f->flags & LSM_CAN_FLAG_RTR) == 0u) {
        for (unsigned i = 0; i < f->dlc; i++) {
            char b[3] = {l[2 + idd + 2 * i], l[3 + idd + 2 * i], 0};
            f->data[i] = (uint8_t)strtoul(b, NULL, 16);
        }
    }
}

static void test_round_trip(void **state)
{
    (void)state;
    uint64_t rng = g_seed * 0x9E3779B97F4A7C15ull + 1u;
    lsm_slcan s;
    lsm_slcan_init(&s);
    char r[LSM_SLCAN_REPLY_MAX + 1];
    lsm_can_frame f, g, h;
    feed(&s, "O\r", &f, r);
    for (unsigned long long n = 0; n < g_count; n++) {
        memset(&f, 0, sizeof f);
        const bool ext = test_urand(&rng) < 0.3;
        f.flags = (uint8_t)((ext ? LSM_CAN_FLAG_EXT : 0u) | (test_urand(&rng) < 0.1 ? LSM_CAN_FLAG_RTR : 0u));
        f.id = (uint32_t)(test_urand(&rng) * ((ext ? LSM_CAN_EXT_ID_MAX : LSM_CAN_STD_ID_MAX) + 1.0));
        f.dlc = (uint8_t)(test_urand(&rng) * 9.0);
        if ((f.flags & LSM_CAN_FLAG_RTR) == 0u)
            for (unsigned i = 0; i < f.dlc; i++)
                f.data[i] = (uint8_t)(test_urand(&rng) * 256.0);
        char line[LSM_SLCAN_FRAME_MAX + 1];
        size_t len = lsm_slcan_encode(&f, line);
        if (len == 0u)
            fail_msg("seed %llu frame %llu: not encoded", g_seed, n);
        /* down: the host's line (lower-case hex half of the time, as some hosts send) fed back */
        if (test_urand(&rng) < 0.5)
            for (size_t i = 1; i < len; i++)
                if (line[i] >= 'A' && line[i] <= 'F')
                    line[i] = (char)(line[i] - 'A' + 'a');
        if (feed(&s, line, &g, r) != LSM_SLCAN_EV_FRAME || memcmp(&f, &g, sizeof f) != 0)
            fail_msg("seed %llu frame %llu: \"%s\" did not come back equal", g_seed, n, line);
        /* up: what python-can reads */
        lsm_slcan_encode(&f, line);
        host_parse(line, &h);
        if (memcmp(&f, &h, sizeof f) != 0)
            fail_msg("seed %llu frame %llu: \"%s\" parsed differently by the host", g_seed, n, line);
    }
}

int main(int argc, char **argv)
{
    g_seed = test_arg_u(argc, argv, 1, 1);
    g_count = test_arg_u(argc, argv, 2, 20000);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_commands),
        cmocka_unit_test(test_malformed),
        cmocka_unit_test(test_encode),
        cmocka_unit_test(test_round_trip),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
