/*
 * test_cia402.c: the CiA 402 axis (cia402.c) through its controlword and its application API:
 *   - the full transition table: every state x every command, with the resulting state and statusword
 *     (checked against the masks that python-canopen's BaseNode402 uses);
 *   - transitions out of motion that wait for standstill (5, 8, 9, 11/12 for each 0x605A option, 16),
 *     cancelling a pending disable, the stop kind and deceleration the application is asked for;
 *   - fault reaction, fault reset edge, fault hold (E-stop), EMCY events;
 *   - Profile Position: single set-point and set-of-set-points hand-shakes (bits 4, 5, 9 and statusword
 *     bits 10, 12), relative set-points and their overflow (bit 11), halt and resume, captured parameters;
 *   - mode switching at rest, CSP pass-through, following-error monitoring with its timeout;
 *   - the node path: a controlword in an RPDO drives the same machine.
 */
#include "co_test_util.h"

static lsm_cia402 ax;
static uint32_t now;

static int setup(void **state)
{
    (void)state;
    assert_int_equal(lsm_cia402_init(&ax), LSM_OK);
    now = 0;
    return 0;
}

static void cw(uint16_t v)
{
    assert_int_equal(lsm_cia402_od_write(&ax, 0x6040, 0, v, now), 0);
}

static void fb(int32_t demand, int32_t actual, bool standstill)
{
    lsm_cia402_feedback f = {demand, actual, 0, standstill};
    lsm_cia402_update(&ax, &f, now);
}

/* BaseNode402's statusword masks */
static const char *state_name(uint16_t sw)
{
    if ((sw & 0x4F) == 0x00)
        return "NOT READY TO SWITCH ON";
    if ((sw & 0x4F) == 0x40)
        return "SWITCH ON DISABLED";
    if ((sw & 0x6F) == 0x21)
        return "READY TO SWITCH ON";
    if ((sw & 0x6F) == 0x23)
        return "SWITCHED ON";
    if ((sw & 0x6F) == 0x27)
        return "OPERATION ENABLED";
    if ((sw & 0x4F) == 0x08)
        return "FAULT";
    if ((sw & 0x4F) == 0x0F)
        return "FAULT REACTION ACTIVE";
    if ((sw & 0x6F) == 0x07)
        return "QUICK STOP ACTIVE";
    return "UNKNOWN";
}

static const char *k_names[] = {"NOT READY TO SWITCH ON", "SWITCH ON DISABLED", "READY TO SWITCH ON",    "SWITCHED ON",
                                "OPERATION ENABLED",      "QUICK STOP ACTIVE",  "FAULT REACTION ACTIVE", "FAULT"};

static void expect_state(lsm_cia402_state s)
{
    if (ax.state != s)
        fail_msg("state %s, expected %s", k_names[ax.state], k_names[s]);
    if (strcmp(state_name(ax.statusword), k_names[s]) != 0)
        fail_msg("statusword 0x%04X reads %s, expected %s", ax.statusword, state_name(ax.statusword), k_names[s]);
    assert_true(ax.statusword & LSM_CIA402_SW_REMOTE);
}

/* From power-on to state s, at standstill. Quick stop option 6 (stay in QUICK STOP ACTIVE), so that the
 * table can show transition 11 on its own. */
static void reach(lsm_cia402_state s)
{
    setup(NULL);
    assert_int_equal(lsm_cia402_od_write(&ax, 0x605A, 0, 6, now), 0);
    switch (s) {
    case LSM_CIA402_SWITCH_ON_DISABLED: break;
    case LSM_CIA402_READY_TO_SWITCH_ON: cw(0x06); break;
    case LSM_CIA402_SWITCHED_ON: cw(0x06), cw(0x07); break;
    case LSM_CIA402_OPERATION_ENABLED: cw(0x06), cw(0x07), cw(0x0F); break;
    case LSM_CIA402_QUICK_STOP_ACTIVE: cw(0x06), cw(0x07), cw(0x0F), cw(0x02); break;
    case LSM_CIA402_FAULT:
        cw(0x00);
        lsm_cia402_fault(&ax, 0x1234, true);
        break;
    case LSM_CIA402_FAULT_REACTION_ACTIVE:
        cw(0x06), cw(0x07), cw(0x0F);
        fb(0, 0, false);
        lsm_cia402_fault(&ax, 0x1234, true);
        break;
    default: break;
    }
    expect_state(s);
}

