"""Coordinated path motion (co_path.h objects 0x5000-0x5010): a G-code program streamed as path blocks with
flow control, sequence gaps and duplicates (no block lost or applied twice), hold / resume / override / clear.
The node runs the blocks through the look-ahead planner (corner blending within each block's tolerance), or
with --path-exec exact as exact-stop moves (test_path_exact)."""
import math
import struct
import time

import numpy as np
import pytest

from lissom_hil.gcode import ARC_CCW, LINE, read_gcode
from lissom_hil.path_stream import ABORT_GAP, PathStreamer
from lissom_hil.trace import check_limits

PROGRAM = """
(rounded pocket corner, a full circle and a plunge: lines, G2/G3 arcs, a helix-free Z move)
G21 G90 G17
G1 X20 Y0 F3000
G1 Y10
G3 X10 Y20 I-10 J0
G3 X0 Y10 I0 J-10
G1 X0 Y0
G2 X0 Y0 I5 J0 F1800
G1 Z-2 F600
G1 Z0
"""
SYNC_S = 0.02


TOL_MM = 0.01


def _path_setup(rig, extra=None):
    if extra:
        rig.restart(extra)
    rig.operational()
    rig.pdo_valid(3, False)  # TPDO2 (path state, free slots, last sequence) is all the streaming needs
    rig.pdo_valid(4, False)
    for k in range(3):
        rig.enable(k, "PATH")
    rig.start_sync(SYNC_S)


def _free_from_tpdo(rig):
    """Free slots (0x5003) from the latest TPDO2 (0x5002 u8, 0x5003 u16, 0x5004 u32 at each SYNC)."""
    cob = 0x280 + rig.node_id

    def free():
        fr = rig.frames.select(lambda f: f.id == cob and len(f.data) == 7, max(rig.frames.mark() - 100, 0))
        return struct.unpack_from("<BHI", fr[-1].data)[1] if fr else None
    return free


def _wait_done(rig, last_seq, timeout=30.0):
    t_end = time.monotonic() + timeout
    while time.monotonic() < t_end:
        if rig.read(0x5005) == last_seq and rig.read(0x5003) == rig.read(0x5007) and rig.read(0x6041) & 0x0400:
            return
        time.sleep(0.05)
    raise TimeoutError("path not finished: executing %d of %d" % (rig.read(0x5005), last_seq))


def _executed_sequence(tr):
    seq = tr["path_seq"].astype(int)
    runs = [int(seq[0])] + [int(b) for a, b in zip(seq, seq[1:]) if b != a]
    return [s for s in runs if s != 0]


def _distances(pts, prev, b):
    """Distance of points from one block's geometry (line segment, or arc circle)."""
    end = np.array(b.end, dtype=float)
    if b.type == LINE:
        d = end - prev
        L2 = float(d @ d)
        t = np.clip(((pts - prev) @ d) / L2, 0, 1) if L2 > 0 else np.zeros(len(pts))
        return np.linalg.norm(pts - (prev + np.outer(t, d)), axis=1)
    c = np.array(b.centre)
    r = math.hypot(prev[0] - c[0], prev[1] - c[1])
    return np.abs(np.hypot(pts[:, 0] - c[0], pts[:, 1] - c[1]) - r)


def _on_block_geometry(tr, blocks, start=(0.0, 0.0, 0.0)):
    """Largest distance (mm) of the trace positions from the programmed path near the block executing at that
    cycle (that block or the one before it: a blended corner carries the tag of the block it leads into)."""
    pos = np.stack([tr.axis(k, "set_mm") for k in range(3)], axis=1)
    seq = tr["path_seq"].astype(int)
    worst = 0.0
    prev = np.array(start, dtype=float)
    before = None
    for s, b in enumerate(blocks, 1):
        pts = pos[seq == s]
        if len(pts):
            err = _distances(pts, prev, b)
            if before is not None:
                err = np.minimum(err, _distances(pts, *before))
            worst = max(worst, float(np.max(err)))
        before = (prev, b)
        prev = np.array(b.end, dtype=float)
    return worst


