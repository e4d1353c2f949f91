"""Installable: `cmake --install build --prefix P` into a fresh temporary prefix puts the programs, machine files,
examples, the EDS and the plotter under P; the installed lissom-sim runs an example with --plots from a directory
outside the source tree and draws its PNGs with the installed plotter; --plots that cannot draw is an error; the
Python package installs with pip from hil/ (its pyproject)."""
import importlib.util
import os
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("LISSOM_BUILD", os.path.join(ROOT, "build"))


def _install(prefix):
    subprocess.run(["cmake", "--install", BUILD, "--prefix", str(prefix)], check=True, capture_output=True)


def test_install_tree_and_plots(tmp_path):
    prefix = tmp_path / "prefix"
    _install(prefix)
    share = prefix / "share" / "lissom"
    for rel in ["bin/lissom-sim", "bin/lissom-node"]:
        assert os.access(prefix / rel, os.X_OK), rel
    for rel in ["machines/router.json", "examples/pocket.ngc", "lissom.eds", "python/lissom_hil/plot.py"]:
        assert (share / rel).is_file(), rel
    # a python3 on PATH that records which lissom_hil it imports, then runs the real one (numpy, matplotlib)
    wrap = tmp_path / "wrap"
    wrap.mkdir()
    log = tmp_path / "which.txt"
    (wrap / "python3").write_text(
        "#!/bin/sh\n%s -c 'import lissom_hil, sys; open(sys.argv[1], \"w\").write(lissom_hil.__file__)' %s\n"
        "exec %s \"$@\"\n" % (sys.executable, log, sys.executable))
    (wrap / "python3").chmod(0o755)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "LISSOM_PYTHON")}
    env["PATH"] = "%s:/usr/bin:/bin" % wrap
    work = tmp_path / "elsewhere"
    work.mkdir()
    out = work / "run"
    p = subprocess.run([str(prefix / "bin" / "lissom-sim"), "run", str(share / "examples" / "shahzadeh_corner.ngc"),
                        "--machine", str(share / "machines" / "router.json"), "--out", str(out), "--plots"],
                       cwd=work, env=env, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    pngs = sorted(f for f in os.listdir(out) if f.endswith(".png"))
    assert pngs == ["run_accel.png", "run_error.png", "run_feed.png", "run_jerk.png", "run_path.png"]
    assert all((out / f).stat().st_size > 1000 for f in pngs)
    assert log.read_text().startswith(str(share / "python")), log.read_text()
    # the same with a plotter that cannot draw: an error, not a warning
    env["LISSOM_PYTHON"] = "/bin/false"
    p = subprocess.run([str(prefix / "bin" / "lissom-sim"), "run", str(share / "examples" / "shahzadeh_corner.ngc"),
                        "--machine", str(share / "machines" / "router.json"), "--out", str(work / "r2"), "--plots",
                        "--no-drive"], cwd=work, env=env, capture_output=True, text=True, timeout=300)
    assert p.returncode == 1
    assert "error: --plots: plotting failed" in p.stderr


def test_pip_installs_the_package(tmp_path):
    src = tmp_path / "hil"
    shutil.copytree(os.path.join(ROOT, "hil"), src, ignore=shutil.ignore_patterns("tests", "vm", "__pycache__"))
    target = tmp_path / "site"
    # offline when the venv has setuptools and wheel (hil/requirements.txt); else pip fetches the build backend
    offline = importlib.util.find_spec("wheel") is not None and importlib.util.find_spec("setuptools") is not None
    args = ["--no-build-isolation", "--no-index"] if offline else []
    p = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", *args, "--target", str(target), str(src)],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    assert (target / "lissom_hil" / "plot.py").is_file() and (target / "lissom_hil" / "gcode.py").is_file()
    env = dict(os.environ, PYTHONPATH=str(target))
    q = subprocess.run([sys.executable, "-c", "import lissom_hil.plot, lissom_hil.gcode, lissom_hil; "
                        "print(lissom_hil.__file__)"], env=env, capture_output=True, text=True, cwd=tmp_path)
    assert q.returncode == 0, q.stderr
    assert q.stdout.strip().startswith(str(target))
