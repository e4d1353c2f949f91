"""HIL suite fixtures. Every test is `test_<feature>(rig)`; the rig is chosen on the command line:

    pytest hil/tests --rig vcan                 # default: lissom-node started per test on vcan0
    pytest hil/tests --rig can0                 # a real board on can0 (node id --node-id), CANopen only
    pytest hil/tests --rig can0 --rig-local     # lissom-node on can0 (e.g. two machines / a USB adapter loop)
    pytest hil/tests --rig mcu                  # the Cortex-M4F controller image under QEMU, over slcan on TCP
Other options: --iface NAME, --node-id N, --machine FILE (limits for the checks; passed to a local node),
--hil-out DIR (artefacts: node log, candump-style frame log, trace CSVs and plots; default out/hil).
"""
import os
import sys

import pytest

# this repository's lissom_hil, whatever the venv's editable install points to
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from lissom_hil.rig import ROOT, Rig, RigConfig  # noqa: E402


def pytest_configure(config):
    config.addinivalue_line("markers", "motion: needs the node's motion layer (PP, CSP, path); skipped on a controller "
                            "image built with the interim hold layer (firmware/apps/controller/ctl_motion_hold.c)")


def pytest_addoption(parser):
    g = parser.getgroup("lissom-hil")
    g.addoption("--rig", default=os.environ.get("LISSOM_RIG", "vcan"), help="vcan (default), can0 / canN, or mcu")
    g.addoption("--iface", default=None, help="CAN interface (default: vcan0 for the vcan rig, else the rig name)")
    g.addoption("--node-id", type=int, default=1)
    g.addoption("--rig-local", action="store_true", default=None, help="start lissom-node also on a real interface")
    g.addoption("--machine", default=None, help="machine file for the local node and the limit checks")
    g.addoption("--hil-out", default=os.path.join(ROOT, "out", "hil"))


@pytest.fixture(scope="session")
def rig_session(request):
    o = request.config.option
    cfg = RigConfig(kind=o.rig, iface=o.iface, node_id=o.node_id, local=o.rig_local, machine=o.machine,
                    out_dir=o.hil_out)
    r = Rig(cfg)
    try:
        r.open()
    except OSError as e:
        pytest.exit("cannot open CAN interface %s: %s" % (r.cfg.iface, e), returncode=3)
    yield r
    r.close()


@pytest.fixture
def rig(rig_session, request):
    """The rig with a freshly booted node (a new lissom-node process on vcan, an NMT reset of a board)."""
    r = rig_session
    if request.node.get_closest_marker("motion") is not None and not r.has_motion:
        pytest.skip("this controller image links the interim hold layer: no motion layer (firmware/motion) on its branch")
    r.set_test_dir(request.node.name)
    mark = r.frames.mark()
    r.start()
    if r.local:  # a fresh lissom-node starts at 0: the trace's absolute positions are the tests' positions
        assert r.home == [0] * len(r.home)
    ok = False
    try:
        yield r
        ok = True
    finally:
        rc = r.stop()
        r.frames.dump(r.out("frames.log"), mark)
        if ok and r.local and rc not in (0, None):  # (None: the test stopped it itself)
            pytest.fail("lissom-node did not shut down cleanly (exit %s); see %s" % (rc, r.out("node.log")))
