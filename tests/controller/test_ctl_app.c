/*
 * test_ctl_app.c: the controller application (firmware/apps/controller/ctl_app.h) on the host, through a fake
 * character link: the node's frames go up only once the host opened the channel (boot-up frame dropped before,
 * as an adapter drops bus traffic nobody opened it for); an expedited SDO upload of 0x1000 and of 0x5F00 (the
 * tick statistics the board passes in); an NMT reset answered with a boot-up frame; a malformed line answered
 * with BEL; the tick parses at most CTL_RX_CHARS_PER_TICK characters and leaves the rest for the next tick; a
 * link without room keeps the frame for the next tick (none lost, order kept); a PP set-point: with the CiA 402
 * layer of firmware/motion the axis reaches it (demand = actual = target, target reached), with the interim
 * layer (ctl_motion_hold.c) it is refused with an application fault (EMCY 0x6100).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "ctl_app.h"
#include "ctl_motion_impl.h"

typedef struct fake_link {
    char in[65536];
    size_t in_len, in_pos;
    char out[65536];
    size_t out_len;
    size_t room; /* characters write may take (SIZE_MAX: unlimited) */
} fake_link;

static fake_link g_link;
static ctl_app g_app;
static struct ctl_motion g_motion;
static uint32_t g_now;

static int l_getc(void *ctx)
{
    fake_link *l = ctx;
    return l->in_pos < l->in_len ? (unsigned char)l->in[l->in_pos++] : -1;
}

static bool l_write(void *ctx, const char *s, size_t n)
{
    fake_link *l = ctx;
    if (n > l->room || l->out_len + n > sizeof l->out)
        return false;
    memcpy(l->out + l->out_len, s, n);
    l->out_len += n;
    if (l->room != SIZE_MAX)
        l->room -= n;
    return true;
}

static size_t l_room(void *ctx)
{
    fake_link *l = ctx;
    return l->room;
}

static void host_send(const char *s)
{
    size_t n = strlen(s);
    assert_true(g_link.in_len + n <= sizeof g_link.in);
    memcpy(g_link.in + g_link.in_len, s, n);
    g_link.in_len += n;
}

static void ticks(unsigned n)
{
    lsm_canopen_tick_stats st =
        {.ticks = 77, .overruns = 0, .worst_instr = 12345, .bg_load_permille = 42, .late_wakes = 3, .clock_ms = 9};
    for (unsigned i = 0; i < n; i++) {
        g_now += 1000u;
        ctl_app_tick(&g_app, g_now, false, &st);
        while (ctl_app_background(&g_app)) { /* the main loop between ticks (PP plans, the path feed) */
        }
    }
}

/* The link output as a string (and cleared). */
static const char *take_out(void);

/* An SDO request that needs an object access: the tick of its arrival queues it (the slcan reply "z" goes at once),
 * the background posts the access, the next tick applies it, the background makes the response, and the tick after
 * that sends it: two ticks later (canopen.h, "Contexts"). */
static void expect_sdo_answer(const char *line)
{
    ticks(1);
    assert_string_equal(take_out(), "z\r");
    ticks(1);
    assert_string_equal(take_out(), "");
    ticks(1);
    assert_string_equal(take_out(), line);
}

/* The link output as a string (and cleared). */
static const char *take_out(void)
{
    static char buf[65536 + 1];
    memcpy(buf, g_link.out, g_link.out_len);
    buf[g_link.out_len] = '\0';
    g_link.out_len = 0;
    return buf;
}

static int setup(void **state)
{
    (void)state;
    memset(&g_link, 0, sizeof g_link);
    g_link.room = SIZE_MAX;
    g_now = 0;
    ctl_app_config cfg = {0};
    cfg.node_id = 5;
    cfg.n_axes = 3;
    cfg.cycle_us = 1000;
    cfg.heartbeat_ms = 0;
    cfg.device_name = "test";
    cfg.motion = &g_motion;
    cfg.link = (ctl_link){l_getc, l_write, l_room, &g_link};
    assert_int_equal(ctl_app_init(&g_app, &cfg), LSM_OK);
    return 0;
}

static void test_init_errors(void **state)
{
    (void)state;
    ctl_app_config cfg = {0};
    cfg.node_id = 5;
    cfg.n_axes = 3;
    cfg.cycle_us = 1000;
    cfg.motion = &g_motion;
    assert_int_equal(ctl_app_init(&g_app, &cfg), LSM_E_ARG); /* no link */
    cfg.link = (ctl_link){l_getc, l_write, l_room, &g_link};
    cfg.cycle_us = 50;
    assert_int_equal(ctl_app_init(&g_app, &cfg), LSM_E_ARG);
    cfg.cycle_us = 1000;
    cfg.motion = NULL;
    assert_int_equal(ctl_app_init(&g_app, &cfg), LSM_E_NULL);
    cfg.motion = &g_motion;
    cfg.node_id = 0;
    assert_int_equal(ctl_app_init(&g_app, &cfg), LSM_E_CO_NODE_ID);
}

