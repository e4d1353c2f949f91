#include "ctl_app.h"

#include <string.h>

lsm_status ctl_app_init(ctl_app *a, const ctl_app_config *cfg)
{
    if (a == NULL || cfg == NULL || cfg->motion == NULL)
        return LSM_E_NULL;
    if (cfg->cycle_us < 100u || cfg->cycle_us > 100000u || cfg->link.getc == NULL || cfg->link.write == NULL ||
        cfg->link.room == NULL)
        return LSM_E_ARG;
    memset(a, 0, sizeof *a);
    a->motion = cfg->motion;
    a->link = cfg->link;
    a->cycle_us = cfg->cycle_us;
    (void)lsm_slcan_init(&a->sl);
    lsm_canopen_config cc = lsm_canopen_default_config();
    cc.node_id = cfg->node_id;
    cc.n_axes = cfg->n_axes;
    cc.heartbeat_ms = cfg->heartbeat_ms;
    cc.device_name = cfg->device_name;
    cc.tx_storage = a->txbuf;
    cc.tx_cap = CTL_TXQ;
    cc.path_storage = a->blocks;
    cc.path_cap = CTL_PATH_SLOTS;
    cc.sdo_background = true; /* the SDO server runs in ctl_app_background */
    lsm_status st = lsm_canopen_init(&a->co, &cc, 0u);
    if (st != LSM_OK)
        return st;
    ctl_motion_config mc;
    mc.n_axes = cfg->n_axes;
    mc.cycle_s = (lsm_real)cfg->cycle_us * (lsm_real)1e-6;
    return ctl_motion_init(a->motion, &mc, &a->co);
}

/* Stage 1: the host's lines since the last tick, bounded. */
static void serve_link_rx(ctl_app *a)
{
    char reply[LSM_SLCAN_REPLY_MAX + 1];
    lsm_can_frame f;
    for (unsigned n = 0; n < CTL_RX_CHARS_PER_TICK; n++) {
        const int c = a->link.getc(a->link.ctx);
        if (c < 0)
            break;
        const lsm_slcan_event ev = lsm_slcan_feed(&a->sl, (char)c, &f, reply);
        if (ev == LSM_SLCAN_EV_NONE)
            continue;
        if (ev == LSM_SLCAN_EV_FRAME) {
            a->n.frames_in++;
            if (lsm_canopen_rx(&a->co, &f, a->now_us) != LSM_OK)
                a->n.frames_refused++;
        }
        if (!a->link.write(a->link.ctx, reply, strlen(reply)))
            a->n.replies_lost++;
    }
}

/* Stage 4: the node's frames up the link while it has room. */
static void serve_link_tx(ctl_app *a)
{
    char line[LSM_SLCAN_FRAME_MAX + 1];
    for (;;) {
        if (!a->have_pending) {
            if (!lsm_canopen_tx_pop(&a->co, &a->pending))
                return;
            a->have_pending = true;
        }
        if (!a->sl.open) {
            a->n.frames_closed++;
            a->have_pending = false;
            continue;
        }
        const size_t len = lsm_slcan_encode(&a->pending, line);
        if (len > a->link.room(a->link.ctx)) {
            a->n.link_waits++;
            return;
        }
        (void)a->link.write(a->link.ctx, line, len);
        a->have_pending = false;
        a->n.frames_out++;
    }
}

void ctl_app_tick(ctl_app *a, uint32_t now_us, bool estop_active, const lsm_canopen_tick_stats *stats)
{
    a->now_us = now_us;
    if (stats != NULL)
        lsm_canopen_set_tick_stats(&a->co, stats);
    serve_link_rx(a);
    lsm_atomic_put_release(&a->clock_us, now_us); /* after the requests it received: lsm_canopen_sdo_background */
    lsm_canopen_estop(&a->co, estop_active, a->now_us);
    (void)lsm_canopen_process(&a->co, a->now_us);
    ctl_motion_tick(a->motion, &a->co, a->now_us);
    serve_link_tx(a);
    a->n.cycles++;
}

bool ctl_app_background(ctl_app *a)
{
    const bool sdo = lsm_canopen_sdo_background(&a->co, lsm_atomic_get_acquire(&a->clock_us));
    const bool motion = ctl_motion_background(a->motion);
    return sdo || motion;
}