/* The transition table at standstill (QUICK STOP ACTIVE with option 6, which stays). */
static void test_transition_table(void **state)
{
    (void)state;
    enum {
        SOD = LSM_CIA402_SWITCH_ON_DISABLED,
        RTSO = LSM_CIA402_READY_TO_SWITCH_ON,
        SO = LSM_CIA402_SWITCHED_ON,
        OE = LSM_CIA402_OPERATION_ENABLED,
        QSA = LSM_CIA402_QUICK_STOP_ACTIVE,
        FRA = LSM_CIA402_FAULT_REACTION_ACTIVE,
        F = LSM_CIA402_FAULT
    };
    static const uint16_t cmds[] = {0x06, 0x07, 0x0F, 0x00, 0x02, 0x80, 0x0E, 0x0B};
    static const uint8_t from[] = {SOD, RTSO, SO, OE, QSA, F, FRA};
    /* rows: from; columns: shutdown, switch on / disable op, enable op, disable voltage, quick stop,
       0x80 (fault reset bit; a disable voltage outside FAULT), 0x0E (shutdown with bit 3), 0x0B (quick stop with bits 0, 3) */
    static const uint8_t want[7][8] = {
        /* SOD  */ {RTSO, SOD, SOD, SOD, SOD, SOD, RTSO, SOD},
        /* RTSO */ {RTSO, SO, OE, SOD, SOD, SOD, RTSO, SOD},
        /* SO   */ {RTSO, SO, OE, SOD, SOD, SOD, RTSO, SOD},
        /* OE   */ {RTSO, SO, OE, SOD, QSA, SOD, RTSO, QSA},
        /* QSA  */ {QSA, QSA, OE, SOD, QSA, SOD, QSA, QSA},
        /* F    */ {F, F, F, F, F, SOD, F, F},
        /* FRA  */ {FRA, FRA, FRA, FRA, FRA, FRA, FRA, FRA},
    };
    for (size_t i = 0; i < sizeof from; i++) {
        for (size_t j = 0; j < sizeof cmds / sizeof cmds[0]; j++) {
            reach((lsm_cia402_state)from[i]);
            cw(cmds[j]);
            if (ax.state != want[i][j])
                fail_msg("from %s with 0x%02X: %s, expected %s", k_names[from[i]], cmds[j], k_names[ax.state],
                         k_names[want[i][j]]);
            expect_state((lsm_cia402_state)want[i][j]);
        }
    }
}

static void test_statusword_values(void **state)
{
    (void)state;
    reach(LSM_CIA402_SWITCH_ON_DISABLED);
    assert_int_equal(ax.statusword, 0x0240);
    reach(LSM_CIA402_READY_TO_SWITCH_ON);
    assert_int_equal(ax.statusword, 0x0231);
    reach(LSM_CIA402_SWITCHED_ON);
    assert_int_equal(ax.statusword, 0x0233);
    reach(LSM_CIA402_OPERATION_ENABLED);
    assert_int_equal(ax.statusword, 0x0637); /* PP at rest on its target: target reached */
    reach(LSM_CIA402_QUICK_STOP_ACTIVE);
    assert_int_equal(ax.statusword, 0x0217);
    reach(LSM_CIA402_FAULT);
    assert_int_equal(ax.statusword, 0x0208);
    reach(LSM_CIA402_FAULT_REACTION_ACTIVE);
    assert_int_equal(ax.statusword, 0x420F); /* stopping */
}

