"""hil/lissom.eds against the firmware's object dictionary.

The firmware is compiled on the fly (tests/py/co_od_dump.c + firmware sources) and lists every object the
node serves for the EDS configuration (3 axes). The EDS must load with the venv's canopen package
(canopen.import_od) and describe exactly those objects: same data type, access, PDO mapping flag, range and
the default the node boots with ($NODEID resolved); nothing missing, nothing extra. Finally the committed
file must be what scripts/gen_eds.py produces today.
"""
import os
import sys

import canopen
import pytest

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EDS = os.path.join(REPO, "hil", "lissom.eds")
sys.path.insert(0, os.path.join(REPO, "scripts"))
import gen_eds  # noqa: E402

NODE_ID = 5


@pytest.fixture(scope="module")
def dump_tool(tmp_path_factory):
    return gen_eds.build_dump_tool(str(tmp_path_factory.mktemp("co_od_dump")))


@pytest.fixture(scope="module")
def served(dump_tool):
    return gen_eds.dump(dump_tool, NODE_ID, gen_eds.EDS_AXES)


@pytest.fixture(scope="module")
def od():
    return canopen.import_od(EDS, node_id=NODE_ID)


def eds_variable(od, index, sub):
    obj = od[index]
    if isinstance(obj, canopen.objectdictionary.ODVariable):
        assert sub == 0, f"0x{index:04X} is a plain variable in the EDS, the node serves sub {sub}"
        return obj
    return obj[sub]


def test_eds_loads(od):
    assert od.device_information.nr_of_RXPDO == 4
    assert od.device_information.nr_of_TXPDO == 4
    assert od.device_information.product_number == 0x4C534D31
    for index in (0x1000, 0x1001, 0x1017, 0x1018, 0x6040, 0x6041, 0x6060, 0x6061, 0x6064, 0x607A, 0x6081,
                  0x6083, 0x6084, 0x6086, 0x60F4, 0x5010):
        assert index in od


def test_every_served_object_is_in_the_eds(od, served):
    objects = served["objects"]
    assert len(objects) > 200
    for o in objects:
        where = f"0x{o['index']:04X}:{o['sub']}"
        assert o["index"] in od, f"{where} missing from the EDS"
        var = eds_variable(od, o["index"], o["sub"])
        assert var.data_type == o["type"], f"{where}: EDS type 0x{var.data_type:X}, node 0x{o['type']:X}"
        assert var.access_type == o["access"], f"{where}: EDS {var.access_type}, node {o['access']}"
        assert var.pdo_mappable == o["pdo"], f"{where}: EDS PDO mapping {var.pdo_mappable}"
        if "default" in o:
            assert var.default == o["default"], f"{where}: EDS default {var.default!r}, node {o['default']!r}"
        else:
            assert var.default is None, f"{where}: write-only object with a default in the EDS"
        if "min" in o:
            assert (var.min, var.max) == (o["min"], o["max"]), f"{where}: EDS range {var.min}..{var.max}"


def test_nothing_extra_in_the_eds(od, served):
    have = {(o["index"], o["sub"]) for o in served["objects"]}
    for index in od.keys():
        if not isinstance(index, int):
            continue
        obj = od[index]
        if isinstance(obj, canopen.objectdictionary.ODVariable):
            assert (index, 0) in have, f"EDS lists 0x{index:04X}, the node does not serve it"
        else:
            for sub in obj.subindices:
                assert (index, sub) in have, f"EDS lists 0x{index:04X}:{sub}, the node does not serve it"


def test_cob_ids_follow_the_node_id(tmp_path):
    od7 = canopen.import_od(EDS, node_id=7)
    assert od7[0x1014].default == 0x87
    assert od7[0x1200][1].default == 0x607
    assert od7[0x1200][2].default == 0x587
    assert od7[0x1800][1].default == 0x40000187
    assert od7[0x1400][1].default == 0x207


def test_eds_is_up_to_date(dump_tool):
    d1 = gen_eds.dump(dump_tool, 1, gen_eds.EDS_AXES)
    d2 = gen_eds.dump(dump_tool, 2, gen_eds.EDS_AXES)
    want = gen_eds.render(d1, d2)
    with open(EDS, newline="") as f:
        have = f.read().replace("\r\n", "\n")
    assert have == want, "hil/lissom.eds is stale: run scripts/gen_eds.py"
