#include "cia402.h"

#include <string.h>

#include "co_od.h"

#define NO_PENDING 0xFFu

typedef enum cmd {
    CMD_NONE,
    CMD_SHUTDOWN,
    CMD_SWITCH_ON, /* also disable operation */
    CMD_ENABLE_OPERATION,
    CMD_DISABLE_VOLTAGE,
    CMD_QUICK_STOP
} cmd;

static cmd decode(uint16_t cw)
{
    if (!(cw & LSM_CIA402_CW_ENABLE_VOLTAGE))
        return CMD_DISABLE_VOLTAGE;
    if (!(cw & LSM_CIA402_CW_QUICK_STOP))
        return CMD_QUICK_STOP;
    if (!(cw & LSM_CIA402_CW_SWITCH_ON))
        return CMD_SHUTDOWN;
    if (!(cw & LSM_CIA402_CW_ENABLE_OPERATION))
        return CMD_SWITCH_ON;
    return CMD_ENABLE_OPERATION;
}

lsm_status lsm_cia402_init(lsm_cia402 *ax)
{
    if (ax == NULL)
        return LSM_E_NULL;
    memset(ax, 0, sizeof *ax);
    ax->abort_option = 3;
    ax->quick_stop_option = 2;
    ax->profile_type = 1;
    ax->mode = LSM_CIA402_MODE_PP;
    ax->mode_display = LSM_CIA402_MODE_PP;
    ax->ip_period_value = 1u;
    ax->ip_period_index = -3;
    ax->fe_timeout_ms = 100u;
    ax->fe_window = 10000u;
    ax->pos_window = 10u;
    ax->profile_velocity = 10000u;
    ax->profile_accel = 100000u;
    ax->profile_decel = 100000u;
    ax->quick_stop_decel = 1000000u;
    ax->counts_per_mm = 1000u;
    ax->profile_jerk = 10000000u;
    ax->profile_snap = 1000000000u;
    ax->pending = NO_PENDING;
    ax->standstill = true;
    ax->state = LSM_CIA402_SWITCH_ON_DISABLED; /* transition 1 at once: nothing to self-test */
    ax->statusword = LSM_CIA402_SW_SOD | LSM_CIA402_SW_REMOTE;
    return LSM_OK;
}

static void push_event(lsm_cia402 *ax, uint16_t code, bool raise)
{
    if (ax->n_events < LSM_CIA402_EVENTS) {
        ax->events[ax->n_events].code = code;
        ax->events[ax->n_events].raise = raise;
        ax->n_events++;
    }
}

bool lsm_cia402_take_event(lsm_cia402 *ax, lsm_cia402_event *ev)
{
    if (ax->n_events == 0u)
        return false;
    *ev = ax->events[0];
    ax->n_events--;
    memmove(&ax->events[0], &ax->events[1], ax->n_events * sizeof ax->events[0]);
    return true;
}

static void flush_setpoints(lsm_cia402 *ax)
{
    ax->have_active = false;
    ax->have_next = false;
    ax->fresh = false;
    ax->replace = false;
    ax->csp_new = false;
}

static bool halted(const lsm_cia402 *ax)
{
    return (ax->controlword & LSM_CIA402_CW_HALT) != 0u &&
           (ax->mode_display == LSM_CIA402_MODE_PP || ax->mode_display == LSM_CIA402_MODE_CSP ||
            ax->mode_display == LSM_CIA402_MODE_PATH);
}

bool lsm_cia402_motion_allowed(const lsm_cia402 *ax)
{
    return ax->state == LSM_CIA402_OPERATION_ENABLED && ax->pending == NO_PENDING && !halted(ax);
}

bool lsm_cia402_power_enabled(const lsm_cia402 *ax)
{
    return ax->state == LSM_CIA402_OPERATION_ENABLED || ax->state == LSM_CIA402_QUICK_STOP_ACTIVE ||
           ax->state == LSM_CIA402_FAULT_REACTION_ACTIVE;
}

lsm_cia402_state lsm_cia402_get_state(const lsm_cia402 *ax)
{
    return (lsm_cia402_state)ax->state;
}