static void test_stops_wait_for_standstill(void **state)
{
    (void)state;
    lsm_cia402_stop_req r;
    /* 5: disable operation while moving -> slow-down ramp, then SWITCHED ON */
    reach(LSM_CIA402_OPERATION_ENABLED);
    assert_false(lsm_cia402_stop_request(&ax, &r) != LSM_CIA402_STOP_NONE);
    assert_true(lsm_cia402_motion_allowed(&ax));
    fb(10, 10, false);
    cw(0x07);
    expect_state(LSM_CIA402_OPERATION_ENABLED);
    assert_true(ax.statusword & LSM_CIA402_SW_STOPPING);
    assert_int_equal(lsm_cia402_stop_request(&ax, &r), LSM_CIA402_STOP_SLOW);
    assert_int_equal(r.decel, ax.profile_decel);
    assert_true(r.jerk == ax.profile_jerk);
    assert_false(lsm_cia402_motion_allowed(&ax));
    fb(20, 20, false);
    expect_state(LSM_CIA402_OPERATION_ENABLED);
    fb(25, 25, true);
    expect_state(LSM_CIA402_SWITCHED_ON);
    /* 8: shutdown while moving -> READY TO SWITCH ON after the stop */
    reach(LSM_CIA402_OPERATION_ENABLED);
    fb(0, 0, false);
    cw(0x06);
    assert_int_equal(lsm_cia402_stop_request(&ax, &r), LSM_CIA402_STOP_SLOW);
    fb(0, 0, true);
    expect_state(LSM_CIA402_READY_TO_SWITCH_ON);
    /* 9: disable voltage while moving -> quick-stop ramp, then SOD */
    reach(LSM_CIA402_OPERATION_ENABLED);
    fb(0, 0, false);
    cw(0x00);
    assert_int_equal(lsm_cia402_stop_request(&ax, &r), LSM_CIA402_STOP_QUICK);
    assert_int_equal(r.decel, ax.quick_stop_decel);
    cw(0x0F); /* asking for operation again does not cancel a disable voltage */
    assert_int_equal(lsm_cia402_stop_request(&ax, NULL), LSM_CIA402_STOP_QUICK);
    fb(0, 0, true);
    expect_state(LSM_CIA402_SWITCH_ON_DISABLED);
    /* a pending disable operation is cancelled by enable operation */
    reach(LSM_CIA402_OPERATION_ENABLED);
    fb(0, 0, false);
    cw(0x07);
    assert_int_equal(lsm_cia402_stop_request(&ax, NULL), LSM_CIA402_STOP_SLOW);
    cw(0x0F);
    assert_int_equal(lsm_cia402_stop_request(&ax, NULL), LSM_CIA402_STOP_NONE);
    fb(0, 0, true);
    expect_state(LSM_CIA402_OPERATION_ENABLED);
}

static void test_quick_stop_options(void **state)
{
    (void)state;
    static const struct {
        int16_t opt;
        uint8_t kind;
        bool stays;
    } o[] = {{1, LSM_CIA402_STOP_SLOW, false},
             {2, LSM_CIA402_STOP_QUICK, false},
             {5, LSM_CIA402_STOP_SLOW, true},
             {6, LSM_CIA402_STOP_QUICK, true}};
    for (size_t i = 0; i < 4; i++) {
        reach(LSM_CIA402_OPERATION_ENABLED);
        assert_int_equal(lsm_cia402_od_write(&ax, 0x605A, 0, o[i].opt, now), 0);
        fb(0, 0, false);
        cw(0x02);
        expect_state(LSM_CIA402_QUICK_STOP_ACTIVE); /* 11 at once, while it stops */
        lsm_cia402_stop_req r;
        assert_int_equal(lsm_cia402_stop_request(&ax, &r), o[i].kind);
        assert_int_equal(r.decel, o[i].kind == LSM_CIA402_STOP_SLOW ? ax.profile_decel : ax.quick_stop_decel);
        assert_true(lsm_cia402_power_enabled(&ax));
        cw(0x0F); /* 16 is only possible at rest */
        expect_state(LSM_CIA402_QUICK_STOP_ACTIVE);
        fb(0, 0, true);
        expect_state(o[i].stays ? LSM_CIA402_QUICK_STOP_ACTIVE : LSM_CIA402_SWITCH_ON_DISABLED);
        if (o[i].stays) {
            cw(0x02);
            cw(0x0F); /* 16 */
            expect_state(LSM_CIA402_OPERATION_ENABLED);
        }
    }
    /* options that would coast are refused */
    for (int16_t bad = -1; bad <= 8; bad++) {
        if (bad == 1 || bad == 2 || bad == 5 || bad == 6)
            continue;
        assert_int_equal(lsm_cia402_od_write(&ax, 0x605A, 0, bad, now), LSM_CO_ABORT_VALUE);
    }
    /* disable voltage in QSA while still moving waits for the stop */
    reach(LSM_CIA402_OPERATION_ENABLED);
    assert_int_equal(lsm_cia402_od_write(&ax, 0x605A, 0, 6, now), 0);
    fb(0, 0, false);
    cw(0x02);
    cw(0x00);
    expect_state(LSM_CIA402_QUICK_STOP_ACTIVE);
    fb(0, 0, true);
    expect_state(LSM_CIA402_SWITCH_ON_DISABLED);
}