def _run_program(rig, extra, name):
    blocks = read_gcode(PROGRAM, n_axes=3)
    assert len(blocks) == 8 and blocks[2].type == ARC_CCW
    _path_setup(rig, extra)
    streamer = PathStreamer(rig.node, 1000, tol_mm=TOL_MM, free_slots=_free_from_tpdo(rig), origin=rig.home)
    started = []

    def start(_i):  # the path starts once the buffer is full: the stream then has to wait for free slots
        if not started:
            started.append(True)
            rig.write(0x5000, 1)

    streamer.stream(blocks, on_wait=start)
    start(None)
    _wait_done(rig, len(blocks))
    assert rig.read(0x5004) == len(blocks)
    assert [rig.demand(k) for k in range(3)] == [0, 0, 0]  # the programmed end, to the count
    assert rig.read(0x5008, 4) >= 1  # underrun counted at the end of the program (and possibly while waiting)
    tr = None
    if rig.local:
        tr = rig.trace()
        assert _executed_sequence(tr) == list(range(1, len(blocks) + 1))
        feed = tr["feed_mm_s"]
        seq = tr["path_seq"].astype(int)
        for s, b in enumerate(blocks, 1):
            f = feed[seq == s]
            assert len(f) == 0 or np.max(f) <= b.feed * (1 + 1e-6) + 1e-3, "block %d feed %.3f > %.3f" % (
                s, np.max(f), b.feed)
        lim = rig.limits[0]
        for k in range(3):
            bad = check_limits(tr.axis(k, "set_mm"), tr.cycle_s, lim["v"], lim["a"], lim["j"], what="axis %d" % k)
            assert not bad, bad
        tr.write_csv(rig.out("%s_trace.csv" % name), decimate=2)
        rig.save_plots(rig.out("%s_trace.csv" % name), "%s_trace" % name)
    return blocks, streamer, tr


@pytest.mark.motion
def test_path_gcode(rig):
    """Look-ahead planner (the node's default executor): a small buffer (4 co_path slots) so that the stream
    must wait for free slots; corners blended within the tolerance, every axis within its v, a, j limits."""
    blocks, streamer, tr = _run_program(rig, ["--path-slots", "4", "--lookahead", "16"], "path")
    if rig.local:  # (a board keeps its own buffer sizes: the small buffers above are lissom-node options)
        assert streamer.waits > 0, "the buffer never filled: flow control was not exercised"
    if tr is not None:
        dev = _on_block_geometry(tr, blocks)
        assert dev <= TOL_MM * 1.01, "the path left the programmed geometry by %.4g mm" % dev
        # blending: the corner between blocks 1 and 2 is not an exact stop (the feed never reaches 0 there; it
        # is low because a 90 degree corner within 0.01 mm has a small radius)
        seq = tr["path_seq"].astype(int)
        k = int(np.nonzero(seq == 2)[0][0])
        assert np.min(tr["feed_mm_s"][k - 20:k + 20]) > 0.1, "stopped at a blended corner"


@pytest.mark.motion
def test_path_exact(rig):
    """The exact-stop executor (--path-exec exact): every block alone, on the geometry to rounding."""
    blocks, _, tr = _run_program(rig, ["--path-exec", "exact"], "exact")
    if tr is not None:
        dev = _on_block_geometry(tr, blocks)
        assert dev < 1e-6, "the path left the programmed geometry by %.3g mm" % dev


