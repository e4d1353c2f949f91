"""Shared pytest fixtures: where lissom-sim is (env LISSOM_SIM, else build/bin/lissom-sim)."""
import json
import os
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


@pytest.fixture(scope="session")
def sim():
    path = os.environ.get("LISSOM_SIM") or os.path.join(ROOT, "build", "bin", "lissom-sim")
    if not os.access(path, os.X_OK):
        pytest.fail(f"lissom-sim not built at {path} (run scripts/build.sh)")

    def run(*args, ok=True):
        p = subprocess.run([path, *map(str, args)], capture_output=True, text=True, timeout=120)
        if ok:
            assert p.returncode == 0, f"lissom-sim {' '.join(map(str, args))} failed: {p.stderr}"
            return json.loads(p.stdout) if "--json" in args else p.stdout
        return p

    return run
