"""Start and stop a local lissom-node daemon (the device under test on the vcan rig).

    proc = NodeProcess(binary, iface="vcan0", node_id=1, trace="/tmp/t.bin", extra=["--axes", "3"])
    proc.start()          # waits for the daemon's "ready" line
    ...
    proc.stop()           # SIGTERM: the daemon quick-stops, waits for standstill, exits 0

The binary is found by `find_node_binary()`: $LISSOM_NODE, else build/bin/lissom-node in the repository.
"""
import os
import signal
import subprocess
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def find_node_binary():
    path = os.environ.get("LISSOM_NODE") or os.path.join(ROOT, "build", "bin", "lissom-node")
    if not os.access(path, os.X_OK):
        raise FileNotFoundError("lissom-node not built at %s (run scripts/build.sh or set LISSOM_NODE)" % path)
    return path


class NodeProcess:
    def __init__(self, binary, iface="vcan0", node_id=1, trace=None, extra=(), log_path=None):
        self.binary = binary
        self.iface = iface
        self.node_id = node_id
        self.trace = trace
        self.extra = list(extra)
        self.log_path = log_path
        self.proc = None
        self.ready_line = None
        self.returncode = None
        self._log = None

    def argv(self):
        a = [self.binary, "--iface", self.iface, "--node-id", str(self.node_id), "--stats"]
        if self.trace:
            a += ["--trace", self.trace]
        return a + self.extra

    def start(self, timeout=20.0):
        if self.proc is not None:
            raise RuntimeError("lissom-node already running")
        self._log = open(self.log_path, "w") if self.log_path else subprocess.DEVNULL
        self.proc = subprocess.Popen(self.argv(), stdout=subprocess.PIPE, stderr=self._log, text=True)
        t_end = time.monotonic() + timeout
        line = self.proc.stdout.readline()  # blocks until "ready" or exit
        if not line.startswith("lissom-node: ready") or time.monotonic() > t_end:
            rc = self.proc.wait(timeout=5)
            self.proc = None
            raise RuntimeError("lissom-node did not start (exit %s): %s; see %s" % (rc, line.strip(), self.log_path))
        self.ready_line = line.strip()
        return self

    def running(self):
        return self.proc is not None and self.proc.poll() is None

    def stop(self, timeout=15.0):
        """SIGTERM and wait; returns the exit code (None if it was not running)."""
        if self.proc is None:
            return self.returncode
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.returncode = self.proc.returncode
        try:
            self.proc.stdout.close()
        except Exception:
            pass
        self.proc = None
        if self._log not in (None, subprocess.DEVNULL):
            self._log.close()
        self._log = None
        return self.returncode

    def log_text(self):
        if self.log_path and os.path.exists(self.log_path):
            with open(self.log_path) as f:
                return f.read()
        return ""