static uint8_t quick_stop_kind(const lsm_cia402 *ax)
{
    return (ax->quick_stop_option == 1 || ax->quick_stop_option == 5) ? LSM_CIA402_STOP_SLOW : LSM_CIA402_STOP_QUICK;
}

lsm_cia402_stop lsm_cia402_stop_request(const lsm_cia402 *ax, lsm_cia402_stop_req *req)
{
    uint8_t kind;
    switch (ax->state) {
    case LSM_CIA402_OPERATION_ENABLED:
        if (ax->pending != NO_PENDING)
            kind = ax->pending_stop;
        else if (halted(ax))
            kind = LSM_CIA402_STOP_HALT;
        else
            kind = LSM_CIA402_STOP_NONE;
        break;
    case LSM_CIA402_QUICK_STOP_ACTIVE: kind = ax->pending != NO_PENDING ? ax->pending_stop : quick_stop_kind(ax); break;
    default: kind = LSM_CIA402_STOP_EMERGENCY; break; /* no motion outside OE/QSA: stop at once if anything moves */
    }
    if (req != NULL) {
        req->kind = kind;
        req->decel =
            (kind == LSM_CIA402_STOP_HALT || kind == LSM_CIA402_STOP_SLOW) ? ax->profile_decel : ax->quick_stop_decel;
        req->jerk = ax->profile_jerk;
    }
    return (lsm_cia402_stop)kind;
}

static uint32_t abs_diff(int32_t a, int32_t b)
{
    int64_t d = (int64_t)a - b;
    return (uint32_t)(d < 0 ? -d : d);
}

bool lsm_cia402_in_position(const lsm_cia402 *ax)
{
    if (ax->state != LSM_CIA402_OPERATION_ENABLED || !ax->standstill)
        return false;
    if (ax->mode_display == LSM_CIA402_MODE_PP && (ax->have_active || ax->have_next))
        return false;
    int32_t goal = ax->mode_display == LSM_CIA402_MODE_PP ? ax->last_target : ax->pos_demand;
    return abs_diff(goal, ax->pos_actual) <= ax->pos_window;
}

static void refresh(lsm_cia402 *ax)
{
    uint16_t sw;
    switch (ax->state) {
    case LSM_CIA402_SWITCH_ON_DISABLED: sw = 0x0040u; break;
    case LSM_CIA402_READY_TO_SWITCH_ON: sw = 0x0031u; break;
    case LSM_CIA402_SWITCHED_ON: sw = 0x0033u; break;
    case LSM_CIA402_OPERATION_ENABLED: sw = 0x0037u; break;
    case LSM_CIA402_QUICK_STOP_ACTIVE: sw = 0x0017u; break;
    case LSM_CIA402_FAULT_REACTION_ACTIVE: sw = 0x000Fu; break;
    case LSM_CIA402_FAULT: sw = 0x0008u; break;
    default: sw = 0x0000u; break;
    }
    sw |= LSM_CIA402_SW_REMOTE;
    bool moving_state = ax->state == LSM_CIA402_OPERATION_ENABLED || ax->state == LSM_CIA402_QUICK_STOP_ACTIVE ||
                        ax->state == LSM_CIA402_FAULT_REACTION_ACTIVE;
    if (moving_state) {
        switch (ax->mode_display) {
        case LSM_CIA402_MODE_PP:
            if (ax->ack)
                sw |= LSM_CIA402_SW_ACK;
            if (ax->state == LSM_CIA402_OPERATION_ENABLED && ax->standstill) {
                if (halted(ax) ||
                    (!ax->have_active && !ax->have_next && abs_diff(ax->last_target, ax->pos_actual) <= ax->pos_window))
                    sw |= LSM_CIA402_SW_TARGET_REACHED;
            }
            break;
        case LSM_CIA402_MODE_CSP:
            if (lsm_cia402_motion_allowed(ax))
                sw |= LSM_CIA402_SW_ACK;
            break;
        case LSM_CIA402_MODE_PATH:
            if (lsm_cia402_in_position(ax))
                sw |= LSM_CIA402_SW_TARGET_REACHED;
            break;
        default: break;
        }
        if (lsm_cia402_stop_request(ax, NULL) != LSM_CIA402_STOP_NONE && !ax->standstill)
            sw |= LSM_CIA402_SW_STOPPING;
    }
    if (ax->fe_over)
        sw |= LSM_CIA402_SW_FOLLOWING_ERROR;
    if (ax->limit)
        sw |= LSM_CIA402_SW_LIMIT;
    ax->statusword = sw;
}

