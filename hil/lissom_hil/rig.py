"""The HIL rig: a Lissom node on a CAN bus, driven by the PyPI `canopen` master (BaseNode402 + hil/lissom.eds).

Three kinds of rig (pytest --rig, see hil/tests/conftest.py):
  vcan   the rig starts build/bin/lissom-node on vcan0 for every test (fresh state, per-cycle trace available);
  can0   a real CAN interface; by default the node is an external board (the rig resets it with NMT and uses
         only what CANopen shows); --rig-local also starts lissom-node on that interface.
  mcu    the Cortex-M4F controller image under QEMU (scripts/mcu_node.sh, lissom_hil.mcu), reached through
         python-can's slcan interface on its TCP port; one image for the session, treated as an external board
         (NMT reset per test, CANopen only). Its clock runs slower than real time by construction (docs/cortex_m.md):
         checks of the node's periods convert with clock_start() / clock_scale() over the window they observe.

    rig = Rig(RigConfig(kind="vcan")); rig.open(); rig.start()
    rig.operational(); rig.enable(0, mode="PROFILED POSITION")
    rig.set_profile(0, v=50, a=500, j=1e4, snap=1e6, profile_type=1)    # mm units, converted with 0x2001
    rig.pp_move(0, 20.0)                                                 # handshake, waits for target reached
    tr = rig.trace()                                                     # lissom_hil.trace.Trace (vcan only)
    rig.stop(); rig.close()

Command line:  python -m lissom_hil.rig plot DIR   makes PNGs (lissom_hil.plot) of every run CSV under DIR.
"""
import json
import os
import shutil
import socket
import sys
import tempfile
import time
from dataclasses import dataclass, field
from typing import Optional

import canopen
from canopen.profiles.p402 import BaseNode402

from . import node_proc
from .frames import FrameLog
from .trace import Trace

ROOT = node_proc.ROOT
EDS = os.path.join(ROOT, "hil", "lissom.eds")
AXIS_STEP = 0x800

# statusword bits (CiA 402)
SW_TARGET_REACHED = 0x0400
SW_ACK = 0x1000
SW_FAULT = 0x0008
SW_STATE_MASK = 0x6F
SW_OPERATION_ENABLED = 0x27

# SDO response timeout of the master: generous, because under emulation the Python threads that read the
# bus can be late (the node answers within a cycle). Measured: in slow runs of the suite (the guest 2x slower
# than usual) a read of 0x6041 was answered on the bus 1 ms after its request (candump log) and still not
# delivered to python-canopen's SDO client 2 s later; 2 s was too short there.
SDO_TIMEOUT_S = 5.0
# Bounds of python-canopen's CiA 402 waits (a state change, a mode change, a fresh statusword TPDO). Its defaults
# (0.2-0.8 s) are shorter than the node's ticks run late on a loaded machine (220 ms seen in a QEMU guest beside
# stress-ng), and a load run failed "Timeout waiting for updated statusword". Each wait ends on the event: the bound
# only says when to give up.
P402_WAIT_S = 10.0

# the node's built-in machine (host_sim/node/node_app.c): used when no machine file is given
BUILTIN_LIMITS = {"v": 250.0, "a": 3000.0, "j": 60000.0, "snap": 1.18e7}


@dataclass
class RigConfig:
    kind: str = "vcan"                 # vcan | can0 | mcu
    iface: Optional[str] = None        # default vcan0 / can0
    node_iface: Optional[str] = None   # local node's interface when it differs (behind lissom_hil.bridge)
    node_id: int = 1
    local: Optional[bool] = None       # start lissom-node (default: True on vcan, False on can0)
    machine: Optional[str] = None      # machine file for the local node (limits for the checks)
    axes: int = 3
    out_dir: str = os.path.join(ROOT, "out", "hil")
    node_args: list = field(default_factory=list)
    rt_prio: int = 50                  # local node: SCHED_FIFO priority (0 = normal scheduling)

    def resolved(self):
        c = RigConfig(**self.__dict__)
        if c.iface is None:
            c.iface = {"vcan": "vcan0", "mcu": "slcan"}.get(c.kind, c.kind)
        if c.kind == "mcu":
            c.local = False
        if c.local is None:
            c.local = c.kind == "vcan"
        return c


