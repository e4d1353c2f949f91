#!/usr/bin/env python3
"""Generate hil/lissom.eds (CiA 306 electronic data sheet) from the object dictionary the firmware serves.

The firmware's table (firmware/canopen/canopen.c) is the single source of truth: tests/py/co_od_dump.c is compiled
against the firmware sources and prints every object the node serves, with its type, access, PDO flag, range
and the value it has after boot. This script adds names and writes the EDS; tests/py/test_eds.py checks
that the committed EDS loads with canopen.import_od and matches the firmware object by object.

    scripts/gen_eds.py [--axes 3] [-o hil/lissom.eds]

Node-id dependent defaults (COB-IDs) are written as $NODEID+0x... : the dump is taken for node ids 1 and 2
and a value that moves with the node id is expressed relative to it.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# the CANopen component and what it uses (paths under firmware/)
FIRMWARE_SOURCES = ["canopen/can.c", "canopen/co_od.c", "canopen/co_sdo.c", "canopen/co_nmt.c", "canopen/co_emcy.c",
                    "canopen/co_pdo.c", "canopen/co_path.c", "canopen/cia402.c", "canopen/canopen.c", "base/status.c"]
FIRMWARE_INCLUDES = ["canopen", "base"]
EDS_AXES = 3  # the configuration the committed EDS describes (X, Y, Z)

# Object names. Per-axis objects (index + 0x800 k) get "Axis k " in front for k > 0.
NAMES = {
    0x1000: ("Device type", None),
    0x1001: ("Error register", None),
    0x1003: ("Pre-defined error field", {0: "Number of errors", "n": "Standard error field {n}"}),
    0x1005: ("COB-ID SYNC message", None),
    0x1006: ("Communication cycle period", None),
    0x1008: ("Manufacturer device name", None),
    0x1014: ("COB-ID EMCY", None),
    0x1016: ("Consumer heartbeat time", {0: "Highest sub-index supported", "n": "Consumer heartbeat time {n}"}),
    0x1017: ("Producer heartbeat time", None),
    0x1018: ("Identity object", {0: "Highest sub-index supported", 1: "Vendor-ID", 2: "Product code",
                                 3: "Revision number", 4: "Serial number"}),
    0x1029: ("Error behavior object", {0: "Highest sub-index supported", 1: "Communication error"}),
    0x1200: ("SDO server parameter", {0: "Highest sub-index supported", 1: "COB-ID client to server",
                                      2: "COB-ID server to client"}),
    0x1400: ("RPDO communication parameter", {0: "Highest sub-index supported", 1: "COB-ID used by RPDO",
                                              2: "Transmission type"}),
    0x1600: ("RPDO mapping parameter", {0: "Number of mapped objects", "n": "Mapped object {n}"}),
    0x1800: ("TPDO communication parameter", {0: "Highest sub-index supported", 1: "COB-ID used by TPDO",
                                              2: "Transmission type", 3: "Inhibit time", 5: "Event timer"}),
    0x1A00: ("TPDO mapping parameter", {0: "Number of mapped objects", "n": "Mapped object {n}"}),
    0x2001: ("Position units per mm", None),
    0x2060: ("Profile jerk", None),
    0x2061: ("Profile snap", None),
    0x5000: ("Path command", None),
    0x5001: ("Path feed override", None),
    0x5002: ("Path state", None),
    0x5003: ("Path buffer free slots", None),
    0x5004: ("Path last accepted sequence", None),
    0x5005: ("Path active sequence", None),
    0x5006: ("Path feed actual", None),
    0x5007: ("Path buffer capacity", None),
    0x5008: ("Path counters", {0: "Highest sub-index supported", 1: "Duplicate blocks", 2: "Sequence gaps",
                               3: "Refused blocks", 4: "Underruns"}),
    0x5010: ("Path block", None),
    0x5020: ("Machine status", None),
    0x5F00: ("Tick statistics", {0: "Highest sub-index supported", 1: "Ticks", 2: "Overruns",
                                 3: "Worst tick instructions", 4: "Background load", 5: "Late wake-ups",
                                 6: "Clock", 7: "Path underruns", 8: "Path set-points ahead minimum",
                                 9: "SDO requests waiting maximum", 10: "SDO requests refused"}),
    0x6007: ("Abort connection option code", None),
    0x603F: ("Error code", None),
    0x6040: ("Controlword", None),
    0x6041: ("Statusword", None),
    0x605A: ("Quick stop option code", None),
    0x6060: ("Modes of operation", None),
    0x6061: ("Modes of operation display", None),
    0x6062: ("Position demand value", None),
    0x6064: ("Position actual value", None),
    0x6065: ("Following error window", None),
    0x6066: ("Following error time out", None),
    0x6067: ("Position window", None),
    0x606C: ("Velocity actual value", None),
    0x607A: ("Target position", None),
    0x6081: ("Profile velocity", None),
    0x6083: ("Profile acceleration", None),
    0x6084: ("Profile deceleration", None),
    0x6085: ("Quick stop deceleration", None),
    0x6086: ("Motion profile type", None),
    0x60C2: ("Interpolation time period", {0: "Highest sub-index supported", 1: "Interpolation time period value",
                                          2: "Interpolation time index"}),
    0x60F4: ("Following error actual value", None),
    0x6502: ("Supported drive modes", None),
}
ARRAYS = {0x1003, 0x1016, 0x1029, 0x5008}
UNITS = {0x2060: "counts/s^3", 0x2061: "counts/s^4", 0x6081: "counts/s", 0x6083: "counts/s^2",
         0x6084: "counts/s^2", 0x6085: "counts/s^2", 0x607A: "counts", 0x6062: "counts", 0x6064: "counts",
         0x60F4: "counts", 0x6065: "counts", 0x6067: "counts", 0x606C: "counts/s", 0x6066: "ms", 0x1017: "ms",
         0x1006: "us", 0x5006: "um/s", 0x5001: "%", 0x2001: "counts/mm"}
GROUP_AXIS, GROUP_RPDO, GROUP_TPDO = 1, 2, 3


def build_dump_tool(workdir, cc=None):
    """Compile tests/py/co_od_dump.c with the firmware sources; return the executable's path."""
    cc = cc or os.environ.get("CC") or shutil.which("cc") or "gcc"
    exe = os.path.join(workdir, "co_od_dump")
    fw = os.path.join(REPO, "firmware")
    cmd = [cc, "-std=c11", "-O1", "-Wall", "-Wextra", "-Werror"]
    cmd += [a for d in FIRMWARE_INCLUDES for a in ("-I", os.path.join(fw, d))]
    cmd += [os.path.join(REPO, "tests", "py", "co_od_dump.c")] + [os.path.join(fw, s) for s in FIRMWARE_SOURCES]
    cmd += ["-o", exe]
    subprocess.run(cmd, check=True)
    return exe