static void test_fault(void **state)
{
    (void)state;
    lsm_cia402_event ev;
    reach(LSM_CIA402_OPERATION_ENABLED);
    fb(0, 0, false);
    lsm_cia402_fault(&ax, 0x5555, true);
    expect_state(LSM_CIA402_FAULT_REACTION_ACTIVE);
    assert_int_equal(ax.error_code, 0x5555);
    assert_int_equal(lsm_cia402_stop_request(&ax, NULL), LSM_CIA402_STOP_EMERGENCY);
    assert_true(lsm_cia402_take_event(&ax, &ev));
    assert_true(ev.raise);
    assert_int_equal(ev.code, 0x5555);
    assert_false(lsm_cia402_take_event(&ax, &ev));
    lsm_cia402_fault(&ax, 0x6666, true); /* the first fault wins */
    assert_int_equal(ax.error_code, 0x5555);
    assert_false(lsm_cia402_take_event(&ax, &ev));
    cw(0x80); /* commands are ignored during the reaction */
    expect_state(LSM_CIA402_FAULT_REACTION_ACTIVE);
    fb(0, 0, true);
    expect_state(LSM_CIA402_FAULT); /* 14 */
    /* the fault reset needs a rising edge of bit 7 */
    cw(0x80);
    expect_state(LSM_CIA402_FAULT);
    cw(0x00);
    lsm_cia402_set_fault_hold(&ax, true);
    cw(0x80);
    expect_state(LSM_CIA402_FAULT); /* refused while held */
    cw(0x00);
    lsm_cia402_set_fault_hold(&ax, false);
    cw(0x80);
    expect_state(LSM_CIA402_SWITCH_ON_DISABLED); /* 15 */
    assert_int_equal(ax.error_code, 0);
    assert_true(lsm_cia402_take_event(&ax, &ev));
    assert_false(ev.raise);
    assert_int_equal(ev.code, 0x5555);
    /* a fault with report = false makes no events */
    lsm_cia402_fault(&ax, 0x9000, false);
    expect_state(LSM_CIA402_FAULT); /* at rest: 13 and 14 at once */
    cw(0x00);
    cw(0x80);
    assert_false(lsm_cia402_take_event(&ax, &ev));
}

static void pp_enable(void)
{
    reach(LSM_CIA402_OPERATION_ENABLED);
    assert_int_equal(ax.mode_display, LSM_CIA402_MODE_PP);
}

static void set_target(int32_t t)
{
    assert_int_equal(lsm_cia402_od_write(&ax, 0x607A, 0, t, now), 0);
}