class Rig:
    def __init__(self, cfg: RigConfig):
        self.cfg = cfg.resolved()
        self.network = None
        self.frames = None
        self.node = None
        self.proc = None
        self.trace_path = None
        self.home = [0] * 6
        self.test_dir = self.cfg.out_dir
        self._hb = None
        self._sync_period = None
        self._pdo_ready = False
        self._tmp = tempfile.mkdtemp(prefix="lissom-hil-")
        self.mcu = None          # lissom_hil.mcu.McuImage (kind mcu)
        self.time_scale = 1.0    # real seconds per node second, roughly (mcu: measured at open; for waits only)
        self.tick_stats = None   # the image's 0x5F00 at close (kind mcu)
        self.axis_names = "XYZUVW"
        self.limits = [dict(BUILTIN_LIMITS, cpm=1000.0) for _ in range(6)]
        if self.cfg.machine:
            with open(self.cfg.machine) as f:
                m = json.load(f)
            self.axis_names = "".join(a["name"] for a in m["axes"])
            for k, a in enumerate(m["axes"]):
                self.limits[k] = {"v": a["v_max_mm_s"], "a": a["a_max_mm_s2"], "j": a["j_max_mm_s3"],
                                  "snap": a["snap_max_mm_s4"], "cpm": 1000.0}

    # ---- session -------------------------------------------------------------------------------------
    @property
    def kind(self):
        return self.cfg.kind

    def open(self):
        if self.cfg.kind == "mcu":
            return self._open_mcu()
        self.frames = FrameLog(self.cfg.iface).start()
        self.network = canopen.Network()
        # the master only listens to what it uses (SDO responses, heartbeat, EMCY, TPDO1 with the statusword):
        # under emulation every frame costs Python milliseconds; telemetry is decoded from the capture instead
        nid = self.cfg.node_id
        flt = [{"can_id": base + nid, "can_mask": 0x7FF, "extended": False} for base in (0x580, 0x700, 0x080, 0x180)]
        self.network.connect(interface="socketcan", channel=self.cfg.iface, can_filters=flt)
        sock = getattr(self.network.bus, "socket", None)
        if sock is not None:  # the master's receive queue: large, for the same reason as the capture's
            try:
                sock.setsockopt(socket.SOL_SOCKET, getattr(socket, "SO_RCVBUFFORCE", 33), 8 << 20)
            except OSError:
                pass
        return self

    def _open_mcu(self):
        from .mcu import BusFrameLog, McuImage
        self.mcu = McuImage(self.cfg.node_id, self.cfg.axes, log_path=os.path.join(self.cfg.out_dir, "qemu.log"))
        self.mcu.start()
        self.network = canopen.Network()
        self.frames = BusFrameLog(self.network)
        self.network.connect(interface="slcan", channel=self.mcu.channel, bitrate=1000000, sleep_after_open=0)
        self.frames.start()
        self.time_scale = self._measure_time_scale()
        return self

    def _tick_stats(self, node):
        return [node.sdo[0x5F00][i].raw for i in range(1, 11)]

    def _measure_time_scale(self, span_s=1.0):
        """Real seconds per node second, from the image's clock (0x5F00 sub 6, ms) over span_s of real time."""
        node = canopen.RemoteNode(self.cfg.node_id, EDS)
        node.sdo.RESPONSE_TIMEOUT = SDO_TIMEOUT_S
        self.network.add_node(node)
        try:
            t0, n0 = time.monotonic(), node.sdo[0x5F00][6].raw
            time.sleep(span_s)
            t1, n1 = time.monotonic(), node.sdo[0x5F00][6].raw
        finally:
            del self.network[self.cfg.node_id]
        return (t1 - t0) / ((n1 - n0) * 1e-3)

    def close(self):
        if self.mcu is not None and self.network is not None:
            self._save_tick_stats()
        if self.node is not None or self.proc is not None:
            self.stop()
        if self.network is not None:
            self.network.disconnect()
            self.network = None
        if self.frames is not None:
            self.frames.stop()
            self.frames = None
        if self.mcu is not None:
            self.mcu.stop()
            self.mcu = None
        shutil.rmtree(self._tmp, ignore_errors=True)

    def _save_tick_stats(self):
        """The image's tick statistics (0x5F00) at the end of the session, to <out_dir>/tick_stats.json."""
        node = canopen.RemoteNode(self.cfg.node_id, EDS)
        node.sdo.RESPONSE_TIMEOUT = SDO_TIMEOUT_S
        if self.cfg.node_id in self.network:
            del self.network[self.cfg.node_id]
        self.network.add_node(node)
        try:
            st = self._tick_stats(node)
        except Exception as e:  # the figures must not hide the test results
            print("tick statistics: %s" % e, file=sys.stderr)
            return
        self.tick_stats = {"ticks": st[0], "overruns": st[1], "worst_tick_instructions": st[2],
                           "background_load_permille": st[3], "late_wakes": st[4], "clock_ms": st[5],
                           "path_underruns": st[6], "path_min_ahead": st[7], "sdo_waiting_max": st[8],
                           "sdo_refused": st[9], "tick_budget_instructions": 168000,
                           "time_scale": self.time_scale}
        os.makedirs(self.cfg.out_dir, exist_ok=True)
        with open(os.path.join(self.cfg.out_dir, "tick_stats.json"), "w") as f:
            json.dump(self.tick_stats, f, indent=1)

    def set_test_dir(self, name):
        self.test_dir = os.path.join(self.cfg.out_dir, name)
        os.makedirs(self.test_dir, exist_ok=True)
        return self.test_dir

    def out(self, name):
        os.makedirs(self.test_dir, exist_ok=True)
        return os.path.join(self.test_dir, name)

    @property
    def node_id(self):
        return self.cfg.node_id

    @property
    def local(self):
        return self.cfg.local

    # ---- device lifecycle ----------------------------------------------------------------------------
    def start(self, extra=(), trace=True, timeout=10.0):
        """Starts the device under test and waits for its boot-up frame: a fresh lissom-node (local), or an NMT
        reset of the board. Returns the boot-up frame."""
        mark = self.frames.mark()
        if self.cfg.local:
            # the trace goes to a local temporary file (the artefact directory may be a slow 9p share in
            # the VM); stop() copies it next to the other artefacts
            self.trace_path = os.path.join(self._tmp, "trace-%d.bin" % os.getpid()) if trace else None
            args = list(self.cfg.node_args) + list(extra)
            if self.cfg.rt_prio > 0 and "--rt" not in args:
                args += ["--rt", str(self.cfg.rt_prio)]
            if self.cfg.machine:
                args += ["--machine", self.cfg.machine]
            if "--axes" not in args and not self.cfg.machine:
                args += ["--axes", str(self.cfg.axes)]
            self.proc = node_proc.NodeProcess(node_proc.find_node_binary(), self.cfg.node_iface or self.cfg.iface,
                                              self.cfg.node_id,
                                              trace=self.trace_path, extra=args, log_path=self.out("node.log"))
            self.proc.start()
        else:
            self.network.send_message(0x000, [0x81, self.cfg.node_id])
        boot = self.frames.wait(lambda f: f.id == 0x700 + self.cfg.node_id and f.data == b"\x00", timeout, mark)
        if boot is None:
            raise RuntimeError("no boot-up frame from node %d on %s" % (self.cfg.node_id, self.cfg.iface))
        self.node = BaseNode402(self.cfg.node_id, EDS)
        self.node.sdo.RESPONSE_TIMEOUT = SDO_TIMEOUT_S
        for name in ("TIMEOUT_SWITCH_OP_MODE", "TIMEOUT_SWITCH_STATE_FINAL", "TIMEOUT_SWITCH_STATE_SINGLE",
                     "TIMEOUT_CHECK_TPDO"):
            setattr(self.node, name, P402_WAIT_S)
        self.network.add_node(self.node)
        self._pdo_ready = False
        # positions are relative to where the axes are now (a board keeps its positions across NMT resets)
        self.home = [self.read(0x6062, axis=k) for k in range(self.cfg.axes)]
        return boot

    def stop(self):
        """Stops SYNC / heartbeat production, detaches the node and stops the local daemon. Returns its exit
        code (None for an external board)."""
        self.stop_sync()
        self.stop_heartbeat()
        if self.node is not None:
            try:
                del self.network[self.cfg.node_id]
            except KeyError:
                pass
            self.node = None
        rc = None
        if self.proc is not None:
            rc = self.proc.stop()
            self.proc = None
            if self.trace_path and os.path.exists(self.trace_path):
                shutil.copyfile(self.trace_path, self.out("trace.bin"))
        return rc

    def restart(self, extra=(), trace=True):
        self.stop()
        return self.start(extra, trace)

    def require_local(self, pytest_mod, why="needs the local lissom-node (trace, simulated inputs)"):
        if not self.cfg.local:
            pytest_mod.skip(why)

    @property
    def has_motion(self):
        """False only for a controller image built with the interim hold layer (its ready line says motion=hold)."""
        if self.mcu is None:
            return True
        return "motion=hold" not in self.mcu.ready_line

    def read_tick_stats(self):
        """The M4 image's tick statistics (0x5F00) as a dict; None on other nodes."""
        if self.cfg.kind != "mcu":
            return None
        st = [self.read(0x5F00, i) for i in range(1, 11)]
        return dict(zip(("ticks", "overruns", "worst_tick_instructions", "background_load_permille", "late_wakes",
                         "clock_ms", "path_underruns", "path_min_ahead", "sdo_waiting_max", "sdo_refused"), st))

    def node_heartbeat_period(self, state=None, intervals=12, timeout=30.0):
        """The M4 image's heartbeat period in its own clock (s): waits for a heartbeat (state byte `state`, None:
        any), reads the node's clock (0x5F00 sub 6) right after it, waits for `intervals` more heartbeats and reads
        the clock again. Both reads come one SDO round trip after a heartbeat, so their difference is the node time
        of the intervals (to the difference of the two round trips). Event-based: no wall-clock waits."""
        nid = self.cfg.node_id

        def pred(f):
            return f.id == 0x700 + nid and len(f.data) == 1 and (state is None or f.data[0] == state)

        m = self.frames.mark()
        f = self.frames.wait(pred, timeout, m)
        if f is None:
            raise TimeoutError("no heartbeat within %.0f s" % timeout)
        n0 = self.read(0x5F00, 6)
        since = self.frames.mark()
        for _ in range(intervals):
            f = self.frames.wait(pred, timeout, since)
            if f is None:
                raise TimeoutError("heartbeats stopped")
            since = self.frames.frames.index(f, since) + 1 if hasattr(self.frames, "frames") else self.frames.mark()
        n1 = self.read(0x5F00, 6)
        return ((n1 - n0) & 0xFFFFFFFF) * 1e-3 / intervals

    def require_socketcan(self, pytest_mod, why="needs a SocketCAN interface for a second tool on the bus; the M4 image "
                                                "is reached over slcan on TCP, which takes one client (slcand would give "
                                                "one: docs/cortex_m.md)"):
        if self.cfg.kind == "mcu":
            pytest_mod.skip(why)

    def clock_start(self):
        """Start of a window over which the node's clock is compared with real time (clock_scale). None on rigs
        whose node runs on real time (lissom-node); the M4 image: (real time, its clock in ms, 0x5F00 sub 6)."""
        if self.cfg.kind != "mcu":
            return None
        return time.monotonic(), self.read(0x5F00, 6)

    def clock_scale(self, start):
        """Real seconds per second of the node's clock since clock_start() (1.0 for a real-time node). The M4
        image's clock runs at about 1/1.344 of real time, and slower still when QEMU falls behind (docs/cortex_m.md),
        so checks of the node's periods convert with the scale of the window they observe."""
        if start is None:
            return 1.0
        t0, n0 = start
        t1, n1 = time.monotonic(), self.read(0x5F00, 6)
        return (t1 - t0) / (((n1 - n0) & 0xFFFFFFFF) * 1e-3)

    # ---- NMT -----------------------------------------------------------------------------------------
    def nmt(self, command):
        """command: 'OPERATIONAL', 'STOPPED', 'PRE-OPERATIONAL', 'RESET', 'RESET COMMUNICATION'."""
        self.node.nmt.send_command({"OPERATIONAL": 0x01, "STOPPED": 0x02, "PRE-OPERATIONAL": 0x80,
                                    "RESET": 0x81, "RESET COMMUNICATION": 0x82}[command])

    def wait_heartbeat(self, state_byte, timeout=2.0, since=None):
        since = self.frames.mark() if since is None else since
        return self.frames.wait(lambda f: f.id == 0x700 + self.cfg.node_id and f.data == bytes([state_byte]),
                                timeout, since)

    def operational(self):
        mark = self.frames.mark()
        self.nmt("OPERATIONAL")
        if self.wait_heartbeat(0x05, 2.0, mark) is None:
            raise RuntimeError("node did not report OPERATIONAL")

    # ---- SDO -----------------------------------------------------------------------------------------
    def read(self, index, sub=None, axis=0):
        var = self.node.sdo[index + AXIS_STEP * axis]
        return (var if sub is None else var[sub]).raw

    def write(self, index, value, sub=None, axis=0):
        var = self.node.sdo[index + AXIS_STEP * axis]
        (var if sub is None else var[sub]).raw = value

    def abort_code(self, fn):
        """Runs fn(); returns the SDO abort code it raised, or 0."""
        try:
            fn()
            return 0
        except canopen.SdoAbortedError as e:
            return e.code

    # ---- CiA 402 -------------------------------------------------------------------------------------
    MODES = {"PROFILED POSITION": 1, "CYCLIC SYNCHRONOUS POSITION": 8, "PATH": -1, "NO MODE": 0}

    def statusword(self, axis=0):
        return self.read(0x6041, axis=axis)

    def state_of(self, axis=0):
        sw = self.statusword(axis)
        for name, (mask, bits) in canopen.profiles.p402.State402.SW_MASK.items():
            if sw & mask == bits:
                return name
        return "UNKNOWN"

    def wait_sw(self, axis, mask, value, timeout=5.0, poll=0.005):
        t_end = time.monotonic() + timeout
        while True:
            sw = self.statusword(axis)
            if sw & mask == value:
                return sw
            if time.monotonic() > t_end:
                raise TimeoutError("axis %d statusword 0x%04X: waited for &0x%04X == 0x%04X" % (axis, sw, mask, value))
            time.sleep(poll)

    def wait_until(self, cond, timeout, what, poll=0.01):
        """Polls cond() until it is true (the event); fails with `what` after timeout seconds. The timeouts of the
        suite are bounds for a loaded machine, never delays: a test waits only as long as the event takes."""
        t_end = time.monotonic() + timeout
        while True:
            v = cond()
            if v:
                return v
            if time.monotonic() > t_end:
                raise TimeoutError("%s (waited %.1f s)" % (what, timeout))
            time.sleep(poll)

    def wait_moving(self, axis, counts, timeout=5.0):
        """Waits until the position demand of axis is more than `counts` from home (a move is well under way)."""
        return self.wait_until(lambda: abs(self.demand(axis)) > counts, timeout,
                               "axis %d: demand did not pass %d counts" % (axis, counts), poll=0.005)

    def enable(self, axis=0, mode="PROFILED POSITION"):
        """Brings the axis to OPERATION ENABLED in `mode`. Axis 0 goes through canopen's BaseNode402 (its PDO
        configuration read from the node, op_mode, the state machine); the other axes have no PDOs of their
        own by default, so their controlword is written by SDO with the same CiA 402 sequence."""
        code = self.MODES[mode]
        if axis == 0 and code > 0:
            if not self._pdo_ready:
                self.node.setup_402_state_machine(read_pdos=True)
                self._pdo_ready = True
            self.node.op_mode = mode
            self.node.state = "OPERATION ENABLED"
        else:
            self.write(0x6060, code, axis=axis)
            for cw in (0x06, 0x07, 0x0F):
                self.write(0x6040, cw, axis=axis)
        self.wait_sw(axis, SW_STATE_MASK, SW_OPERATION_ENABLED, 2.0)
        t_end = time.monotonic() + 2.0
        while self.read(0x6061, axis=axis) != code:
            if time.monotonic() > t_end:
                raise RuntimeError("axis %d: mode display is not %s" % (axis, mode))
            time.sleep(0.01)

    def controlword(self, axis, value):
        self.write(0x6040, value, axis=axis)

    def cpm(self, axis=0):
        return self.limits[axis]["cpm"]

    def set_profile(self, axis=0, v=None, a=None, d=None, j=None, snap=None, profile_type=None, quick_decel=None):
        """Profile objects in mm units (converted with the axis's counts per mm)."""
        c = self.cpm(axis)
        for idx, val in ((0x6081, v), (0x6083, a), (0x6084, d if d is not None else a), (0x2060, j),
                         (0x2061, snap), (0x6085, quick_decel)):
            if val is not None:
                self.write(idx, int(round(val * c)), axis=axis)
        if profile_type is not None:
            self.write(0x6086, profile_type, axis=axis)

    def counts(self, axis, mm):
        """Absolute counts of a position given in mm from the axis's home (its position when the test started)."""
        return self.home[axis] + int(round(mm * self.cpm(axis)))

    def demand(self, axis=0):
        """Position demand 0x6062 in counts from home."""
        return self.read(0x6062, axis=axis) - self.home[axis]

    def wait_demand(self, axis, mm, timeout=5.0, poll=0.002, direction=None):
        """Waits until the position demand 0x6062 has reached or passed `mm` (from home), in the direction from
        the demand at the call towards `mm` (an event of the motion, not a wall-clock delay). Returns the demand
        in counts from home."""
        goal = int(round(mm * self.cpm(axis)))
        # the direction of the move: given, or from the demand at the call (a fast node may already have passed
        # `mm` when the first read arrives: give the direction then)
        sign = direction if direction is not None else (1 if goal >= self.demand(axis) else -1)
        t_end = time.monotonic() + timeout
        while True:
            d = self.demand(axis)
            if (d - goal) * sign >= 0:
                return d
            if time.monotonic() > t_end:
                raise TimeoutError("axis %d demand %d counts: waited to pass %d" % (axis, d, goal))
            time.sleep(poll)

    def actual(self, axis=0):
        """Position actual 0x6064 in counts from home."""
        return self.read(0x6064, axis=axis) - self.home[axis]

    def set_target(self, axis, target_mm):
        self.write(0x607A, self.counts(axis, target_mm), axis=axis)

    def pp_move(self, axis, target_mm, immediate=True, relative=False, wait=True, timeout=30.0):
        """Profile Position set-point with the CiA 402 hand-shake: target (mm from home; with relative=True,
        from the previous target), new set-point (bit 4) rising edge, wait for the set-point acknowledge
        (statusword bit 12), bit 4 back to 0; then (wait=True) wait for target reached (bit 10). Returns the time
        the move took (from the edge) or None."""
        if relative:
            self.write(0x607A, int(round(target_mm * self.cpm(axis))), axis=axis)
        else:
            self.set_target(axis, target_mm)
        cw = 0x0F | (0x20 if immediate else 0) | (0x40 if relative else 0)
        t0 = time.monotonic()
        self.controlword(axis, cw | 0x10)
        self.wait_sw(axis, SW_ACK, SW_ACK, 2.0)
        self.controlword(axis, cw)
        if not wait:
            return None
        self.wait_sw(axis, SW_TARGET_REACHED | SW_ACK, SW_TARGET_REACHED, timeout)
        return time.monotonic() - t0

    # ---- PDOs, SYNC, heartbeat --------------------------------------------------------------------------
    def map_tpdo(self, k, objects, trans_type=1, event_ms=0):
        """Maps objects [(index, sub, bits), ...] into TPDO k (1..4) with the CiA 301 procedure (PRE-OP or OP)."""
        comm, mapi = 0x1800 + k - 1, 0x1A00 + k - 1
        cob = self.node.sdo[comm][1].raw
        self.node.sdo[comm][1].raw = cob | 0x80000000
        self.node.sdo[mapi][0].raw = 0
        for i, (idx, sub, bits) in enumerate(objects, 1):
            self.node.sdo[mapi][i].raw = (idx << 16) | (sub << 8) | bits
        self.node.sdo[mapi][0].raw = len(objects)
        self.node.sdo[comm][2].raw = trans_type
        self.node.sdo[comm][5].raw = event_ms
        self.node.sdo[comm][1].raw = cob & ~0x80000000

    def pdo_valid(self, k, valid, tx=True):
        """Makes TPDO (tx) or RPDO k (1..4) valid or not valid (COB-ID bit 31)."""
        comm = (0x1800 if tx else 0x1400) + k - 1
        cob = self.node.sdo[comm][1].raw
        self.node.sdo[comm][1].raw = (cob & ~0x80000000) if valid else (cob | 0x80000000)

    def start_sync(self, period_s):
        self.network.sync.start(period_s)
        self._sync_period = period_s

    def stop_sync(self):
        if self._sync_period is not None and self.network is not None:
            self.network.sync.stop()
        self._sync_period = None

    def start_heartbeat(self, master_id, period_s=0.05):
        """Produce a master heartbeat (state OPERATIONAL) with the kernel's periodic send."""
        self.stop_heartbeat()
        self._hb = self.network.send_periodic(0x700 + master_id, [0x05], period_s)

    def stop_heartbeat(self):
        if self._hb is not None:
            self._hb.stop()
            self._hb = None

    # ---- the node's trace (local only) ------------------------------------------------------------------
    def trace(self, settle_s=0.15, timeout=10.0):
        """The node's trace so far. The daemon writes it every 64 cycles: while it runs, this waits for two more
        writes (the file grows twice: every cycle up to the call is then in it), an event rather than a delay,
        so a late node under load only makes the wait longer. settle_s=0: what the file holds now."""
        if not self.trace_path:
            raise RuntimeError("no trace: the node is not local, or was started without one")
        running = self.proc is not None and self.proc.proc is not None and self.proc.proc.poll() is None
        if settle_s > 0 and running and os.path.exists(self.trace_path):
            size = os.path.getsize(self.trace_path)
            for _ in range(2):
                self.wait_until(lambda: os.path.getsize(self.trace_path) > size, timeout,
                                "the node's trace did not grow", poll=0.01)
                size = os.path.getsize(self.trace_path)
        return Trace(self.trace_path)

    def save_plots(self, csv_path, prefix):
        """Plots a run CSV now (LISSOM_HIL_PLOT=1, the default on a host), or leaves it for
        `python -m lissom_hil.rig plot DIR` (LISSOM_HIL_PLOT=0: in the VM, where matplotlib is slow)."""
        if os.environ.get("LISSOM_HIL_PLOT", "1") == "0":
            return []
        from . import plot
        return plot.plot_run(csv_path, out_dir=os.path.dirname(csv_path), prefix=prefix, machine=self.cfg.machine)


def plot_dir(path):
    """Plots every *.csv run file under path (skips those whose PNGs are newer)."""
    from . import plot
    made = []
    for dirpath, _, files in os.walk(path):
        for fn in sorted(files):
            if not fn.endswith(".csv"):
                continue
            csv_path = os.path.join(dirpath, fn)
            prefix = fn[:-4]
            pngs = [p for p in os.listdir(dirpath) if p.startswith(prefix + "_") and p.endswith(".png")]
            if pngs and all(os.path.getmtime(os.path.join(dirpath, p)) >= os.path.getmtime(csv_path) for p in pngs):
                continue
            try:
                made += plot.plot_run(csv_path, out_dir=dirpath, prefix=prefix) or []
            except Exception as e:  # a plot must not hide the test results
                print("plot %s: %s" % (csv_path, e), file=sys.stderr)
    return made


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) == 2 and argv[0] == "plot":
        for p in plot_dir(argv[1]):
            print(p)
        return 0
    print(__doc__)
    return 2


if __name__ == "__main__":
    sys.exit(main())

