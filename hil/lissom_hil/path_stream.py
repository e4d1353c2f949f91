"""Streaming path blocks to the node (object 0x5010) with flow control and sequence numbers (co_path.h).

Encoding (little-endian): seq u32, type u8, plane u8, n u8, flags u8, feed u32 (um/s), tolerance u32 (um),
end i32 x n (counts), centre i32 x 2 (arcs, counts on the plane's first and second axis).

Flow control, as a careful master does it:
  - the buffer's free slots (0x5003) are known from the synchronous TPDO the rig maps them into, or read by SDO;
    no block is sent while the node reports no free slot;
  - an SDO abort 0x08000020 (buffer full) means "retry the same block later";
  - an SDO abort 0x06090031 (sequence gap) means the node did not get some earlier block: read the last
    accepted sequence 0x5004 and resend from the one after it;
  - an SDO timeout (the response was lost) means "send the same block again": if the node had stored it, the
    repeat is acknowledged as a duplicate and not applied twice; so does a transfer broken at the SDO protocol
    level (a toggle error 0x05030000, a server time-out 0x05040000, an out-of-sequence command 0x05040001, or an
    unexpected answer: what a lost, duplicated or reordered frame of the transfer gives);
  - a read of 0x5003 / 0x5004 that fails the same way is read again.
"""
import struct
import time

import canopen

ABORT_GAP = 0x06090031
ABORT_FULL = 0x08000020
ABORT_STATE = 0x08000022
ABORT_SDO_TIMEOUT = 0x05040000  # the server timed the transfer out
ABORT_SDO_COMMAND = 0x05040001  # the server took a segment for something else (the transfer is gone)
# SDO protocol aborts: the transfer broke (a frame lost, repeated or out of order), not the block. 0x06070010
# (length mismatch) belongs here too: the streamer only sends 0x5010 blocks of their exact length and reads
# objects of fixed size, so the node says it only of a transfer whose frames were lost, repeated or reordered
# (seen on the lossy bridge, test_fault_lossy_bridge: a repeated segment's abort answered the next upload).
PROTOCOL_ABORTS = (0x05030000, 0x05040000, 0x05040001, 0x06070010)
READ_RETRIES = 20


def encode_block(seq, blk, counts_per_mm, tol_mm=0.01, origin=None):
    """Bytes of one 0x5010 block; positions in mm are converted to counts and offset by origin (counts per axis,
    default 0: the program's zero is where the axes are at `origin`)."""
    n = len(blk.end)
    cpm = counts_per_mm if isinstance(counts_per_mm, (list, tuple)) else [counts_per_mm] * n
    org = list(origin) if origin is not None else [0] * n
    feed_um = max(1, int(round(blk.feed * 1000)))
    tol_um = max(1, int(round(tol_mm * 1000)))
    data = struct.pack("<IBBBBII", seq & 0xFFFFFFFF, blk.type, blk.plane if blk.type != 1 else 0, n, 0, feed_um, tol_um)
    data += struct.pack("<%di" % n, *(o + int(round(e * c)) for e, c, o in zip(blk.end, cpm, org)))
    if blk.type != 1:
        pa, pb = {0: (0, 1), 1: (2, 0), 2: (1, 2)}[blk.plane]  # the plane's first and second axis
        data += struct.pack("<ii", org[pa] + int(round(blk.centre[0] * cpm[pa])),
                            org[pb] + int(round(blk.centre[1] * cpm[pb])))
    return data