@pytest.mark.motion
def test_path_seq(rig):
    """Gaps and duplicates: nothing lost, nothing applied twice."""
    pts = [(5.0 * (i + 1), 4.0 * (i % 2), 0.0) for i in range(10)]
    text = "G21 G90\n" + "".join("G1 X%.3f Y%.3f F2400\n" % (x, y) for x, y, _ in pts)
    blocks = read_gcode(text)
    _path_setup(rig)
    streamer = PathStreamer(rig.node, 1000, origin=rig.home)
    done = set()
    results = {}

    def inject(i):
        if i in done:
            return
        done.add(i)
        if i == 3:   # the master repeats block 3 (as after a lost SDO response): acknowledged, not stored
            results["dup"] = streamer.send(3, blocks[2])
        if i == 5:   # block 8 arrives before 6: refused with 0x06090031, nothing stored
            results["gap"] = streamer.send(8, blocks[7])

    rig.write(0x5000, 1)
    streamer.stream(blocks, on_block=inject, lose=lambda i: i == 7)  # and block 8's download is "lost"
    _wait_done(rig, len(blocks))
    assert results == {"dup": 0, "gap": ABORT_GAP}
    assert streamer.retries["gap"] == 1, streamer.log  # the lost block 8 was detected and resent
    assert rig.read(0x5008, 1) == 1, "duplicates counted"
    assert rig.read(0x5008, 2) == 2, "gaps counted (the injected one and the lost block)"
    assert rig.read(0x5004) == len(blocks)
    assert rig.demand(0) == round(pts[-1][0] * 1000) and rig.demand(1) == round(pts[-1][1] * 1000)
    if rig.local:
        tr = rig.trace()
        assert _executed_sequence(tr) == list(range(1, len(blocks) + 1)), "blocks lost or repeated"
        assert _on_block_geometry(tr, blocks) <= TOL_MM * 1.01


@pytest.mark.motion
def test_path_hold(rig):
    """Feed hold and resume on the path, override, clear."""
    _path_setup(rig)
    streamer = PathStreamer(rig.node, 1000, origin=rig.home)
    b1, b2, b3 = read_gcode("G21 G90\nG1 X60 Y30 F2400\nG1 X0 Y30\nG1 X0 Y0\n")
    rig.write(0x5000, 1)
    assert streamer.send(1, b1) == 0
    rig.wait_moving(0, 10000)  # 10 mm along the first block
    rig.write(0x5000, 2)  # hold
    t_end = time.monotonic() + 3
    while rig.read(0x5002) != 3 and time.monotonic() < t_end:  # HELD
        time.sleep(0.02)
    assert rig.read(0x5002) == 3
    held = [rig.demand(k) for k in range(2)]
    assert 0 < held[0] < 60000 and abs(held[1] * 2 - held[0]) <= 2, "held off the line: %s" % held
    time.sleep(0.1)
    assert [rig.demand(k) for k in range(2)] == held
    rig.write(0x5000, 3)  # resume
    rig.write(0x5001, 50)  # override 50 % for the next block
    assert streamer.send(2, b2) == 0
    _wait_done(rig, 2)
    assert [rig.demand(k) for k in range(2)] == [0, 30000]
    # clear while moving: quick stop on the path, buffer flushed, state IDLE
    rig.write(0x5001, 100)
    assert streamer.send(3, b3) == 0
    rig.wait_until(lambda: rig.read(0x5005) == 3 and rig.demand(1) < 25000, 5.0, "block 3 not under way")
    rig.write(0x5000, 4)
    t_end = time.monotonic() + 3
    while rig.read(0x5002) != 0 and time.monotonic() < t_end:
        time.sleep(0.02)
    assert rig.read(0x5002) == 0 and rig.read(0x5003) == rig.read(0x5007)
    y_stop = rig.demand(1)
    assert 0 < y_stop < 30000 and rig.demand(0) == 0
    if rig.local:
        tr = rig.trace()
        x, y = tr.axis(0, "set_mm"), tr.axis(1, "set_mm")
        seq = tr["path_seq"].astype(int)
        on1 = seq == 1
        assert np.max(np.abs(y[on1] * 2 - x[on1])) < 1e-6, "hold left the line"
        f2 = tr["feed_mm_s"][seq == 2]
        assert np.max(f2) <= 20.0 * (1 + 1e-6) and np.max(f2) > 19.0, "override 50 %% of 40 mm/s: %.3f" % np.max(f2)
        lim = rig.limits[0]
        for k in range(2):
            bad = check_limits(tr.axis(k, "set_mm"), tr.cycle_s, lim["v"], lim["a"], lim["j"], what="axis %d" % k)
            assert not bad, bad
        tr.write_csv(rig.out("hold_trace.csv"), decimate=2)
        rig.save_plots(rig.out("hold_trace.csv"), "hold_trace")