static void test_channel_and_sdo(void **state)
{
    (void)state;
    ticks(2);
    assert_string_equal(take_out(), ""); /* boot-up dropped: channel closed */
    assert_int_equal(g_app.n.frames_closed, 1);
    host_send("C\rS8\rO\r");
    ticks(1);
    assert_string_equal(take_out(), "\r\r\r");
    /* SDO upload 0x1000 sub 0 -> 0x00020192 */
    host_send("t6058"
              "4000100000000000"
              "\r");
    expect_sdo_answer("t5858"
                      "4300100092010200"
                      "\r");
    /* 0x5F00 sub 3: the worst tick the board passed in */
    host_send("t6058"
              "40005F0300000000"
              "\r");
    expect_sdo_answer("t5858"
                      "43005F0339300000"
                      "\r");
    host_send("t6058"
              "40005F0600000000"
              "\r");
    expect_sdo_answer("t5858"
                      "43005F0609000000"
                      "\r");
    /* writing it is refused (read-only: 0x06010002) */
    host_send("t6058"
              "23005F0301000000"
              "\r");
    expect_sdo_answer("t5858"
                      "80005F0302000106"
                      "\r");
    /* NMT reset node: a boot-up frame */
    host_send("t00028105\r");
    ticks(3);
    assert_string_equal(take_out(), "z\rt705100\r");
    /* malformed line: BEL, nothing served */
    uint32_t in = g_app.n.frames_in;
    host_send("t60G0\r");
    ticks(1);
    assert_string_equal(take_out(), "\a");
    assert_int_equal(g_app.n.frames_in, in);
}

static void test_bounded_parsing_and_link_room(void **state)
{
    (void)state;
    host_send("O\r");
    ticks(1);
    take_out();
    /* 40 SDO requests at once: more characters than one tick parses */
    for (int i = 0; i < 40; i++)
        host_send("t6058"
                  "4000100000000000"
                  "\r");
    const size_t total = g_link.in_len, start = g_link.in_pos;
    ticks(1);
    assert_int_equal(g_link.in_pos - start, CTL_RX_CHARS_PER_TICK);
    assert_true(g_link.in_pos < total);
    ticks(5);
    assert_int_equal(g_link.in_pos, total);
    ticks(LSM_CANOPEN_SDO_QUEUE * 2u + 2u);
    /* a client that keeps the protocol has one request out; this burst overflows the tick -> background SDO ring
     * (LSM_CANOPEN_SDO_QUEUE): every request is answered once, either served or refused at once with 0x05040005 */
    const char *out = take_out();
    unsigned answers = 0, refused = 0;
    for (const char *p = out; (p = strstr(p, "t5858"
                                             "4300100092010200"
                                             "\r")) != NULL;
         p++)
        answers++;
    for (const char *p = out; (p = strstr(p, "t5858"
                                             "8000100005000405"
                                             "\r")) != NULL;
         p++)
        refused++;
    assert_int_equal(answers + refused, 40);
    assert_true(answers >= LSM_CANOPEN_SDO_QUEUE);
    uint32_t waiting = 99, most = 0, n_refused = 0;
    lsm_canopen_sdo_stats(&g_app.co, &waiting, &most, &n_refused);
    assert_int_equal(waiting, 0);
    assert_int_equal(most, LSM_CANOPEN_SDO_QUEUE);
    assert_int_equal(n_refused, refused);
    assert_int_equal(g_app.n.frames_refused, refused);
    /* a link with no room: the answer waits, then goes out whole */
    g_link.room = 5;
    host_send("t6058"
              "4000100000000000"
              "\r");
    ticks(1);
    assert_string_equal(take_out(), "z\r"); /* the reply fitted */
    ticks(2);
    assert_string_equal(take_out(), ""); /* the 24-character frame did not */
    assert_true(g_app.have_pending);
    g_link.room = SIZE_MAX;
    ticks(1);
    assert_string_equal(take_out(), "t5858"
                                    "4300100092010200"
                                    "\r");
    assert_int_equal(g_app.n.replies_lost, 0);
}

static void test_pp_setpoint(void **state)
{
    (void)state;
    host_send("O\r");
    ticks(1);
    lsm_cia402 *ax = lsm_canopen_axis(&g_app.co, 0);
    host_send("t00020105\r"); /* NMT start */
    ticks(2);
    /* mode PP, shutdown, switch on, enable */
    host_send("t6058"
              "2F60600001000000"
              "\r");
    ticks(2);
    host_send("t6058"
              "2B40600006000000"
              "\r");
    ticks(2);
    host_send("t6058"
              "2B40600007000000"
              "\r");
    ticks(2);
    host_send("t6058"
              "2B4060000F000000"
              "\r");
    ticks(3);
    assert_int_equal(ax->state, LSM_CIA402_OPERATION_ENABLED);
    take_out();
    host_send("t6058"
              "237A6000E8030000"
              "\r"); /* target 1000 */
    ticks(2);
    host_send("t6058"
              "2B4060001F000000"
              "\r"); /* new set-point */
#if defined(CTL_MOTION_CIA402)
    ticks(2000); /* 1 mm with the default profile objects: well within 2 s */
    assert_int_equal(ax->pos_demand, 1000);
    assert_int_equal(ax->pos_actual, 1000); /* ideal loopback */
    assert_true((ax->statusword & 0x0400u) != 0u);
    assert_int_equal(ax->error_code, 0);
#else
    ticks(5);
    const char *out = take_out();
    assert_non_null(strstr(out, "t0858"
                                "0061")); /* EMCY 0x6100 */
    assert_int_equal(g_motion.refused[0], 1);
    assert_int_equal(ax->error_code, 0x6100);
#endif
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_init_errors),
        cmocka_unit_test_setup(test_channel_and_sdo, setup),
        cmocka_unit_test_setup(test_bounded_parsing_and_link_room, setup),
        cmocka_unit_test_setup(test_pp_setpoint, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