class PathStreamer:
    def __init__(self, node, counts_per_mm=1000, tol_mm=0.01, free_slots=None, log=None, origin=None):
        """node: a canopen RemoteNode. free_slots: optional callable returning the latest free-slot count seen
        in telemetry (None: read 0x5003 by SDO when needed). origin: counts of the program's zero per axis."""
        self.node = node
        self.origin = origin
        self.cpm = counts_per_mm
        self.tol = tol_mm
        self.free_slots = free_slots
        self.log = log if log is not None else []
        self.sent = 0
        self.retries = {"full": 0, "gap": 0, "timeout": 0, "protocol": 0, "aborted": 0}
        self.waits = 0  # times no free slot was reported (flow control held the stream)

    def _read(self, index):
        for k in range(READ_RETRIES):
            try:
                return self.node.sdo[index].raw
            except canopen.SdoCommunicationError:
                self.retries["timeout"] += 1
            except canopen.SdoAbortedError as e:
                if e.code not in PROTOCOL_ABORTS or k == READ_RETRIES - 1:
                    raise
                self.retries["protocol"] += 1
        raise TimeoutError("reading 0x%04X failed %d times" % (index, READ_RETRIES))

    def last_accepted(self):
        return self._read(0x5004)

    def _free(self):
        if self.free_slots is not None:
            v = self.free_slots()
            if v is not None:
                return v
        return self._read(0x5003)

    def write_raw(self, data):
        """One 0x5010 download. Returns 0 or the abort code; raises on other SDO errors."""
        try:
            self.node.sdo.download(0x5010, 0, data)
            return 0
        except canopen.SdoAbortedError as e:
            return e.code

    def send(self, seq, blk):
        return self.write_raw(encode_block(seq, blk, self.cpm, self.tol, self.origin))

    def stream(self, blocks, first_seq=1, timeout=60.0, on_block=None, lose=None, on_wait=None):
        """Sends blocks[i] with sequence first_seq + i, in order, with the flow control above. on_block(i) is
        called before each first attempt (a test can inject frames there); lose(i) returning True makes the
        streamer skip that download as if it had been lost on the way (a test of the gap recovery).
        on_wait(i) is called each time the stream has to wait for a free slot before block i.
        Returns the number of downloads."""
        i = 0
        t_end = time.monotonic() + timeout
        downloads = 0
        waited_full = False
        lost = set()
        while i < len(blocks):
            if time.monotonic() > t_end:
                raise TimeoutError("path streaming: %d of %d blocks after %.0f s" % (i, len(blocks), timeout))
            if not waited_full and self._free() <= 0:
                self.waits += 1
                if on_wait is not None:
                    on_wait(i)
                time.sleep(0.01)
                continue
            if on_block is not None and not waited_full:
                on_block(i)
            if lose is not None and i not in lost and lose(i):
                lost.add(i)
                self.log.append(("lost", first_seq + i))
                i += 1
                continue
            try:
                code = self.send(first_seq + i, blocks[i])
            except canopen.SdoCommunicationError:
                self.retries["timeout"] += 1
                self.log.append(("timeout", first_seq + i))
                continue  # same block again: a duplicate is acknowledged and not stored twice
            downloads += 1
            if code == 0:
                self.log.append(("ok", first_seq + i))
                i += 1
                waited_full = False
            elif code in PROTOCOL_ABORTS:
                self.retries["protocol"] += 1
                self.log.append(("protocol", first_seq + i, code))
            elif code == ABORT_FULL:
                self.retries["full"] += 1
                waited_full = False
                time.sleep(0.01)
            elif code in (ABORT_SDO_TIMEOUT, ABORT_SDO_COMMAND):
                # the transfer broke (a late master: the server timed out, or took a segment for a new request);
                # the same block again: if the first attempt was stored, it is acknowledged as a duplicate
                self.retries["aborted"] += 1
                self.log.append(("aborted", first_seq + i, code))
                continue
            elif code == ABORT_GAP:
                self.retries["gap"] += 1
                last = self.last_accepted()
                self.log.append(("gap", first_seq + i, last))
                i = last + 1 - first_seq
                if i < 0:
                    raise RuntimeError("node's last accepted sequence %d is before the program" % last)
            else:
                raise RuntimeError("block %d refused: SDO abort 0x%08X" % (first_seq + i, code))
        self.sent += downloads
        return downloads
