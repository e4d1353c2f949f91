"""Bus-off and recovery. vcan has no CAN controller, so the controller's error frames (linux/can/error.h) are
injected: any socket on vcan0 can send a frame with CAN_ERR_FLAG, and the node's socket, which subscribes to
error frames, receives it exactly as it would from a real controller. Error passive -> EMCY 0x8120; bus-off ->
the node goes silent and applies the communication-error reaction (PRE-OPERATIONAL, 0x6007 quick stop:
a jerk-limited stop); restarted -> EMCY 0x8140 and the heartbeat again. (On a real bus the controller produces
these frames itself; the same path is covered without CAN by tests/canopen/test_canopen.c.)"""
import time

import can
import pytest

from lissom_hil.checks import stop_violations
from lissom_hil.frames import (CAN_ERR_BUSOFF, CAN_ERR_CRTL, CAN_ERR_CRTL_ACTIVE, CAN_ERR_CRTL_TX_PASSIVE,
                               CAN_ERR_RESTARTED)


def _error_frame(rig, bits, data=b"\0" * 8):
    rig.network.bus.send(can.Message(arbitration_id=bits, is_error_frame=True, is_extended_id=False,
                                     data=data, dlc=8))


def test_busoff(rig):
    rig.require_local(pytest, "error frames can only be injected on a virtual bus")
    nid = rig.node_id
    rig.operational()
    rig.enable(0, "PROFILED POSITION")
    rig.set_profile(0, v=100.0, a=1000.0, j=20000.0, snap=2e6, quick_decel=2000.0, profile_type=1)

    # error passive: EMCY 0x8120 (once), then back to error active
    m = rig.frames.mark()
    _error_frame(rig, CAN_ERR_CRTL, bytes([0, CAN_ERR_CRTL_TX_PASSIVE, 0, 0, 0, 0, 0, 0]))
    assert rig.frames.wait_emcy(nid, 0x8120, 1.0, m) is not None, "no error-passive EMCY"
    _error_frame(rig, CAN_ERR_CRTL, bytes([0, CAN_ERR_CRTL_ACTIVE, 0, 0, 0, 0, 0, 0]))

    rig.pp_move(0, 250.0, wait=False)
    rig.wait_moving(0, 20000)  # 20 mm under way
    m = rig.frames.mark()
    _error_frame(rig, CAN_ERR_BUSOFF)
    t_err = rig.frames.wait(lambda f: f.err, 1.0, m).t
    time.sleep(0.6)
    # the node's frames (EMCY, TPDO, SDO response, heartbeat) 50 ms after the error frame: none (frames the
    # node queued before its next cycle saw the error frame may still go out)
    node_ids = {0x80 + nid, 0x180 + nid, 0x280 + nid, 0x380 + nid, 0x480 + nid, 0x580 + nid, 0x700 + nid}
    talk = rig.frames.select(lambda f: f.id in node_ids and not f.err and f.t > t_err + 0.05, m)
    assert not talk, "the node kept transmitting while bus-off: %s" % talk[:5]

    m = rig.frames.mark()
    _error_frame(rig, CAN_ERR_RESTARTED)
    e = rig.frames.wait_emcy(nid, 0x8140, 1.0, m)
    assert e is not None, "no 'recovered from bus-off' EMCY"
    assert rig.wait_heartbeat(0x7F, 1.0, m) is not None, "heartbeat (PRE-OPERATIONAL) not back"
    t_end = time.monotonic() + 3
    while rig.state_of(0) != "SWITCH ON DISABLED":
        assert time.monotonic() < t_end, "axis not stopped after bus-off"
        time.sleep(0.02)
    stopped = rig.demand(0)
    assert 0 < stopped < 250000
    tr = rig.trace()
    q = tr.first(tr.axis(0, "state") == 5)
    assert q is not None, "no quick stop in the trace"
    bad = stop_violations(tr, 0, q, {"a": 2000.0, "j": 20000.0, "snap": 2e6}, pre=1)
    assert not bad, bad
    tr.write_csv(rig.out("busoff_trace.csv"), start=max(q - 400, 0))
    rig.save_plots(rig.out("busoff_trace.csv"), "busoff_trace")