static void test_pp_single_setpoint(void **state)
{
    (void)state;
    lsm_cia402_setpoint sp;
    pp_enable();
    assert_true(ax.statusword & LSM_CIA402_SW_TARGET_REACHED);
    set_target(1000);
    cw(0x3F); /* enable + new set-point + change immediately */
    assert_true(ax.statusword & LSM_CIA402_SW_ACK);
    assert_false(ax.statusword & LSM_CIA402_SW_TARGET_REACHED);
    assert_int_equal(lsm_cia402_pp_fetch(&ax, &sp), LSM_CIA402_SP_START);
    assert_int_equal(sp.target, 1000);
    assert_int_equal(sp.velocity, 10000);
    assert_int_equal(sp.accel, 100000);
    assert_int_equal(sp.decel, 100000);
    assert_true(sp.jerk == 10000000u);
    assert_true(sp.snap == 1000000000u);
    assert_int_equal(sp.profile_type, 1);
    assert_false(sp.blend);
    assert_int_equal(lsm_cia402_pp_fetch(&ax, &sp), LSM_CIA402_SP_NONE); /* fetched once */
    cw(0x2F);                                                            /* master clears bit 4 */
    assert_false(ax.statusword & LSM_CIA402_SW_ACK);
    fb(500, 498, false);
    assert_false(ax.statusword & LSM_CIA402_SW_TARGET_REACHED);
    /* change set immediately while moving: REPLACE, with the parameters of that moment */
    assert_int_equal(lsm_cia402_od_write(&ax, 0x6086, 0, 0, now), 0);
    ax.profile_velocity = 2222;
    set_target(3000);
    cw(0x3F);
    ax.profile_velocity = 3333; /* after the edge: not captured */
    assert_int_equal(lsm_cia402_pp_fetch(&ax, &sp), LSM_CIA402_SP_REPLACE);
    assert_int_equal(sp.target, 3000);
    assert_int_equal(sp.velocity, 2222);
    assert_int_equal(sp.profile_type, 0);
    cw(0x2F);
    /* the move ends: done, at rest within the window (10 counts) */
    lsm_cia402_pp_done(&ax);
    fb(3000, 2991, true); /* 9 counts off: inside the 10-count window */
    assert_true(ax.statusword & LSM_CIA402_SW_TARGET_REACHED);
}

static void test_pp_target_reached_window(void **state)
{
    (void)state;
    lsm_cia402_setpoint sp;
    pp_enable();
    set_target(3000);
    cw(0x3F);
    assert_int_equal(lsm_cia402_pp_fetch(&ax, &sp), LSM_CIA402_SP_START);
    cw(0x2F);
    lsm_cia402_pp_done(&ax);
    fb(3000, 2989, true); /* 11 counts off: outside the 10-count window */
    assert_false(ax.statusword & LSM_CIA402_SW_TARGET_REACHED);
    assert_false(lsm_cia402_in_position(&ax));
    fb(3000, 2990, true); /* 10: inside */
    assert_true(ax.statusword & LSM_CIA402_SW_TARGET_REACHED);
    assert_true(lsm_cia402_in_position(&ax));
}

static void test_pp_set_of_setpoints(void **state)
{
    (void)state;
    lsm_cia402_setpoint sp;
    pp_enable();
    set_target(100);
    cw(0x1F); /* new set-point, not immediately */
    assert_true(ax.statusword & LSM_CIA402_SW_ACK);
    assert_int_equal(lsm_cia402_pp_fetch(&ax, &sp), LSM_CIA402_SP_START);
    assert_int_equal(sp.target, 100);
    fb(10, 10, false);
    cw(0x0F);
    assert_false(ax.statusword & LSM_CIA402_SW_ACK); /* room for the next one */
    set_target(200);
    cw(0x1F | LSM_CIA402_CW_CHANGE_ON_SETPOINT);
    assert_true(ax.statusword & LSM_CIA402_SW_ACK);
    assert_int_equal(lsm_cia402_pp_fetch(&ax, &sp), LSM_CIA402_SP_NONE); /* buffered, not started */
    assert_true(lsm_cia402_pp_peek_next(&ax, &sp));
    assert_int_equal(sp.target, 200);
    assert_true(sp.blend);
    cw(0x0F);
    assert_true(ax.statusword & LSM_CIA402_SW_ACK); /* buffer full: stays set */
    set_target(300);
    cw(0x1F);
    assert_int_equal(ax.sp_ignored, 1); /* no room: ignored */
    assert_true(lsm_cia402_pp_peek_next(&ax, &sp));
    assert_int_equal(sp.target, 200);
    cw(0x0F);
    /* the first move ends: the second starts, ack falls */
    lsm_cia402_pp_done(&ax);
    assert_false(ax.statusword & LSM_CIA402_SW_ACK);
    assert_int_equal(lsm_cia402_pp_fetch(&ax, &sp), LSM_CIA402_SP_START);
    assert_int_equal(sp.target, 200);
    assert_false(lsm_cia402_pp_peek_next(&ax, &sp));
    lsm_cia402_pp_done(&ax);
    fb(200, 200, true);
    assert_true(ax.statusword & LSM_CIA402_SW_TARGET_REACHED);
    /* relative: on top of the last target */
    set_target(-50);
    cw(0x5F);
    assert_int_equal(lsm_cia402_pp_fetch(&ax, &sp), LSM_CIA402_SP_START);
    assert_int_equal(sp.target, 150);
    cw(0x4F);
    lsm_cia402_pp_done(&ax);
    fb(150, 150, true);
    /* relative overflow: not acknowledged, internal limit bit */
    set_target(INT32_MAX);
    cw(0x5F);
    assert_false(ax.statusword & LSM_CIA402_SW_ACK);
    assert_true(ax.statusword & LSM_CIA402_SW_LIMIT);
    assert_int_equal(lsm_cia402_pp_fetch(&ax, &sp), LSM_CIA402_SP_NONE);
    cw(0x4F);
    set_target(10);
    cw(0x5F);
    assert_false(ax.statusword & LSM_CIA402_SW_LIMIT);
    assert_int_equal(lsm_cia402_pp_fetch(&ax, &sp), LSM_CIA402_SP_START);
    assert_int_equal(sp.target, 160);
}

