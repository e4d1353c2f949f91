"""The Cortex-M4F controller image as a device under test: QEMU started by scripts/mcu_node.sh, its CAN bus on a TCP
port as an slcan adapter (docs/cortex_m.md, "Controller image"), and a frame log fed by the master's own bus.

    img = McuImage(node_id=1, log_path="out/hil-mcu/qemu.log").start()     # waits for "lissom-controller: ready"
    net = canopen.Network(); log = BusFrameLog(net, "slcan")              # before connect: sees every frame first
    net.connect(interface="slcan", channel=img.channel, bitrate=1000000, sleep_after_open=0)
    log.start()                                                           # also logs what the master sends
    ...
    img.stop()

BusFrameLog has the interface of frames.FrameLog (mark, select, wait, emcy, wait_emcy, dump) for a bus that only
one client can open (the image's TCP port takes one connection): it is a listener placed before the CANopen
master's on the same python-can bus, so a frame is logged before the master reacts to it, and it wraps the bus's
send() (periodic sends included: python-can's software cyclic tasks call it) to log the master's own frames. Time
stamps are the host's time.time() at reception (python-can's slcan interface) or at sending. Error frames and
frames of other nodes' traffic never reach it: a serial adapter shows only the bus, and this bus has two nodes.
"""
import os
import socket
import subprocess
import threading
import time

import can

from .frames import Emcy, Frame, FrameLog

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MCU_NODE = os.path.join(ROOT, "scripts", "mcu_node.sh")
READY = "lissom-controller: ready"


def free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class McuImage:
    """scripts/mcu_node.sh in the background; its stderr (the image's semihosting output, QEMU's warnings) goes to
    log_path."""

    def __init__(self, node_id=1, axes=3, port=None, log_path=None, elf=None):
        self.node_id, self.axes = node_id, axes
        self.port = port or free_port()
        self.log_path = log_path
        self.elf = elf
        self.proc = None
        self._log = None
        self.ready_line = ""

    @property
    def channel(self):
        return "socket://127.0.0.1:%d" % self.port

    def start(self, timeout=60.0):
        args = [MCU_NODE, "--tcp", str(self.port), "--node-id", str(self.node_id), "--axes", str(self.axes)]
        if self.elf:
            args += ["--elf", self.elf]
        if self.log_path:
            os.makedirs(os.path.dirname(self.log_path), exist_ok=True)
        self._log = open(self.log_path or os.devnull, "w")
        self.proc = subprocess.Popen(args, stdout=self._log, stderr=subprocess.STDOUT, cwd=ROOT)
        t_end = time.monotonic() + timeout
        while True:
            if self.proc.poll() is not None:
                raise RuntimeError("mcu_node.sh exited with %s (see %s)" % (self.proc.returncode, self.log_path))
            if self.log_path:
                ready = [ln for ln in open(self.log_path).read().splitlines() if ln.startswith(READY)]
                if ready:
                    self.ready_line = ready[0]
                    break
            if time.monotonic() > t_end:
                self.stop()
                raise RuntimeError("no '%s' line within %.0f s (see %s)" % (READY, timeout, self.log_path))
            time.sleep(0.05)
        while True:  # QEMU listens once the image runs; connecting is left to the master
            try:
                with socket.create_connection(("127.0.0.1", self.port), timeout=0.2):
                    pass
                break
            except OSError:
                if time.monotonic() > t_end:
                    raise
                time.sleep(0.05)
        return self

    def stop(self):
        rc = None
        if self.proc is not None:
            if self.proc.poll() is None:
                self.proc.terminate()
                try:
                    self.proc.wait(5)
                except subprocess.TimeoutExpired:
                    self.proc.kill()
                    self.proc.wait()
            rc = self.proc.returncode
            self.proc = None
        if self._log is not None:
            self._log.close()
            self._log = None
        return rc


class BusFrameLog(can.Listener, FrameLog):
    def __init__(self, network, channel="slcan"):
        FrameLog.__init__(self, channel)
        self.network = network
        self._send_lock = threading.Lock()
        network.listeners.insert(0, self)  # before the master's own listener: logged before it reacts

    # ---- capture --------------------------------------------------------------------------------------
    def start(self):
        """After network.connect(): wraps the bus's send."""
        bus = self.network.bus
        orig = bus.send

        def send(msg, timeout=None):
            with self._send_lock:  # one line at a time on the serial link (SYNC, heartbeat, SDO threads)
                orig(msg, timeout)
            self._add(msg, time.time())

        bus.send = send
        self._thread = True  # (FrameLog.mark: the log is live)
        return self

    def stop(self):
        self._thread = None

    def on_message_received(self, msg):
        self._add(msg, msg.timestamp or time.time())

    def _add(self, msg, t):
        if msg.is_error_frame:
            f = Frame(t, msg.arbitration_id, bytes(msg.data), False, False, True)
        else:
            f = Frame(t, msg.arbitration_id, b"" if msg.is_remote_frame else bytes(msg.data),
                      msg.is_extended_id, msg.is_remote_frame, False)
        with self.cond:
            self.frames.append(f)
            self.cond.notify_all()

    def mark(self):
        """Index of the next frame: the listener runs before the master's, so every frame the master has seen
        is already logged."""
        with self.cond:
            return len(self.frames)


__all__ = ["McuImage", "BusFrameLog", "Emcy", "free_port"]
