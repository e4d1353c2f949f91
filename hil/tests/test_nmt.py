"""NMT slave, boot-up and heartbeat producer (CiA 301 §7.2.8)."""
import time

import canopen
import numpy as np


def _hb_times(rig, since, state=None):
    nid = rig.node_id
    return np.array([f.t for f in rig.frames.select(
        lambda f: f.id == 0x700 + nid and len(f.data) == 1 and (state is None or f.data[0] == state), since)])


def test_nmt(rig):
    nid = rig.node_id
    # boot-up (sent once, state byte 0) then heartbeats in PRE-OPERATIONAL (0x7F) every 100 ms (0x1017 default)
    # of the node's clock (the M4 image's clock runs slower than real time and unevenly under load: its period is
    # measured in its own clock, docs/cortex_m.md)
    if rig.kind == "mcu":
        period = rig.node_heartbeat_period(0x7F)
    else:
        m = rig.frames.mark()
        assert rig.frames.wait_count(lambda f: f.id == 0x700 + nid and f.data == b"\x7f", 6, 5.0, m), \
            "fewer than 6 heartbeats in PRE-OPERATIONAL"
        t = _hb_times(rig, m, 0x7F)
        period = np.median(np.diff(t))
    assert abs(period - 0.100) < 0.015, "heartbeat period %.4f s" % period
    assert rig.read(0x1017) == 100

    # OPERATIONAL: heartbeat 0x05 and the node's TPDOs appear
    m = rig.frames.mark()
    rig.operational()
    assert rig.frames.wait(lambda f: f.id == 0x180 + nid, 1.0, m) is not None, "no TPDO1 in OPERATIONAL"

    # STOPPED: heartbeat 0x04, SDO is not served, no PDOs
    m = rig.frames.mark()
    rig.nmt("STOPPED")
    assert rig.wait_heartbeat(0x04, 1.0, m) is not None
    m2 = rig.frames.mark()
    rig.node.sdo.RESPONSE_TIMEOUT = 0.3
    try:
        rig.node.sdo.upload(0x1000, 0)
        assert False, "SDO answered in STOPPED"
    except canopen.SdoCommunicationError:
        pass
    finally:
        rig.node.sdo.RESPONSE_TIMEOUT = 2.0
    time.sleep(0.2)
    assert not rig.frames.select(lambda f: 0x180 <= f.id - nid < 0x580 and (f.id - nid) % 0x80 == 0, m2), \
        "PDOs in STOPPED"

    # back to PRE-OPERATIONAL: SDO again
    m = rig.frames.mark()
    rig.nmt("PRE-OPERATIONAL")
    assert rig.wait_heartbeat(0x7F, 1.0, m) is not None
    assert rig.read(0x1000) == 0x00020192

    # heartbeat producer time: 50 ms, then off
    rig.write(0x1017, 50)
    if rig.kind == "mcu":
        period = rig.node_heartbeat_period()
        assert abs(period - 0.050) < 0.01, "50 ms heartbeat: %.4f s" % period
    else:
        m = rig.frames.mark()
        assert rig.frames.wait_count(lambda f: f.id == 0x700 + nid and len(f.data) == 1, 8, 5.0, m), \
            "fewer than 8 heartbeats at 50 ms"
        t = _hb_times(rig, m)
        assert len(t) >= 6 and abs(np.median(np.diff(t)) - 0.050) < 0.01, "50 ms heartbeat: %s" % np.diff(t)
    rig.write(0x1017, 0)
    if rig.kind == "mcu":
        time.sleep(0.06 * rig.time_scale)  # a heartbeat the image's UART still holds (its clock is scaled)
    m = rig.frames.mark()  # after the write's SDO answer: a heartbeat queued before the write went out before it
    time.sleep(0.3)  # an absence window: nothing may come in it (load can only make a window quieter)
    assert len(_hb_times(rig, m)) == 0, "heartbeat still produced with 0x1017 = 0"

    # reset communication: boot-up again, 0x1017 back to its default; application objects kept
    rig.write(0x6081, 12345)
    m = rig.frames.mark()
    rig.nmt("RESET COMMUNICATION")
    assert rig.frames.wait(lambda f: f.id == 0x700 + nid and f.data == b"\x00", 1.0, m) is not None
    assert rig.read(0x1017) == 100
    assert rig.read(0x6081) == 12345

    # reset node: boot-up, application objects back to their defaults too
    m = rig.frames.mark()
    rig.nmt("RESET")
    assert rig.frames.wait(lambda f: f.id == 0x700 + nid and f.data == b"\x00", 1.0, m) is not None
    assert rig.read(0x6081) == 10000
    assert rig.wait_heartbeat(0x7F, 0.5) is not None
