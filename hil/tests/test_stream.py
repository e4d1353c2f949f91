"""A dense path program streamed over CAN while it runs: 240 points 0.5 mm apart (a gentle sine in XY, the kind of
polyline CAM output makes) at 10 mm/s, so the node has to take in 20 blocks per second of its clock from the
stream (0x5010 segmented downloads with flow control) and keep its look-ahead ahead of the interpolator.

Checks: every block executed once, in order, ending exactly on the last point; the path never ran dry before the
end of the program (0x5008 sub 4 underruns: only the final one). Figures (stream.json in the test's artefact
directory, and in the test output): blocks per second sustained (real time and the node's clock), stream waits,
and on the M4 image its tick statistics (0x5F00) over the stream: worst tick and background load.
"""
import json
import math
import time

from lissom_hil.gcode import read_gcode
from lissom_hil.path_stream import PathStreamer

N_POINTS = 240
STEP_MM = 0.5
FEED_MM_MIN = 600  # 10 mm/s: 20 blocks/s of 0.5 mm
SYNC_S = 0.02


def _program():
    lines = ["G21 G90 G17"]
    for i in range(1, N_POINTS + 1):
        x = i * STEP_MM
        lines.append("G1 X%.4f Y%.4f F%d" % (x, 2.0 * math.sin(x / 8.0), FEED_MM_MIN))
    return "\n".join(lines) + "\n"


def test_path_dense_stream(rig):
    blocks = read_gcode(_program(), n_axes=3)
    assert len(blocks) == N_POINTS
    rig.operational()
    rig.pdo_valid(3, False)
    rig.pdo_valid(4, False)
    for k in range(3):
        rig.enable(k, "PATH")
    rig.start_sync(SYNC_S)
    under0 = rig.read(0x5008, 4)
    stats0 = rig.read_tick_stats()
    streamer = PathStreamer(rig.node, 1000, tol_mm=0.01, origin=rig.home)
    # the path starts after the first 8 blocks: from then on the stream must keep ahead of the motion
    c = rig.clock_start()
    t0 = time.monotonic()
    streamer.stream(blocks[:8])
    rig.write(0x5000, 1)
    streamer.stream(blocks[8:], first_seq=9, timeout=120.0)
    t_stream = time.monotonic() - t0
    under_mid = rig.read(0x5008, 4) - under0  # before the end of the program: must be 0
    scale = rig.clock_scale(c)
    stats1 = rig.read_tick_stats()
    t_end = time.monotonic() + 60.0
    while rig.read(0x5005) != N_POINTS or rig.read(0x5003) != rig.read(0x5007):
        assert time.monotonic() < t_end, "path not finished: executing %d of %d" % (rig.read(0x5005), N_POINTS)
        time.sleep(0.05)
    time.sleep(0.3 * rig.time_scale)
    end = [rig.demand(k) for k in range(3)]
    want = [int(round(v * 1000)) for v in blocks[-1].end]
    fig = {"blocks": N_POINTS, "stream_s": t_stream, "blocks_per_s_real": N_POINTS / t_stream,
           "blocks_per_s_node": N_POINTS / (t_stream / scale), "demand_blocks_per_s_node": FEED_MM_MIN / 60 / STEP_MM,
           "stream_waits": streamer.waits, "retries": streamer.retries, "underruns_before_end": under_mid,
           "time_scale": scale}
    if stats0 is not None and stats1 is not None:
        fig["tick_stats_before"] = stats0
        fig["tick_stats_after"] = stats1
    with open(rig.out("stream.json"), "w") as f:
        json.dump(fig, f, indent=1)
    print("dense stream: %s" % json.dumps(fig))
    assert rig.read(0x5004) == N_POINTS
    assert end == want, "end %s, programmed %s" % (end, want)
    assert under_mid == 0, "the path ran dry %d times before the end of the program" % under_mid
