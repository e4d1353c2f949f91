"""Interoperability: python-canopen (a CANopen master no one here wrote) against the firmware's CANopen layer.

No CAN hardware and no vcan: the firmware runs in tests/py/co_node_pipe.c (compiled on the fly with the
firmware sources and a toy motion application), and frames travel over its stdin/stdout through a small
python-can bus class. These tests check what the unit tests cannot: that canopen's own SDO client, PDO
configuration code, BaseNode402, NMT/heartbeat and EMCY consumers work with this node and with
hil/lissom.eds, as they will on vcan0 and on a real bus.
"""
import os
import queue
import struct
import subprocess
import sys
import threading
import time

import can
import canopen
import pytest
from canopen.profiles.p402 import BaseNode402

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EDS = os.path.join(REPO, "hil", "lissom.eds")
sys.path.insert(0, os.path.join(REPO, "scripts"))
import gen_eds  # noqa: E402

NODE_ID = 5
AXES = 3


class PipeBus(can.BusABC):
    """A python-can bus whose other end is a co_node_pipe process."""

    def __init__(self, exe, node_id, n_axes, **kwargs):
        self.proc = subprocess.Popen([exe, str(node_id), str(n_axes)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True, bufsize=1)
        self.rx = queue.Queue()
        self.lock = threading.Lock()
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()
        self.channel_info = "co_node_pipe"
        super().__init__(channel="pipe", **kwargs)

    def _read(self):
        for line in self.proc.stdout:
            parts = line.split()
            if len(parts) >= 3 and parts[0] == "F":
                dlc = int(parts[2])
                data = bytes.fromhex(parts[3]) if dlc else b""
                self.rx.put(can.Message(arbitration_id=int(parts[1], 16), data=data, is_extended_id=False,
                                        timestamp=time.time()))

    def _recv_internal(self, timeout):
        try:
            return self.rx.get(timeout=timeout), False
        except queue.Empty:
            return None, False

    def command(self, text):
        with self.lock:
            self.proc.stdin.write(text + "\n")
            self.proc.stdin.flush()

    def send(self, msg, timeout=None):
        self.command(f"F {msg.arbitration_id:03X} {msg.dlc} {bytes(msg.data).hex()}")

    def shutdown(self):
        try:
            self.command("Q")
        except (BrokenPipeError, ValueError):
            pass
        self.proc.wait(timeout=5)
        super().shutdown()


@pytest.fixture(scope="module")
def pipe_exe(tmp_path_factory):
    d = str(tmp_path_factory.mktemp("co_node_pipe"))
    exe = os.path.join(d, "co_node_pipe")
    fw = os.path.join(REPO, "firmware")
    cc = os.environ.get("CC", "cc")
    incs = [a for d in gen_eds.FIRMWARE_INCLUDES for a in ("-I", os.path.join(fw, d))]
    subprocess.run([cc, "-std=c11", "-O1", "-Wall", "-Wextra", "-Werror"] + incs +
                   [os.path.join(REPO, "tests", "py", "co_node_pipe.c")]
                   + [os.path.join(fw, s) for s in gen_eds.FIRMWARE_SOURCES] + ["-o", exe], check=True)
    return exe


@pytest.fixture
def net(pipe_exe):
    bus = PipeBus(pipe_exe, NODE_ID, AXES)
    network = canopen.Network(bus)
    network.connect()
    yield network
    network.disconnect()


def add_node(net, cls=canopen.RemoteNode):
    node = cls(NODE_ID, EDS)
    net.add_node(node)
    return node


def test_boot_and_heartbeat(net):
    node = add_node(net)
    seen = queue.Queue()
    net.subscribe(0x700 + NODE_ID, lambda can_id, data, ts: seen.put(bytes(data)))
    # (canopen's wait_for_bootup can miss a boot-up that comes back within a millisecond: listen first)
    node.nmt.send_command(0x82)  # reset communication
    assert seen.get(timeout=10) == b"\x00"
    node.nmt.send_command(0x81)  # reset node
    assert seen.get(timeout=10) == b"\x00"
    node.sdo["Producer heartbeat time"].raw = 20
    assert node.nmt.wait_for_heartbeat(10) == "PRE-OPERATIONAL"
    node.nmt.state = "OPERATIONAL"
    time.sleep(0.1)
    assert node.nmt.wait_for_heartbeat(10) == "OPERATIONAL"
    node.nmt.state = "STOPPED"
    time.sleep(0.1)
    assert node.nmt.wait_for_heartbeat(10) == "STOPPED"


def test_sdo(net):
    node = add_node(net)
    assert node.sdo[0x1000].raw == 0x00020192
    assert node.sdo["Manufacturer device name"].raw == "Lissom motion controller"  # segmented upload
    assert node.sdo[0x1018][2].raw == 0x4C534D31
    node.sdo["Profile jerk"].raw = 123456789012  # UNSIGNED64: segmented download
    assert node.sdo["Profile jerk"].raw == 123456789012
    node.sdo[0x687A].raw = -5000  # axis 1 target
    assert node.sdo["Axis 1 target position"].raw == -5000
    with pytest.raises(canopen.SdoAbortedError) as e:
        node.sdo.upload(0x1234, 0)
    assert e.value.code == 0x06020000
    with pytest.raises(canopen.SdoAbortedError) as e:
        node.sdo["Modes of operation"].raw = 5
    assert e.value.code == 0x06090030
    with pytest.raises(canopen.SdoAbortedError) as e:
        node.sdo.download(0x6081, 0, struct.pack("<I", 0))
    assert e.value.code == 0x06090032
    with pytest.raises(canopen.SdoAbortedError) as e:
        node.sdo.download(0x1000, 0, struct.pack("<I", 1))
    assert e.value.code == 0x06010002


def sync_and_receive(net, pdo, timeout=10.0):
    """Sends a SYNC and waits for a new reception of pdo (PdoMap.wait_for_reception misses a quick one)."""
    before = pdo.timestamp
    net.sync.transmit()
    deadline = time.time() + timeout
    while time.time() < deadline:
        if pdo.timestamp is not None and pdo.timestamp != before:
            return True
        time.sleep(0.002)
    return False


def test_pdo_configuration_and_sync(net):
    node = add_node(net)
    node.tpdo.read()
    node.rpdo.read()
    assert [v.index for v in node.tpdo[1].map] == [0x6041, 0x6061]
    assert [v.index for v in node.rpdo[1].map] == [0x6040]
    # canopen's own mapping procedure: statusword of axes 0..2 on TPDO3, at every SYNC
    tp = node.tpdo[3]
    tp.clear()
    tp.add_variable(0x6041)
    tp.add_variable(0x6841)
    tp.add_variable(0x7041)
    tp.trans_type = 1
    tp.enabled = True
    tp.save()
    node.tpdo.read()
    assert [v.index for v in node.tpdo[3].map] == [0x6041, 0x6841, 0x7041]
    node.nmt.state = "OPERATIONAL"
    time.sleep(0.05)
    for _ in range(3):
        assert sync_and_receive(net, node.tpdo[3]) and sync_and_receive(net, node.tpdo[2])
    assert node.tpdo[3]["Statusword"].raw & 0x4F == 0x40
    assert node.tpdo[2]["Path buffer free slots"].raw == 16
    before = node.tpdo[1].timestamp
    time.sleep(0.2)  # TPDO1: event timer 50 ms
    assert node.tpdo[1].timestamp is not None and node.tpdo[1].timestamp != before


def test_basenode402_pp_moves(net):
    node = add_node(net, BaseNode402)
    node.nmt.state = "PRE-OPERATIONAL"
    node.setup_402_state_machine()
    node.nmt.state = "OPERATIONAL"
    time.sleep(0.05)
    node.state = "SWITCH ON DISABLED"
    node.state = "OPERATION ENABLED"
    assert node.state == "OPERATION ENABLED"
    assert node.op_mode == "PROFILED POSITION"
    for profile in (0, 1):  # linear and sin^2 ramps
        node.sdo["Motion profile type"].raw = profile
        target = 3000 if profile == 0 else -1500
        node.sdo["Profile velocity"].raw = 200000
        node.sdo["Target position"].raw = target
        node.controlword = 0x3F  # new set-point, change immediately
        deadline = time.time() + 2
        while not node.sdo["Statusword"].raw & 0x1000:  # set-point acknowledge
            assert time.time() < deadline
        node.controlword = 0x2F
        while not node.sdo["Statusword"].raw & 0x0400:  # target reached
            assert time.time() < deadline
        assert node.sdo["Position actual value"].raw == target
    node.state = "SWITCH ON DISABLED"
    assert node.state == "SWITCH ON DISABLED"


def path_block(seq, end, feed=100000, tol=5):
    return struct.pack("<IBBBBII", seq, 1, 0, len(end), 0, feed, tol) + struct.pack(f"<{len(end)}i", *end)


def test_path_streaming(net):
    node = add_node(net)
    node.nmt.state = "OPERATIONAL"
    for k in range(AXES):
        node.sdo[0x6060 + 0x800 * k].raw = -1
        for cw in (0x06, 0x07, 0x0F):
            node.sdo[0x6040 + 0x800 * k].raw = cw
    node.sdo["Path command"].raw = 1  # start
    n_blocks = 40
    seq = 1
    while seq <= n_blocks:  # flow control on the free slots
        if node.sdo["Path buffer free slots"].raw == 0:
            time.sleep(0.005)
            continue
        node.sdo.download(0x5010, 0, path_block(seq, [seq * 100, -seq * 50, seq]))
        seq += 1
    node.sdo.download(0x5010, 0, path_block(n_blocks, [n_blocks * 100, -n_blocks * 50, n_blocks]))  # duplicate
    with pytest.raises(canopen.SdoAbortedError) as e:
        node.sdo.download(0x5010, 0, path_block(n_blocks + 2, [1, 2, 3]))  # gap
    assert e.value.code == 0x06090031
    deadline = time.time() + 5
    while node.sdo["Path active sequence"].raw != n_blocks or node.sdo["Path buffer free slots"].raw != 16:
        assert time.time() < deadline
        time.sleep(0.01)
    assert node.sdo["Path last accepted sequence"].raw == n_blocks
    assert node.sdo["Path counters"]["Duplicate blocks"].raw == 1
    assert node.sdo["Path counters"]["Sequence gaps"].raw == 1
    deadline = time.time() + 2
    while node.sdo["Position actual value"].raw != n_blocks * 100:
        assert time.time() < deadline


def wait_emcy(node, code, timeout=10.0):
    """The EMCY with this code in canopen's log (EmcyConsumer.wait misses one that came before the call)."""
    deadline = time.time() + timeout
    while time.time() < deadline:
        for err in node.emcy.log:
            if err.code == code:
                return err
        time.sleep(0.01)
    return None


def test_estop_emcy(net):
    node = add_node(net)
    node.nmt.state = "OPERATIONAL"
    time.sleep(0.05)
    net.bus.command("E 1")
    err = wait_emcy(node, 0x9000)
    assert err is not None and err.register & 0x01
    assert node.sdo["Statusword"].raw & 0x4F == 0x08  # FAULT
    assert node.sdo["Error code"].raw == 0x9000
    net.bus.command("E 0")
    assert wait_emcy(node, 0x0000) is not None
    assert node.emcy.active == []
    node.sdo["Controlword"].raw = 0x00
    node.sdo["Controlword"].raw = 0x80
    assert node.sdo["Statusword"].raw & 0x4F == 0x40


def test_bus_off_recovery(net):
    node = add_node(net)
    node.nmt.state = "OPERATIONAL"
    time.sleep(0.05)
    net.bus.command("B 2")  # bus-off
    time.sleep(0.05)
    net.bus.command("B 0")  # recovered
    assert wait_emcy(node, 0x8140) is not None
    assert node.sdo[0x5020].raw & 0x04 == 0
