"""A lossy bridge between two CAN interfaces (fault injection for the HIL rig, docs/reliability.md).

The master stays on one interface (vcan0), the node runs on another (vcan1); the bridge forwards every frame both
ways through two raw SocketCAN sockets, and a policy decides, frame by frame, to pass it, drop it, send it twice,
or hold it back until the next frame in the same direction has gone (a reordering; a held frame is released after
`hold_s` at the latest, so that a request/response protocol cannot dead-lock on it):

    br = LossyBridge("vcan0", "vcan1", policy).start()     # policy(direction, k, can_id) -> PASS|DROP|DUP|HOLD
    ...
    br.stop(); br.log                                       # [(t, direction, k, can_id, action), ...]

direction is "m2n" (vcan0 -> vcan1) or "n2m"; k counts the frames of that direction the policy was asked about.
"""
import select
import socket
import struct
import threading
import time

PASS, DROP, DUP, HOLD = "pass", "drop", "dup", "hold"
_FRAME = struct.Struct("=IB3x8s")
CAN_ERR_FLAG = 0x20000000


def _open(iface):
    s = socket.socket(socket.PF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
    s.bind((iface,))
    s.setblocking(False)
    return s


class LossyBridge:
    def __init__(self, master_iface, node_iface, policy, hold_s=0.1):
        self.ifaces = (master_iface, node_iface)
        self.policy = policy
        self.hold_s = hold_s
        self.log = []
        self.counts = {PASS: 0, DROP: 0, DUP: 0, HOLD: 0}
        self._run = False
        self._thread = None
        self._socks = None

    def start(self):
        self._socks = (_open(self.ifaces[0]), _open(self.ifaces[1]))
        self._run = True
        self._thread = threading.Thread(target=self._loop, daemon=True)
        self._thread.start()
        return self

    def stop(self):
        self._run = False
        if self._thread is not None:
            self._thread.join(timeout=2)
            self._thread = None
        if self._socks is not None:
            for s in self._socks:
                s.close()
            self._socks = None

    @staticmethod
    def _send(sock, data):
        for _ in range(200):  # the interface queue may be full for a moment: retry, never block the loop for long
            try:
                sock.send(data)
                return
            except (BlockingIOError, OSError):
                time.sleep(0.0005)

    def _loop(self):
        k = {"m2n": 0, "n2m": 0}
        held = {"m2n": None, "n2m": None}  # (data, t) held back per direction
        src = {self._socks[0].fileno(): ("m2n", self._socks[0], self._socks[1]),
               self._socks[1].fileno(): ("n2m", self._socks[1], self._socks[0])}
        while self._run:
            r, _, _ = select.select(list(src), [], [], 0.01)
            now = time.monotonic()
            for d, dst in (("m2n", self._socks[1]), ("n2m", self._socks[0])):  # release overdue held frames
                if held[d] is not None and now - held[d][1] > self.hold_s:
                    self._send(dst, held[d][0])
                    held[d] = None
            for fd in r:
                d, s_in, s_out = src[fd]
                while True:
                    try:
                        data = s_in.recv(16)
                    except (BlockingIOError, InterruptedError):
                        break
                    can_id = _FRAME.unpack(data)[0]
                    if can_id & CAN_ERR_FLAG:
                        continue  # error frames belong to one controller: not forwarded
                    act = self.policy(d, k[d], can_id & 0x1FFFFFFF)
                    if act == HOLD and held[d] is not None:
                        act = PASS  # one held frame at a time
                    self.log.append((time.time(), d, k[d], can_id & 0x1FFFFFFF, act))
                    self.counts[act] += 1
                    k[d] += 1
                    if act == DROP:
                        continue
                    if act == HOLD:
                        held[d] = (data, time.monotonic())
                        continue
                    self._send(s_out, data)
                    if act == DUP:
                        self._send(s_out, data)
                    if held[d] is not None:  # the held frame goes after this one: reordered
                        self._send(s_out, held[d][0])
                        held[d] = None