static void test_pp_halt(void **state)
{
    (void)state;
    lsm_cia402_setpoint sp;
    lsm_cia402_stop_req r;
    pp_enable();
    set_target(5000);
    cw(0x3F);
    assert_int_equal(lsm_cia402_pp_fetch(&ax, &sp), LSM_CIA402_SP_START);
    fb(100, 100, false);
    cw(0x2F | LSM_CIA402_CW_HALT);
    assert_int_equal(lsm_cia402_stop_request(&ax, &r), LSM_CIA402_STOP_HALT);
    assert_int_equal(r.decel, ax.profile_decel);
    expect_state(LSM_CIA402_OPERATION_ENABLED);
    fb(200, 200, true);
    assert_true(ax.statusword & LSM_CIA402_SW_TARGET_REACHED); /* halted at rest */
    set_target(6000);
    cw(0x3F | LSM_CIA402_CW_HALT); /* a set-point during halt is taken, not started */
    assert_int_equal(lsm_cia402_pp_fetch(&ax, &sp), LSM_CIA402_SP_NONE);
    cw(0x2F); /* release */
    assert_int_equal(lsm_cia402_stop_request(&ax, NULL), LSM_CIA402_STOP_NONE);
    assert_int_equal(lsm_cia402_pp_fetch(&ax, &sp), LSM_CIA402_SP_REPLACE);
    assert_int_equal(sp.target, 6000);
}

static void test_setpoint_needs_pp_and_oe(void **state)
{
    (void)state;
    lsm_cia402_setpoint sp;
    reach(LSM_CIA402_SWITCHED_ON);
    set_target(10);
    cw(0x17); /* bit 4 while only switched on */
    assert_false(ax.statusword & LSM_CIA402_SW_ACK);
    cw(0x0F);
    assert_int_equal(lsm_cia402_pp_fetch(&ax, &sp), LSM_CIA402_SP_NONE);
    assert_int_equal(lsm_cia402_od_write(&ax, 0x6060, 0, LSM_CIA402_MODE_CSP, now), 0);
    assert_int_equal(ax.mode_display, LSM_CIA402_MODE_CSP);
    cw(0x1F);
    assert_int_equal(lsm_cia402_pp_fetch(&ax, &sp), LSM_CIA402_SP_NONE);
}