static void update_mode_display(lsm_cia402 *ax)
{
    if (ax->mode_display == ax->mode)
        return;
    if (ax->state == LSM_CIA402_OPERATION_ENABLED && (!ax->standstill || ax->have_active))
        return; /* switch when at rest */
    if (ax->state == LSM_CIA402_QUICK_STOP_ACTIVE || ax->state == LSM_CIA402_FAULT_REACTION_ACTIVE)
        if (!ax->standstill)
            return;
    ax->mode_display = ax->mode;
    flush_setpoints(ax);
    ax->ack = false;
}

static void enter(lsm_cia402 *ax, uint8_t state)
{
    uint8_t old = ax->state;
    ax->state = state;
    ax->pending = NO_PENDING;
    if (state != LSM_CIA402_OPERATION_ENABLED) {
        flush_setpoints(ax);
        ax->ack = false;
    }
    if (state == LSM_CIA402_OPERATION_ENABLED && old != LSM_CIA402_OPERATION_ENABLED) {
        ax->last_target = ax->pos_demand; /* relative set-points start from where the axis is */
        ax->limit = false;
        flush_setpoints(ax);
    }
}

/* A transition out of motion: at once at standstill, else after the stop. */
static void leave_motion(lsm_cia402 *ax, uint8_t state, uint8_t stop)
{
    flush_setpoints(ax);
    ax->ack = false;
    if (ax->standstill) {
        enter(ax, state);
        return;
    }
    if (ax->pending == NO_PENDING || stop > ax->pending_stop)
        ax->pending_stop = stop;
    ax->pending = state;
}

static void enter_quick_stop(lsm_cia402 *ax)
{
    enter(ax, LSM_CIA402_QUICK_STOP_ACTIVE);
    if (ax->standstill && (ax->quick_stop_option == 1 || ax->quick_stop_option == 2))
        enter(ax, LSM_CIA402_SWITCH_ON_DISABLED); /* transition 12 at once: nothing to stop */
}