def dump(exe, node_id, n_axes):
    out = subprocess.run([exe, str(node_id), str(n_axes)], check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def base_index(o):
    if o["group"] == GROUP_AXIS:
        return o["index"] - 0x800 * o["instance"]
    if o["group"] in (GROUP_RPDO, GROUP_TPDO):
        return o["index"] - o["instance"]
    return o["index"]


def object_name(o):
    name, _ = NAMES[base_index(o)]
    if o["group"] == GROUP_AXIS and o["instance"] > 0:
        return f"Axis {o['instance']} {name[0].lower()}{name[1:]}"
    if o["group"] in (GROUP_RPDO, GROUP_TPDO):
        return f"{name} {o['instance'] + 1}"
    return name


def sub_name(o):
    _, subs = NAMES[base_index(o)]
    if subs is None:
        return object_name(o)
    if o["sub"] in subs:
        return subs[o["sub"]]
    return subs["n"].format(n=o["sub"])


def fmt_default(o, o2):
    """DefaultValue text; o2 is the same object dumped for node id + 1."""
    t, v = o["type"], o["default"]
    if t == 0x09:
        return v
    if v != o2["default"]:
        delta = o2["default"] - v
        if delta != 1:
            raise ValueError(f"0x{o['index']:04X}:{o['sub']} moves by {delta} per node id")
        return f"$NODEID+0x{v - o['node_id']:X}"
    if t in (0x02, 0x03, 0x04, 0x15):
        return str(v)
    return f"0x{v:X}"


def var_lines(o, o2, name):
    lines = [f"ParameterName={name}", "ObjectType=0x7", f"DataType=0x{o['type']:04X}", f"AccessType={o['access']}"]
    if "default" in o:
        lines.append(f"DefaultValue={fmt_default(o, o2)}")
    if "min" in o:
        signed = o["type"] in (0x02, 0x03, 0x04, 0x15)
        lines.append(f"LowLimit={o['min']}" if signed else f"LowLimit=0x{o['min']:X}")
        lines.append(f"HighLimit={o['max']}" if signed else f"HighLimit=0x{o['max']:X}")
    lines.append(f"PDOMapping={1 if o['pdo'] else 0}")
    unit = UNITS.get(base_index(o))
    if unit:
        lines.append(f"Unit={unit}")
    return lines


def render(d1, d2):
    """The EDS text for dump d1 (node id n) and d2 (node id n + 1)."""
    objs = {}
    twin = {(o["index"], o["sub"]): o for o in d2["objects"]}
    for o in d1["objects"]:
        o["node_id"] = d1["node_id"]
        objs.setdefault(o["index"], []).append(o)
    for subs in objs.values():
        subs.sort(key=lambda o: o["sub"])
    indices = sorted(objs)
    mandatory = [i for i in indices if i in (0x1000, 0x1001, 0x1018)]
    manufacturer = [i for i in indices if 0x2000 <= i <= 0x5FFF]
    optional = [i for i in indices if i not in mandatory and i not in manufacturer]

    out = []

    def section(name, lines):
        out.append(f"[{name}]")
        out.extend(lines)
        out.append("")

    section("FileInfo", [
        "FileName=lissom.eds", "FileVersion=1", "FileRevision=0", "EDSVersion=4.0",
        f"Description=Lissom motion controller: CiA 301 node with {d1['n_axes']} CiA 402 axes and coordinated path motion",
        "CreationTime=12:00PM", "CreationDate=01-01-2025", "CreatedBy=scripts/gen_eds.py",
        "ModificationTime=12:00PM", "ModificationDate=01-01-2025", "ModifiedBy=scripts/gen_eds.py"])
    section("DeviceInfo", [
        "VendorName=Lissom", f"VendorNumber=0x{d1['vendor_id']:X}", f"ProductName={d1['device_name']}",
        f"ProductNumber=0x{d1['product_code']:X}", f"RevisionNumber=0x{d1['revision']:X}", "OrderCode=",
        "BaudRate_10=0", "BaudRate_20=0", "BaudRate_50=0", "BaudRate_125=1", "BaudRate_250=1", "BaudRate_500=1",
        "BaudRate_800=0", "BaudRate_1000=1", "SimpleBootUpMaster=0", "SimpleBootUpSlave=1", "Granularity=8",
        "DynamicChannelsSupported=0", "GroupMessaging=0", f"NrOfRXPDO={d1['n_rpdo']}",
        f"NrOfTXPDO={d1['n_tpdo']}", "LSS_Supported=0"])
    section("DummyUsage", [f"Dummy000{i}=0" for i in range(1, 8)])
    comments = [
        f"Generated from the firmware's object table for {d1['n_axes']} axes (scripts/gen_eds.py --axes N for others).",
        "Axis k (0-based) answers CiA 402 objects at index + 0x800*k and its manufacturer objects 0x2001-0x2061 too.",
        "Positions are integer counts; 0x2001 gives counts per mm (default 1000: 1 count = 1 um).",
        "Modes: 1 Profile Position, 8 Cyclic Synchronous Position, -1 coordinated path (manufacturer).",
        "0x6086 motion profile type: 0 linear ramp (trapezoidal acceleration), 1 sin^2 ramp.",
        "Path blocks: write 0x5010 (DOMAIN) by SDO; layout and flow control in docs/canopen.md.",
    ]
    section("Comments", [f"Lines={len(comments)}"] + [f"Line{i + 1}={c}" for i, c in enumerate(comments)])
    for title, lst in (("MandatoryObjects", mandatory), ("OptionalObjects", optional),
                       ("ManufacturerObjects", manufacturer)):
        section(title, [f"SupportedObjects={len(lst)}"] + [f"{i + 1}=0x{idx:04X}" for i, idx in enumerate(lst)])
    for idx in indices:
        subs = objs[idx]
        if len(subs) == 1 and subs[0]["sub"] == 0 and base_index(subs[0]) not in ARRAYS and \
                NAMES[base_index(subs[0])][1] is None:
            o = subs[0]
            section(f"{idx:04X}", var_lines(o, twin[(idx, 0)], object_name(o)))
            continue
        otype = "0x8" if base_index(subs[0]) in ARRAYS else "0x9"
        section(f"{idx:04X}", [f"ParameterName={object_name(subs[0])}", f"ObjectType={otype}",
                               f"SubNumber={len(subs)}"])
        for o in subs:
            section(f"{idx:04X}sub{o['sub']:X}", var_lines(o, twin[(idx, o['sub'])], sub_name(o)))
    return "\n".join(out)


def generate(n_axes=EDS_AXES, node_id=1):
    with tempfile.TemporaryDirectory() as tmp:
        exe = build_dump_tool(tmp)
        d1 = dump(exe, node_id, n_axes)
        d2 = dump(exe, node_id + 1, n_axes)
    return render(d1, d2)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--axes", type=int, default=EDS_AXES)
    ap.add_argument("-o", "--output", default=os.path.join(REPO, "hil", "lissom.eds"))
    args = ap.parse_args()
    text = generate(args.axes)
    with open(args.output, "w", newline="\r\n") as f:
        f.write(text)
    print(f"wrote {args.output}", file=sys.stderr)


if __name__ == "__main__":
    main()
