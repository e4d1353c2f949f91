"""`lissom-sim stream` without a node: its usage errors, a program with errors refused (every error listed, exit 1)
before the bus is touched, and an interface that cannot be opened (exit 4). The end-to-end runs on vcan0 are in
hil/tests/test_stream.py."""
import os

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def test_usage(sim, tmp_path):
    prog = tmp_path / "p.ngc"
    prog.write_text("G0 X1\nM2\n")
    for args in (["stream", prog], ["stream", prog, "--iface", "vcan0"], ["stream", "--iface", "vcan0", "--node-id", 1],
                 ["stream", prog, "--iface", "vcan0", "--node-id", 0], ["stream", prog, "--iface", "vcan0",
                 "--node-id", 1, "--tol-mm", 0], ["stream", prog, "--iface", "vcan0", "--node-id", 1, "--bogus"]):
        p = sim(*args, ok=False)
        assert p.returncode == 2, (args, p.stderr)
    p = sim("stream", tmp_path / "missing.ngc", "--iface", "vcan0", "--node-id", 1, ok=False)
    assert p.returncode == 2 and "cannot read" in p.stderr


def test_program_errors_refused_before_the_bus(sim, tmp_path):
    prog = tmp_path / "bad.ngc"
    prog.write_text("G21\nG1 X1 Q7 F100\nG1 X#2\nM2\n")
    p = sim("stream", prog, "--iface", "no-such-can9", "--node-id", 1, ok=False)
    assert p.returncode == 1
    assert p.stderr.splitlines() == [f"{prog}:2:7: error: unknown word 'Q7'", f"{prog}:3:5: error: unsupported: "
                                     "parameters (#2)", f"{prog}: 2 error(s): nothing was sent"]


def test_no_interface(sim, tmp_path):
    prog = tmp_path / "p.ngc"
    prog.write_text("G0 X1\nM2\n")
    p = sim("stream", prog, "--iface", "no-such-can9", "--node-id", 1, ok=False)
    assert p.returncode == 4
    assert p.stderr.startswith("error: ") and ("no-such-can9" in p.stderr or "SocketCAN" in p.stderr)
