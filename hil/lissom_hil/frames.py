"""Capture of every CAN frame on the bus (like candump), with kernel timestamps.

    log = FrameLog("vcan0"); log.start()
    f = log.wait(lambda f: f.id == 0x701, timeout=2)      # a Frame, or None
    log.emcy(node_id=1)                                   # decoded EMCY frames so far
    log.stop()

A plain SocketCAN raw socket read by one thread, with as little work per frame as possible (no python-can
Message objects): under emulation (the HIL VM) Python is about 20 times slower than on the host, and a busy
capture thread would starve the CANopen master. The socket also subscribes to error frames and has a large
receive queue. Frames the rig itself sends (SYNC, NMT, SDO requests) are captured too: on a SocketCAN bus
every socket sees the others' frames.
"""
import os
import select
import socket
import struct
import threading
import time
from collections import namedtuple

Frame = namedtuple("Frame", "t id data ext rtr err")
Emcy = namedtuple("Emcy", "t code register info extra")

CAN_EFF_FLAG = 0x80000000
CAN_RTR_FLAG = 0x40000000
CAN_ERR_FLAG = 0x20000000
CAN_EFF_MASK = 0x1FFFFFFF
CAN_ERR_BUSOFF = 0x00000040
CAN_ERR_RESTARTED = 0x00000100
CAN_ERR_CRTL = 0x00000004
CAN_ERR_CRTL_RX_PASSIVE = 0x10
CAN_ERR_CRTL_TX_PASSIVE = 0x20
CAN_ERR_CRTL_ACTIVE = 0x40
_SOL_CAN_RAW = 101
_CAN_RAW_ERR_FILTER = 2
_SO_TIMESTAMP = 29
_SO_RCVBUFFORCE = 33
_FRAME = struct.Struct("=IB3x8s")
_TIMEVAL = struct.Struct("=qq")


