"""Heartbeat consumer: the master's heartbeat stops during a move -> EMCY 0x8130, NMT PRE-OPERATIONAL
(0x1029 = 0), and the 0x6007 reaction (quick stop) brings the axis to a jerk-limited stop."""
import time

import pytest

from lissom_hil.checks import stop_violations

MASTER_ID = 0x10
# Consumer time: 1 s. The master's heartbeats (every 50 ms) came up to 0.56 s apart in a guest beside a CPU hog
# (docs/reliability.md, test_fault_master_lost_mid_path); a 200 ms consumer then lost the master before the test
# stopped it. The move (200 mm at 80 mm/s) is still under way when the deliberate loss is detected.
CONSUMER_MS = 1000
QS = dict(quick_decel=1500.0, j=30000.0, snap=3e6)


@pytest.mark.motion
def test_heartbeat_loss(rig):
    nid = rig.node_id
    m0 = rig.frames.mark()
    rig.start_heartbeat(MASTER_ID, 0.05)
    rig.write(0x1016, (MASTER_ID << 16) | CONSUMER_MS, sub=1)  # monitor the master
    rig.operational()
    rig.enable(0, "PROFILED POSITION")
    rig.set_profile(0, v=80.0, a=800.0, snap=3e6, profile_type=1, j=30000.0, quick_decel=QS["quick_decel"])
    # the consumer has seen several heartbeats (an event: counted on the bus, not waited for by the clock)
    assert rig.frames.wait_count(lambda f: f.id == 0x700 + MASTER_ID, 8, 5.0, m0), "master heartbeats not produced"
    m = rig.frames.mark()
    assert not rig.frames.emcy(nid, m0), "EMCY while the master's heartbeat runs"
    rig.pp_move(0, 200.0, wait=False)
    rig.wait_moving(0, 20000)  # 20 mm under way
    c = rig.clock_start()
    rig.stop_heartbeat()
    last_hb = rig.frames.select(lambda f: f.id == 0x700 + MASTER_ID, m)[-1].t
    e = rig.frames.wait_emcy(nid, 0x8130, 10.0, m)
    assert e is not None, "no heartbeat EMCY"
    assert e.info == MASTER_ID
    late = (e.t - last_hb) / rig.clock_scale(c)  # in the node's clock (the M4 image's runs slower: docs/cortex_m.md)
    # (upper bound: the consumer time, plus the node's cycle and scheduling under emulation)
    assert CONSUMER_MS / 1000 * 0.9 <= late <= CONSUMER_MS / 1000 + 0.3, "EMCY %.3f s after the last heartbeat" % late
    assert rig.wait_heartbeat(0x7F, 5.0, m) is not None, "node did not go to PRE-OPERATIONAL"
    # quick stop (0x6007 = 3, 0x605A = 2): QUICK STOP ACTIVE until at rest, then SWITCH ON DISABLED (the wait is a
    # bound for a loaded machine: the stop takes well under a second of the node's clock)
    rig.wait_until(lambda: rig.state_of(0) == "SWITCH ON DISABLED", 30.0, "axis did not stop", poll=0.02)
    stopped = rig.demand(0)
    assert 0 < stopped < 200000
    time.sleep(0.1)
    assert rig.demand(0) == stopped
    assert rig.read(0x5020) & 0x02, "machine status: heartbeat lost"
    # the master comes back: the heartbeat error is cleared (EMCY with code 0: no error left)
    m2 = rig.frames.mark()
    rig.start_heartbeat(MASTER_ID, 0.05)
    assert rig.frames.wait_emcy(nid, 0x0000, 10.0, m2) is not None, "no error-reset EMCY"
    if rig.local:
        tr = rig.trace()
        st = tr.axis(0, "state")
        q = tr.first(st == 5)
        assert q is not None
        bad = stop_violations(tr, 0, q, {"a": QS["quick_decel"], "j": QS["j"], "snap": QS["snap"]}, pre=1)
        assert not bad, bad
        tr.write_csv(rig.out("heartbeat_trace.csv"), start=max(q - 600, 0))
        rig.save_plots(rig.out("heartbeat_trace.csv"), "heartbeat_trace")
