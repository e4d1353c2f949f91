"""Malformed frames: each is ignored (NMT, SDO, remote and 29-bit frames) or answered with its CiA 301 EMCY
(PDO too short 0x8210, too long 0x8220, SYNC with data 0x8240); the node keeps working afterwards."""
import struct

import can


def _send(rig, ident, data=b"", ext=False, rtr=False, dlc=None):
    rig.network.bus.send(can.Message(arbitration_id=ident, data=data, is_extended_id=ext, is_remote_frame=rtr,
                                     dlc=len(data) if dlc is None else dlc))


def test_malformed(rig):
    nid = rig.node_id
    rig.operational()
    m = rig.frames.mark()
    # NMT with a wrong length (a "stop" command with DLC 1 and with DLC 3): ignored
    _send(rig, 0x000, bytes([0x02]))
    _send(rig, 0x000, bytes([0x02, nid, 0x00]))
    # SDO request with DLC 4, a remote frame on the SDO id, a 29-bit frame with the SDO id: no response
    _send(rig, 0x600 + nid, bytes([0x40, 0x00, 0x10, 0x00]))
    _send(rig, 0x600 + nid, rtr=True, dlc=8)
    _send(rig, 0x600 + nid, bytes([0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0]), ext=True)
    # the node serves frames in order: once it has answered a good request sent after them, it has seen them all
    assert rig.read(0x1000) == 0x00020192
    rig.frames.mark()  # drains the capture socket: the answer the master just took is in the capture too
    answers = rig.frames.select(lambda f: f.id == 0x580 + nid, m)
    assert len(answers) == 1, "the node answered a malformed SDO frame: %s" % answers
    assert rig.wait_heartbeat(0x05, 0.5) is not None, "a malformed NMT frame changed the state"

    # RPDO1 (controlword, 2 bytes) with 1 byte: not processed, EMCY 0x8210; with 3 bytes: processed, 0x8220
    m = rig.frames.mark()
    _send(rig, 0x200 + nid, bytes([0x06]))
    e = rig.frames.wait_emcy(nid, 0x8210, 1.0, m)
    assert e is not None and e.info == 0, "no EMCY 0x8210 for a short RPDO"
    assert rig.state_of(0) == "SWITCH ON DISABLED"
    _send(rig, 0x200 + nid, struct.pack("<H", 0x0000))  # a good frame re-arms the length EMCY of RPDO1
    _send(rig, 0x200 + nid, struct.pack("<HB", 0x0006, 0xAA))
    assert rig.frames.wait_emcy(nid, 0x8220, 1.0, m) is not None, "no EMCY 0x8220 for a long RPDO"
    assert rig.state_of(0) == "READY TO SWITCH ON", "the long RPDO's controlword was not applied"
    # SYNC with a data byte: EMCY 0x8240
    _send(rig, 0x080, bytes([1]))
    assert rig.frames.wait_emcy(nid, 0x8240, 1.0, m) is not None, "no EMCY 0x8240 for a SYNC with data"

    # still fully working: SDO, heartbeat, state
    assert rig.read(0x1000) == 0x00020192
    assert rig.wait_heartbeat(0x05, 0.5) is not None
    history = rig.read(0x1003, sub=0)
    assert history >= 3
