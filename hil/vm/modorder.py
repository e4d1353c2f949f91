#!/usr/bin/env python3
"""List kernel modules with their dependencies, dependencies first (the order insmod needs).

usage: modorder.py MODDIR NAME...
MODDIR holds modules.dep; NAME is a module name without .ko ('-' and '_' are the same).
Prints one path per line, relative to MODDIR.
"""
import os
import sys


def load_deps(moddir):
    deps, path_of = {}, {}
    with open(os.path.join(moddir, "modules.dep")) as f:
        for line in f:
            mod, _, rest = line.strip().partition(":")
            if not mod:
                continue
            deps[mod] = rest.split()
            path_of[os.path.basename(mod)[: -len(".ko")].replace("-", "_")] = mod
    return deps, path_of


def main(moddir, names):
    deps, path_of = load_deps(moddir)
    order = []

    def add(mod):
        if mod in order:
            return
        for d in deps.get(mod, []):
            add(d)
        order.append(mod)

    for name in names:
        mod = path_of.get(name.replace("-", "_"))
        if mod is None:
            sys.exit("modorder: no module %s in %s" % (name, moddir))
        add(mod)
    print("\n".join(order))


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2:])