class FrameLog:
    def __init__(self, channel):
        self.channel = channel
        self.frames = []
        self.cond = threading.Condition()
        self.sock = None
        self._thread = None
        self._run = False
        self._wake_r = self._wake_w = None
        self._drains = 0  # times the reader has found the socket empty (see mark)

    def start(self):
        s = socket.socket(socket.PF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
        s.setsockopt(_SOL_CAN_RAW, _CAN_RAW_ERR_FILTER, struct.pack("=I", 0x1FFFFFFF))
        s.setsockopt(socket.SOL_SOCKET, _SO_TIMESTAMP, 1)
        for opt in (_SO_RCVBUFFORCE, socket.SO_RCVBUF):
            try:
                s.setsockopt(socket.SOL_SOCKET, opt, 8 << 20)
                break
            except OSError:
                continue
        s.bind((self.channel,))
        self.sock = s
        self._wake_r, self._wake_w = os.pipe()
        os.set_blocking(self._wake_r, False)
        self._run = True
        self._thread = threading.Thread(target=self._reader, name="framelog", daemon=True)
        self._thread.start()
        return self

    def stop(self):
        self._run = False
        if self._thread is not None:
            self._thread.join(timeout=2)
            self._thread = None
        if self.sock is not None:
            self.sock.close()
            self.sock = None
        for fd in (self._wake_r, self._wake_w):
            if fd is not None:
                os.close(fd)
        self._wake_r = self._wake_w = None

    def _reader(self):
        s = self.sock
        anc = socket.CMSG_SPACE(_TIMEVAL.size)
        while self._run:
            r, _, _ = select.select([s, self._wake_r], [], [], 0.1)
            if self._wake_r in r:  # mark() asks for a drain
                try:
                    os.read(self._wake_r, 4096)
                except BlockingIOError:
                    pass
            batch = []
            while True:
                try:
                    data, ancdata, _, _ = s.recvmsg(16, anc, socket.MSG_DONTWAIT)
                except (BlockingIOError, InterruptedError):
                    break
                except OSError:
                    return
                t = time.time()
                for lvl, typ, val in ancdata:
                    if lvl == socket.SOL_SOCKET and typ == _SO_TIMESTAMP:
                        sec, usec = _TIMEVAL.unpack(val[: _TIMEVAL.size])
                        t = sec + usec * 1e-6
                ident, dlc, payload = _FRAME.unpack(data)
                err = bool(ident & CAN_ERR_FLAG)
                ext = bool(ident & CAN_EFF_FLAG)
                rtr = bool(ident & CAN_RTR_FLAG)
                batch.append(Frame(t, ident & (CAN_EFF_MASK if ext or err else 0x7FF), b"" if rtr else payload[:dlc],
                                   ext, rtr, err))
            with self.cond:  # the socket is empty: everything queued on it before this drain is captured
                self.frames.extend(batch)
                self._drains += 1
                self.cond.notify_all()

    def mark(self):
        """Index to pass as `since` to only look at frames captured from now on. A frame already on the bus counts
        as before the mark even if the capture thread has not read it yet (say the response to an SDO request the
        master has just received on its own socket): the capture socket is drained first."""
        with self.cond:
            if self._thread is None:
                return len(self.frames)
            n = self._drains
            os.write(self._wake_w, b"\0")
            # a drain that ended before this call may still be counting itself: wait for the one after it, which
            # began after the wake-up
            self.cond.wait_for(lambda: self._drains >= n + 2 or not self._run, timeout=2.0)
            return len(self.frames)

    def select(self, pred=None, since=0):
        with self.cond:
            fr = self.frames[since:]
        return [f for f in fr if pred is None or pred(f)]

    def wait(self, pred, timeout=2.0, since=0):
        """First frame (captured at index >= since) matching pred, waiting up to timeout seconds; None if none."""
        t_end = time.monotonic() + timeout
        i = since
        with self.cond:
            while True:
                while i < len(self.frames):
                    if pred(self.frames[i]):
                        return self.frames[i]
                    i += 1
                left = t_end - time.monotonic()
                if left <= 0:
                    return None
                self.cond.wait(left)

    def wait_count(self, pred, n, timeout=5.0, since=0):
        """The first n frames (captured at index >= since) matching pred, waiting up to timeout seconds for the n-th
        (an event, not a fixed delay: under load the wait only gets longer); None if fewer arrived."""
        got = []
        t_end = time.monotonic() + timeout
        i = since
        with self.cond:
            while True:
                while i < len(self.frames):
                    if pred(self.frames[i]):
                        got.append(self.frames[i])
                        if len(got) >= n:
                            return got
                    i += 1
                left = t_end - time.monotonic()
                if left <= 0:
                    return None
                self.cond.wait(left)

    def emcy(self, node_id, since=0):
        out = []
        for f in self.select(lambda f: f.id == 0x80 + node_id and not f.err and not f.ext, since):
            if len(f.data) == 8:
                code, reg, info, extra = struct.unpack("<HBBI", f.data)
                out.append(Emcy(f.t, code, reg, info, extra))
        return out

    def wait_emcy(self, node_id, code, timeout=2.0, since=0):
        f = self.wait(lambda f: f.id == 0x80 + node_id and len(f.data) == 8 and not f.err and not f.ext
                      and struct.unpack_from("<H", f.data)[0] == code, timeout, since)
        if f is None:
            return None
        c, reg, info, extra = struct.unpack("<HBBI", f.data)
        return Emcy(f.t, c, reg, info, extra)

    def dump(self, path, since=0):
        """Write the captured frames in candump's log format (candump -L), for the test artefacts."""
        with open(path, "w") as out:
            for f in self.select(None, since):
                if f.err:
                    ident = "%08X" % (f.id | CAN_ERR_FLAG)
                elif f.ext:
                    ident = "%08X" % f.id
                else:
                    ident = "%03X" % f.id
                body = "R" if f.rtr else f.data.hex().upper()
                out.write("(%.6f) %s %s#%s\n" % (f.t, self.channel, ident, body))