static void apply_command(lsm_cia402 *ax, cmd c)
{
    switch (ax->state) {
    case LSM_CIA402_SWITCH_ON_DISABLED:
        if (c == CMD_SHUTDOWN)
            enter(ax, LSM_CIA402_READY_TO_SWITCH_ON); /* 2 */
        break;
    case LSM_CIA402_READY_TO_SWITCH_ON:
        if (c == CMD_SWITCH_ON)
            enter(ax, LSM_CIA402_SWITCHED_ON); /* 3 */
        else if (c == CMD_ENABLE_OPERATION) {
            enter(ax, LSM_CIA402_SWITCHED_ON);       /* 3 */
            enter(ax, LSM_CIA402_OPERATION_ENABLED); /* 4 */
        } else if (c == CMD_DISABLE_VOLTAGE || c == CMD_QUICK_STOP)
            enter(ax, LSM_CIA402_SWITCH_ON_DISABLED); /* 7 */
        break;
    case LSM_CIA402_SWITCHED_ON:
        if (c == CMD_ENABLE_OPERATION)
            enter(ax, LSM_CIA402_OPERATION_ENABLED); /* 4 */
        else if (c == CMD_SHUTDOWN)
            enter(ax, LSM_CIA402_READY_TO_SWITCH_ON); /* 6 */
        else if (c == CMD_DISABLE_VOLTAGE || c == CMD_QUICK_STOP)
            enter(ax, LSM_CIA402_SWITCH_ON_DISABLED); /* 10 */
        break;
    case LSM_CIA402_OPERATION_ENABLED:
        switch (c) {
        case CMD_SWITCH_ON: leave_motion(ax, LSM_CIA402_SWITCHED_ON, LSM_CIA402_STOP_SLOW); break;               /* 5 */
        case CMD_SHUTDOWN: leave_motion(ax, LSM_CIA402_READY_TO_SWITCH_ON, LSM_CIA402_STOP_SLOW); break;         /* 8 */
        case CMD_DISABLE_VOLTAGE: leave_motion(ax, LSM_CIA402_SWITCH_ON_DISABLED, LSM_CIA402_STOP_QUICK); break; /* 9 */
        case CMD_QUICK_STOP: enter_quick_stop(ax); break; /* 11 */
        case CMD_ENABLE_OPERATION:
            /* a pending 5/8 is cancelled by asking for operation again; the 9 of a disable voltage is not */
            if (ax->pending != NO_PENDING && ax->pending != LSM_CIA402_SWITCH_ON_DISABLED)
                ax->pending = NO_PENDING;
            break;
        default: break;
        }
        break;
    case LSM_CIA402_QUICK_STOP_ACTIVE:
        if (c == CMD_DISABLE_VOLTAGE) {
            if (ax->standstill)
                enter(ax, LSM_CIA402_SWITCH_ON_DISABLED); /* 12 */
            else {
                ax->pending = LSM_CIA402_SWITCH_ON_DISABLED;
                ax->pending_stop = quick_stop_kind(ax);
            }
        } else if (c == CMD_ENABLE_OPERATION && (ax->quick_stop_option == 5 || ax->quick_stop_option == 6) &&
                   ax->standstill) {
            enter(ax, LSM_CIA402_OPERATION_ENABLED); /* 16 */
        }
        break;
    default: break;
    }
}

static void accept_setpoint(lsm_cia402 *ax, uint16_t cw)
{
    bool immediate = (cw & LSM_CIA402_CW_IMMEDIATE) != 0u;
    if (!immediate && ax->have_active && ax->have_next) {
        ax->sp_ignored++;
        return;
    }
    int64_t t = ax->target;
    if (cw & LSM_CIA402_CW_RELATIVE)
        t += ax->last_target;
    if (t > INT32_MAX || t < INT32_MIN) {
        ax->limit = true; /* not acknowledged; bit 11 until a set-point is taken */
        return;
    }
    lsm_cia402_setpoint sp;
    sp.target = (int32_t)t;
    sp.velocity = ax->profile_velocity;
    sp.accel = ax->profile_accel;
    sp.decel = ax->profile_decel;
    sp.jerk = ax->profile_jerk;
    sp.snap = ax->profile_snap;
    sp.profile_type = ax->profile_type;
    sp.blend = (cw & LSM_CIA402_CW_CHANGE_ON_SETPOINT) != 0u;
    sp.id = ++ax->sp_count;
    ax->limit = false;
    ax->last_target = sp.target;
    ax->ack = true;
    if (immediate) {
        ax->replace = ax->have_active || !ax->standstill;
        ax->sp_active = sp;
        ax->have_active = true;
        ax->have_next = false;
        ax->fresh = true;
    } else if (!ax->have_active) {
        ax->sp_active = sp;
        ax->have_active = true;
        ax->fresh = true;
        ax->replace = !ax->standstill;
    } else {
        ax->sp_next = sp;
        ax->have_next = true;
    }
}

