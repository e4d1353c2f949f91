"""E-stop input on a gpio-sim line: edge during a move -> EMCY 0x9000, FAULT REACTION ACTIVE with the
fastest jerk-limited stop the machine allows, then FAULT; fault reset refused while the input stays active;
the drive-enable and in-position outputs follow the axis."""
import time

import pytest

from lissom_hil import gpio_sim
from lissom_hil.checks import stop_violations

ESTOP, ENABLE, INPOS = 0, 1, 2


def _wait(cond, timeout, what):
    t_end = time.monotonic() + timeout
    while not cond():
        assert time.monotonic() < t_end, what
        time.sleep(0.01)


def test_estop(rig):
    rig.require_local(pytest, "E-stop is simulated with gpio-sim next to a local lissom-node")
    if not gpio_sim.available():
        pytest.skip("gpio-sim is not available in this kernel (hil/vm builds it for the VM)")
    chip = gpio_sim.GpioSim("lissom-hil", 8, {ESTOP: "estop", ENABLE: "drive-enable", INPOS: "in-position"}).create()
    try:
        chip.pull(ESTOP, "pull-down")  # contact closed: no stop requested
        rig.restart(["--gpio-chip", chip.name, "--estop-line", str(ESTOP), "--enable-line", str(ENABLE),
                     "--inpos-line", str(INPOS)])
        assert "estop=yes" in rig.proc.ready_line
        assert chip.value(ENABLE) == 0 and chip.value(INPOS) == 0
        nid = rig.node_id
        rig.operational()
        for k in range(3):  # in position = every axis at its target (and enabled)
            rig.enable(k, "PROFILED POSITION")
        rig.set_profile(0, v=120.0, a=1000.0, j=20000.0, snap=2e6, profile_type=1)
        _wait(lambda: chip.value(ENABLE) == 1, 1.0, "drive enable not set in OPERATION ENABLED")
        _wait(lambda: chip.value(INPOS) == 1, 1.0, "in position not set at rest")
        rig.pp_move(0, 300.0, wait=False)
        rig.wait_moving(0, 20000)  # 20 mm under way
        assert chip.value(INPOS) == 0, "in position while moving"
        m = rig.frames.mark()
        chip.pull(ESTOP, "pull-up")  # E-stop pressed (or the wire broken)
        e = rig.frames.wait_emcy(nid, 0x9000, 1.0, m)
        assert e is not None, "no E-stop EMCY"
        _wait(lambda: rig.state_of(0) == "FAULT", 3.0, "axis not in FAULT after the stop")
        assert rig.read(0x603F) == 0x9000
        assert rig.read(0x5020) & 0x01
        _wait(lambda: chip.value(ENABLE) == 0, 1.0, "drive enable still set in FAULT")
        stopped = rig.demand(0)
        assert 0 < stopped < 300000
        # fault reset is refused while the E-stop is active
        rig.controlword(0, 0x00)
        rig.controlword(0, 0x80)
        time.sleep(0.05)
        assert rig.state_of(0) == "FAULT"
        # release: error reset EMCY, then the fault reset works
        m2 = rig.frames.mark()
        chip.pull(ESTOP, "pull-down")
        assert rig.frames.wait_emcy(nid, 0x0000, 1.0, m2) is not None, "no error-reset EMCY on release"
        rig.controlword(0, 0x00)
        rig.controlword(0, 0x80)
        _wait(lambda: rig.state_of(0) == "SWITCH ON DISABLED", 1.0, "fault reset refused after release")
        assert rig.demand(0) == stopped
        tr = rig.trace()
        q = tr.first(tr["estop"] > 0)
        assert q is not None and tr.axis(0, "state")[q] == 6  # FAULT REACTION ACTIVE
        lim = dict(rig.limits[0])
        bad = stop_violations(tr, 0, q, {"a": lim["a"], "j": lim["j"], "snap": lim["snap"]}, pre=1)
        assert not bad, bad
        tr.write_csv(rig.out("estop_trace.csv"), start=max(q - 400, 0))
        rig.save_plots(rig.out("estop_trace.csv"), "estop_trace")
        assert rig.stop() == 0, "lissom-node did not shut down cleanly"
    finally:
        rig.stop()
        chip.remove()