static void test_mode_switch_at_rest(void **state)
{
    (void)state;
    lsm_cia402_setpoint sp;
    pp_enable();
    set_target(50);
    cw(0x3F);
    assert_int_equal(lsm_cia402_pp_fetch(&ax, &sp), LSM_CIA402_SP_START);
    fb(1, 1, false);
    assert_int_equal(lsm_cia402_od_write(&ax, 0x6060, 0, LSM_CIA402_MODE_CSP, now), 0);
    assert_int_equal(ax.mode, LSM_CIA402_MODE_CSP);
    assert_int_equal(ax.mode_display, LSM_CIA402_MODE_PP); /* still moving */
    lsm_cia402_pp_done(&ax);
    fb(50, 50, true);
    assert_int_equal(ax.mode_display, LSM_CIA402_MODE_CSP);
    assert_int_equal(lsm_cia402_od_write(&ax, 0x6060, 0, 3, now), LSM_CO_ABORT_VALUE);
    assert_int_equal(lsm_cia402_od_write(&ax, 0x6060, 0, LSM_CIA402_MODE_PATH, now), 0);
    assert_int_equal(lsm_cia402_od_write(&ax, 0x6060, 0, LSM_CIA402_MODE_NONE, now), 0);
}

static void test_csp(void **state)
{
    (void)state;
    int32_t t;
    assert_int_equal(lsm_cia402_od_write(&ax, 0x6060, 0, LSM_CIA402_MODE_CSP, now), 0);
    set_target(77); /* not enabled: not passed */
    reach(LSM_CIA402_OPERATION_ENABLED);
    assert_int_equal(lsm_cia402_od_write(&ax, 0x6060, 0, LSM_CIA402_MODE_CSP, now), 0);
    assert_false(lsm_cia402_csp_fetch(&ax, &t));
    assert_true(ax.statusword & LSM_CIA402_SW_ACK); /* following the command value */
    for (int32_t k = 1; k <= 5; k++) {
        set_target(k * 1000);
        assert_true(lsm_cia402_csp_fetch(&ax, &t));
        assert_int_equal(t, k * 1000);
        assert_false(lsm_cia402_csp_fetch(&ax, &t));
        fb(t, t, false);
    }
    cw(0x0F | LSM_CIA402_CW_HALT);
    assert_false(ax.statusword & LSM_CIA402_SW_ACK);
    set_target(9999);
    assert_false(lsm_cia402_csp_fetch(&ax, &t));
    assert_int_equal(lsm_cia402_stop_request(&ax, NULL), LSM_CIA402_STOP_HALT);
}

static void test_following_error(void **state)
{
    (void)state;
    pp_enable();
    ax.fe_window = 100;
    ax.fe_timeout_ms = 10;
    now = 1000;
    fb(1150, 1000, false);
    assert_int_equal(ax.fe_actual, 150);
    assert_true(ax.statusword & LSM_CIA402_SW_FOLLOWING_ERROR);
    now = 5000;
    fb(1050, 1000, false); /* back inside: the timer restarts */
    assert_false(ax.statusword & LSM_CIA402_SW_FOLLOWING_ERROR);
    now = 6000;
    fb(1000, 1101, false);
    assert_int_equal(ax.fe_actual, -101);
    now = 15999;
    fb(1000, 1101, false);
    expect_state(LSM_CIA402_OPERATION_ENABLED);
    now = 16000;
    fb(1000, 1101, false);
    expect_state(LSM_CIA402_FAULT_REACTION_ACTIVE);
    assert_int_equal(ax.error_code, 0x8611);
    lsm_cia402_event ev;
    assert_true(lsm_cia402_take_event(&ax, &ev));
    assert_int_equal(ev.code, 0x8611);
    fb(1000, 1101, true);
    expect_state(LSM_CIA402_FAULT);
    /* window 0xFFFFFFFF: off */
    pp_enable();
    ax.fe_window = 0xFFFFFFFFu;
    ax.fe_timeout_ms = 0;
    fb(INT32_MAX, INT32_MIN, false);
    assert_int_equal(ax.fe_actual, INT32_MAX); /* saturated */
    expect_state(LSM_CIA402_OPERATION_ENABLED);
}

static void test_outputs(void **state)
{
    (void)state;
    reach(LSM_CIA402_SWITCHED_ON);
    assert_false(lsm_cia402_power_enabled(&ax));
    assert_false(lsm_cia402_in_position(&ax));
    assert_int_equal(lsm_cia402_stop_request(&ax, NULL), LSM_CIA402_STOP_EMERGENCY); /* no motion allowed */
    reach(LSM_CIA402_OPERATION_ENABLED);
    assert_true(lsm_cia402_power_enabled(&ax));
    assert_true(lsm_cia402_in_position(&ax));
    fb(0, 0, false);
    assert_false(lsm_cia402_in_position(&ax));
    reach(LSM_CIA402_FAULT_REACTION_ACTIVE);
    assert_true(lsm_cia402_power_enabled(&ax)); /* powered while it stops */
    reach(LSM_CIA402_FAULT);
    assert_false(lsm_cia402_power_enabled(&ax));
    assert_int_equal(lsm_cia402_get_state(&ax), LSM_CIA402_FAULT);
}