static void controlword(lsm_cia402 *ax, uint16_t cw)
{
    uint16_t prev = ax->controlword;
    ax->controlword = cw;
    if (ax->state == LSM_CIA402_FAULT) {
        if ((cw & LSM_CIA402_CW_FAULT_RESET) && !(prev & LSM_CIA402_CW_FAULT_RESET) && !ax->fault_hold) {
            if (ax->fault_reported)
                push_event(ax, ax->error_code, false);
            ax->fault_reported = false;
            ax->error_code = 0u;
            ax->fe_over = false;
            enter(ax, LSM_CIA402_SWITCH_ON_DISABLED); /* 15 */
        }
    } else if (ax->state != LSM_CIA402_FAULT_REACTION_ACTIVE) {
        apply_command(ax, decode(cw));
    }
    if (ax->state == LSM_CIA402_OPERATION_ENABLED && ax->pending == NO_PENDING &&
        ax->mode_display == LSM_CIA402_MODE_PP) {
        if ((cw & LSM_CIA402_CW_NEW_SETPOINT) && !(prev & LSM_CIA402_CW_NEW_SETPOINT))
            accept_setpoint(ax, cw);
        if ((prev & LSM_CIA402_CW_HALT) && !(cw & LSM_CIA402_CW_HALT) && ax->have_active) {
            ax->fresh = true; /* resume the set-point after a halt */
            ax->replace = true;
        }
    }
    if (!(cw & LSM_CIA402_CW_NEW_SETPOINT) && !ax->have_next)
        ax->ack = false;
    update_mode_display(ax);
    refresh(ax);
}

uint32_t lsm_cia402_od_write(lsm_cia402 *ax, uint16_t index, uint8_t sub, int64_t value, uint32_t now_us)
{
    (void)now_us;
    (void)sub; /* every hooked axis object is a sub-index 0 variable */
    switch (index) {
    case 0x6040: controlword(ax, (uint16_t)value); return LSM_CO_ABORT_NONE;
    case 0x6060:
        if (value != LSM_CIA402_MODE_NONE && value != LSM_CIA402_MODE_PP && value != LSM_CIA402_MODE_CSP &&
            value != LSM_CIA402_MODE_PATH)
            return LSM_CO_ABORT_VALUE;
        ax->mode = (int8_t)value;
        update_mode_display(ax);
        refresh(ax);
        return LSM_CO_ABORT_NONE;
    case 0x605A:
        if (value != 1 && value != 2 && value != 5 && value != 6)
            return LSM_CO_ABORT_VALUE;
        ax->quick_stop_option = (int16_t)value;
        return LSM_CO_ABORT_NONE;
    case 0x6086:
        if (value != 0 && value != 1)
            return LSM_CO_ABORT_VALUE;
        ax->profile_type = (int16_t)value;
        return LSM_CO_ABORT_NONE;
    case 0x607A:
        ax->target = (int32_t)value;
        if (ax->mode_display == LSM_CIA402_MODE_CSP && lsm_cia402_motion_allowed(ax))
            ax->csp_new = true;
        return LSM_CO_ABORT_NONE;
    case 0x2001:
        if (lsm_cia402_power_enabled(ax))
            return LSM_CO_ABORT_DEVICE_STATE;
        ax->counts_per_mm = (uint32_t)value;
        return LSM_CO_ABORT_NONE;
    default: return LSM_CO_ABORT_NO_OBJECT;
    }
}

void lsm_cia402_update(lsm_cia402 *ax, const lsm_cia402_feedback *fb, uint32_t now_us)
{
    ax->pos_demand = fb->demand;
    ax->pos_actual = fb->actual;
    ax->vel_actual = fb->velocity;
    ax->standstill = fb->standstill;
    int64_t fe = (int64_t)fb->demand - fb->actual;
    ax->fe_actual = fe > INT32_MAX ? INT32_MAX : fe < INT32_MIN ? INT32_MIN : (int32_t)fe;

    bool monitored = (ax->state == LSM_CIA402_OPERATION_ENABLED || ax->state == LSM_CIA402_QUICK_STOP_ACTIVE) &&
                     ax->mode_display != LSM_CIA402_MODE_NONE && ax->fe_window != 0xFFFFFFFFu;
    if (monitored && (uint64_t)(fe < 0 ? -fe : fe) > ax->fe_window) {
        if (!ax->fe_over) {
            ax->fe_over = true;
            ax->fe_since_us = now_us;
        }
        if ((uint32_t)(now_us - ax->fe_since_us) >= (uint32_t)ax->fe_timeout_ms * 1000u)
            lsm_cia402_fault(ax, 0x8611u, true);
    } else if (ax->state != LSM_CIA402_FAULT && ax->state != LSM_CIA402_FAULT_REACTION_ACTIVE) {
        ax->fe_over = false;
    }

    if (ax->standstill) {
        switch (ax->state) {
        case LSM_CIA402_OPERATION_ENABLED:
            if (ax->pending != NO_PENDING)
                enter(ax, ax->pending);
            break;
        case LSM_CIA402_QUICK_STOP_ACTIVE:
            if (ax->pending != NO_PENDING)
                enter(ax, ax->pending);
            else if (ax->quick_stop_option == 1 || ax->quick_stop_option == 2)
                enter(ax, LSM_CIA402_SWITCH_ON_DISABLED); /* 12 */
            break;
        case LSM_CIA402_FAULT_REACTION_ACTIVE: enter(ax, LSM_CIA402_FAULT); break; /* 14 */
        default: break;
        }
    }
    if (!(ax->controlword & LSM_CIA402_CW_NEW_SETPOINT) && !ax->have_next)
        ax->ack = false;
    update_mode_display(ax);
    refresh(ax);
}

