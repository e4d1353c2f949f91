"""`lissom-sim run` progress bar: on stderr only, on a terminal once the run is long (2 s of wall time) or
whenever --progress asks for it (one line per 10 % step when stderr is not a terminal), never with
--no-progress; stdout holds nothing but the --json summary in every case."""
import json
import os
import pty
import re
import subprocess
import time

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SIM = os.environ.get("LISSOM_SIM") or os.path.join(ROOT, "build", "bin", "lissom-sim")
PROG = os.path.join(ROOT, "host_sim", "examples", "surface_finish.ngc")  # 58.6 s of machine time, 3 drives
SHORT = os.path.join(ROOT, "host_sim", "examples", "shahzadeh_corner.ngc")
MACHINE = os.path.join(ROOT, "host_sim", "machines", "router.json")
LINE = re.compile(r"^progress: (planning|drives|CSV|plots)\s+(?:\[([#.]{20})\]\s+(\d+) %|\.\.\.)")


def run_pipe(tmp_path, *extra, prog=PROG):
    return subprocess.run([SIM, "run", prog, "--machine", MACHINE, "--out", str(tmp_path / "run"), "--json",
                           *extra], capture_output=True, text=True, timeout=300)


def run_pty(tmp_path, *extra, prog=PROG):
    """stderr on a pseudo-terminal (isatty true), stdout on a pipe."""
    master, slave = pty.openpty()
    try:
        p = subprocess.run([SIM, "run", prog, "--machine", MACHINE, "--out", str(tmp_path / "run"), "--json",
                            *extra], stdout=subprocess.PIPE, stderr=slave, timeout=300)
    finally:
        os.close(slave)
    err = b""
    while True:
        try:
            chunk = os.read(master, 65536)
        except OSError:  # EIO once the terminal is drained
            break
        if not chunk:
            break
        err += chunk
    os.close(master)
    return p.returncode, p.stdout.decode(), err.decode()


def check_summary(stdout, tmp_path):
    out = json.loads(stdout)  # nothing but the summary on stdout
    with open(tmp_path / "run" / "summary.json", encoding="utf-8") as f:
        assert out == json.load(f)
    assert "\r" not in stdout and "progress" not in stdout
    return out


def test_progress_lines_when_asked(tmp_path):
    p = run_pipe(tmp_path, "--progress", "--plots")
    assert p.returncode == 0, p.stderr
    check_summary(p.stdout, tmp_path)
    lines = p.stderr.splitlines()
    assert lines and all(LINE.match(x) for x in lines), p.stderr
    phases = [LINE.match(x).group(1) for x in lines]
    # the phases come in order, each drawn more than once (every 10 % step), then the plots
    order = [ph for i, ph in enumerate(phases) if i == 0 or phases[i - 1] != ph]
    assert order == ["planning", "drives", "CSV", "plots"]
    for ph in ("planning", "drives", "CSV"):
        pct = [int(LINE.match(x).group(3)) for x in lines if LINE.match(x).group(1) == ph]
        assert len(pct) >= 5, (ph, pct)
        assert pct == sorted(pct) and pct[0] == 0 and pct[-1] >= 80, (ph, pct)
        # the bar is as full as the percentage says, one '#' per 5 %
        for x in lines:
            m = LINE.match(x)
            if m.group(1) == ph:
                assert m.group(2).count("#") == int(m.group(3)) // 5
    # machine time on the planning and CSV lines, up to the run's duration
    t = [float(x) for x in re.findall(r"planning .* (\d+\.\d) s machine time", p.stderr)]
    assert t == sorted(t) and 0.8 * 58.6 <= t[-1] <= 58.6


def test_quiet_without_terminal(tmp_path):
    p = run_pipe(tmp_path)
    assert p.returncode == 0 and p.stderr == ""
    check_summary(p.stdout, tmp_path)
    p = run_pipe(tmp_path, "--no-progress")
    assert p.returncode == 0 and p.stderr == ""


def test_terminal_bar(tmp_path):
    rc, out, err = run_pty(tmp_path, "--progress")
    assert rc == 0, err
    check_summary(out, tmp_path)
    assert "\n" not in err.replace("\r\n", "")  # redrawn in place
    frames = [f for f in err.split("\r") if f.strip()]
    assert frames and any(f.startswith("planning  [") for f in frames) and any(f.startswith("drives") for f in frames)
    assert re.search(r"\r +\r$", err), "the bar is cleared at the end"
    # without the option, a run that takes more than 2 s of wall time (the offline reference planner on this
    # program: about 3 s) draws the bar once the 2 s have passed
    t0 = time.monotonic()
    rc, out, err = run_pty(tmp_path, "--planner", "vpop")
    elapsed = time.monotonic() - t0
    assert rc == 0, err
    check_summary(out, tmp_path)
    frames = [f for f in err.split("\r") if f.strip()]
    assert frames or elapsed < 2.5, f"no progress bar in a run of {elapsed:.1f} s"  # a much faster machine
    assert all(re.match(r"(planning|drives|CSV) ", f) for f in frames), err
    assert all(float(re.search(r"(\d+\.\d) s *$", f).group(1)) >= 2.0 for f in frames)  # elapsed wall time
    # a short run on a terminal stays quiet (under the 2 s delay), and --no-progress silences a long one
    rc, out, err = run_pty(tmp_path, prog=SHORT)
    assert rc == 0 and err == ""
    check_summary(out, tmp_path)
    rc, out, err = run_pty(tmp_path, "--no-progress")
    assert rc == 0 and err == ""


@pytest.mark.parametrize("args,msg", [(["--progress", "--no-progress"], "exclude each other"),
                                      (["--plots", "--out", "{tmp}/it's"], "single quote")])
def test_progress_option_errors(tmp_path, args, msg):
    args = [a.format(tmp=tmp_path) for a in args]
    if "--out" not in args:
        args += ["--out", str(tmp_path / "r")]
    p = subprocess.run([SIM, "run", SHORT, "--machine", MACHINE, *args], capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and msg in p.stderr
    assert not os.path.exists(os.path.join(str(tmp_path), "it's"))