/* Through the node: controlword by RPDO, statusword by SDO, multi-axis indices. */
static void test_through_node(void **state)
{
    (void)state;
    static test_node tn;
    assert_int_equal(tn_init(&tn, 2, PATHCAP), LSM_OK);
    tn_nmt(&tn, 0x01, NODE_ID);
    static const uint16_t seq[] = {0x06, 0x07, 0x0F};
    for (size_t i = 0; i < 3; i++) {
        uint8_t d[2] = {(uint8_t)seq[i], 0};
        assert_int_equal(tn_rx(&tn, mkframe(0x205, 2, d)), LSM_OK);
    }
    uint64_t v;
    assert_int_equal(sdo_read_u(&tn, 0x6041, 0, &v), 0);
    assert_int_equal(v & 0x6F, 0x27);
    assert_int_equal(sdo_read_u(&tn, 0x6841, 0, &v), 0);
    assert_int_equal(v & 0x4F, 0x40); /* axis 1 untouched */
    assert_int_equal(sdo_read_u(&tn, 0x6502, 0, &v), 0);
    assert_int_equal(v, LSM_CIA402_SUPPORTED_MODES);
    assert_int_equal(sdo_read_u(&tn, 0x6D02, 0, &v), 0); /* 0x6502 + 0x800 */
    assert_int_equal(sdo_read_u(&tn, 0x7502, 0, &v), LSM_CO_ABORT_NO_OBJECT);
    assert_true(lsm_canopen_drive_enable(&tn.node));
    /* the node turns application faults into EMCY 0xXXXX with the axis in byte 3 */
    assert_int_equal(lsm_canopen_axis_fault(&tn.node, 2, 0x7300), LSM_E_ARG);
    assert_int_equal(lsm_canopen_axis_fault(&tn.node, 1, 0x7300), LSM_OK);
    lsm_canopen_process(&tn.node, 0);
    drain(&tn);
    lsm_can_frame e;
    assert_int_equal(count_id(&tn, 0x085, &e), 1);
    assert_int_equal(lsm_can_get_u16(&e.data[0]), 0x7300);
    assert_int_equal(e.data[3], 1);
    assert_true(e.data[2] & LSM_CO_ERREG_PROFILE);
    /* fault reset on axis 1 (0x6840): EMCY error reset */
    assert_int_equal(sdo_write_u(&tn, 0x6840, 0, 0x80, 2), 0);
    lsm_canopen_process(&tn.node, 0);
    drain(&tn);
    assert_int_equal(count_id(&tn, 0x085, &e), 1);
    assert_int_equal(lsm_can_get_u16(&e.data[0]), 0x0000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_transition_table, setup),
        cmocka_unit_test_setup(test_statusword_values, setup),
        cmocka_unit_test_setup(test_stops_wait_for_standstill, setup),
        cmocka_unit_test_setup(test_quick_stop_options, setup),
        cmocka_unit_test_setup(test_fault, setup),
        cmocka_unit_test_setup(test_pp_single_setpoint, setup),
        cmocka_unit_test_setup(test_pp_target_reached_window, setup),
        cmocka_unit_test_setup(test_pp_set_of_setpoints, setup),
        cmocka_unit_test_setup(test_pp_halt, setup),
        cmocka_unit_test_setup(test_setpoint_needs_pp_and_oe, setup),
        cmocka_unit_test_setup(test_mode_switch_at_rest, setup),
        cmocka_unit_test_setup(test_csp, setup),
        cmocka_unit_test_setup(test_following_error, setup),
        cmocka_unit_test_setup(test_outputs, setup),
        cmocka_unit_test(test_through_node),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