lsm_cia402_sp_event lsm_cia402_pp_fetch(lsm_cia402 *ax, lsm_cia402_setpoint *sp)
{
    if (!ax->fresh || !lsm_cia402_motion_allowed(ax) || ax->mode_display != LSM_CIA402_MODE_PP)
        return LSM_CIA402_SP_NONE;
    *sp = ax->sp_active;
    ax->fresh = false;
    ax->standstill = false; /* assume moving until the application says otherwise */
    lsm_cia402_sp_event ev = ax->replace ? LSM_CIA402_SP_REPLACE : LSM_CIA402_SP_START;
    ax->replace = false;
    refresh(ax);
    return ev;
}

bool lsm_cia402_pp_peek_next(const lsm_cia402 *ax, lsm_cia402_setpoint *sp)
{
    if (!ax->have_next)
        return false;
    *sp = ax->sp_next;
    return true;
}

void lsm_cia402_pp_done(lsm_cia402 *ax)
{
    if (!ax->have_active || ax->fresh)
        return; /* nothing running (or not yet fetched) */
    if (ax->have_next) {
        ax->sp_active = ax->sp_next;
        ax->have_next = false;
        ax->fresh = true;
        ax->replace = false;
    } else {
        ax->have_active = false;
    }
    if (!(ax->controlword & LSM_CIA402_CW_NEW_SETPOINT))
        ax->ack = false;
    refresh(ax);
}

bool lsm_cia402_csp_fetch(lsm_cia402 *ax, int32_t *target)
{
    if (!ax->csp_new || !lsm_cia402_motion_allowed(ax) || ax->mode_display != LSM_CIA402_MODE_CSP)
        return false;
    ax->csp_new = false;
    ax->standstill = false;
    *target = ax->target;
    return true;
}

void lsm_cia402_fault(lsm_cia402 *ax, uint16_t code, bool report)
{
    if (ax->state == LSM_CIA402_FAULT || ax->state == LSM_CIA402_FAULT_REACTION_ACTIVE)
        return; /* the first fault is the one reported */
    ax->error_code = code;
    ax->fault_reported = report;
    if (report)
        push_event(ax, code, true);
    enter(ax, LSM_CIA402_FAULT_REACTION_ACTIVE); /* 13 */
    if (ax->standstill)
        enter(ax, LSM_CIA402_FAULT); /* 14 at once: nothing to stop */
    refresh(ax);
}

void lsm_cia402_set_fault_hold(lsm_cia402 *ax, bool hold)
{
    ax->fault_hold = hold;
}

void lsm_cia402_comm_lost(lsm_cia402 *ax)
{
    switch (ax->abort_option) {
    case 1: lsm_cia402_fault(ax, 0x8130u, false); break;
    case 2:
        if (ax->state != LSM_CIA402_FAULT && ax->state != LSM_CIA402_FAULT_REACTION_ACTIVE)
            apply_command(ax, CMD_DISABLE_VOLTAGE);
        break;
    case 3:
        if (ax->state != LSM_CIA402_FAULT && ax->state != LSM_CIA402_FAULT_REACTION_ACTIVE)
            apply_command(ax, CMD_QUICK_STOP);
        break;
    default: break;
    }
    refresh(ax);
}
