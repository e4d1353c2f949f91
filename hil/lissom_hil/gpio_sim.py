"""A simulated GPIO chip (the kernel's gpio-sim, configured through configfs) for the E-stop and the outputs.

    chip = GpioSim("lissom-hil", n_lines=8).create()   # needs root, configfs and the gpio-sim module
    chip.name                      # "gpiochipN": pass it to lissom-node --gpio-chip
    chip.pull(0, "pull-up")        # what the "outside world" drives on input line 0
    chip.value(1)                  # what the node drives on output line 1 (0/1)
    chip.remove()

In the HIL VM the module is built by hil/vm/setup_vm.sh (Debian's kernel lacks CONFIG_GPIO_SIM).
"""
import os
import time

CONFIGFS = "/sys/kernel/config/gpio-sim"


def available():
    return os.path.isdir(CONFIGFS) and os.access(CONFIGFS, os.W_OK)


def _write(path, text):
    with open(path, "w") as f:
        f.write(text)


def _read(path):
    with open(path) as f:
        return f.read().strip()


class GpioSim:
    def __init__(self, label="lissom-hil", n_lines=8, names=None):
        self.label = label
        self.n_lines = n_lines
        self.names = names or {}
        self.dir = os.path.join(CONFIGFS, "%s-%d" % (label, os.getpid()))
        self.name = None
        self.sysfs = None

    def create(self):
        if not available():
            raise RuntimeError("gpio-sim is not available (configfs %s)" % CONFIGFS)
        bank = os.path.join(self.dir, "bank0")
        os.mkdir(self.dir)
        os.mkdir(bank)
        _write(os.path.join(bank, "num_lines"), str(self.n_lines))
        _write(os.path.join(bank, "label"), self.label)
        for k, nm in self.names.items():
            os.mkdir(os.path.join(bank, "line%d" % k))
            _write(os.path.join(bank, "line%d" % k, "name"), nm)
        _write(os.path.join(self.dir, "live"), "1")
        self.name = _read(os.path.join(bank, "chip_name"))
        dev = _read(os.path.join(self.dir, "dev_name"))
        self.sysfs = "/sys/devices/platform/%s/%s" % (dev, self.name)
        t_end = time.monotonic() + 10.0  # the sysfs attributes appear shortly after "live" (a bound, not a delay)
        while not os.path.exists(os.path.join(self.sysfs, "sim_gpio0", "value")) and time.monotonic() < t_end:
            time.sleep(0.01)
        return self

    def pull(self, line, how):
        """how: "pull-up" or "pull-down" (the level an external circuit puts on the line)."""
        _write(os.path.join(self.sysfs, "sim_gpio%d" % line, "pull"), how)

    def value(self, line):
        return int(_read(os.path.join(self.sysfs, "sim_gpio%d" % line, "value")))

    def remove(self):
        if not os.path.isdir(self.dir):
            return
        try:
            _write(os.path.join(self.dir, "live"), "0")
        except OSError:
            pass
        bank = os.path.join(self.dir, "bank0")
        for k in self.names:
            try:
                os.rmdir(os.path.join(bank, "line%d" % k))
            except OSError:
                pass
        for d in (bank, self.dir):
            try:
                os.rmdir(d)
            except OSError:
                pass
