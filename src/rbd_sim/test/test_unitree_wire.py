"""The mock A1's own wire description against the vendor's offsets (rbd_wire_oracle), both SDK layouts.

The mock imports nothing of rbd_a1_driver; these tests hold its packets to the vendor facts:
every member the mock writes must read back through the vendor table at the vendor offset.
"""

import ast
import math
import os

import pytest

from rbd_sim import unitree_wire as wire
from rbd_sim.a1_model import A1Config, A1Model
from rbd_wire_oracle import unitree as vendor

PKG = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
LAYOUTS = ["3.3", "3.3.4"]


def test_sizes_are_the_vendors():
    assert wire.HIGH_CMD.size == vendor.HIGH_CMD.size
    assert {k: s.size for k, s in wire.HIGH_STATE.items()} == {k: s.size for k, s in vendor.HIGH_STATES.items()}
    assert wire.REMOTE.size == vendor.REMOTE.size and wire.MOTOR_STATE.size == vendor.MOTOR_STATE.size


@pytest.mark.parametrize("layout", LAYOUTS)
def test_member_offsets_are_the_vendors(layout):
    ours = {name: offset for name, _, _, offset, _ in wire.HIGH_STATE[layout].members}
    theirs = {f.name: f.offset for f in vendor.HIGH_STATES[layout].fields}
    assert ours == theirs


def walked_model(seconds=1.3):
    m = A1Model(A1Config(drift_per_180=0.0))
    packet = vendor.pack(vendor.HIGH_CMD, {"mode": vendor.MODE_VELOCITY_WALK, "gaitType": vendor.GAIT_TROT,
                                           "velocity": (0.3, 0.05), "yawSpeed": 0.2})
    t = 0.0
    while t < seconds:
        m.receive(packet, t)
        t += 0.004
        m.step(t)
        m.high_state()  # the node builds one per cycle: the legs advance with it
    m.press(("L2", "B"), t, 1.0)
    return m


def close(a, b):
    """Equal up to float32 rounding, element by element (nested dicts/sequences)."""
    if isinstance(a, dict):
        return all(close(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple, bytes)):
        a, b = list(bytearray(a) if isinstance(a, bytes) else a), list(bytearray(b) if isinstance(b, bytes) else b)
        return len(a) == len(b) and all(close(x, y) for x, y in zip(a, b))
    return math.isclose(a, b, rel_tol=1e-6, abs_tol=1e-6)


@pytest.mark.parametrize("layout", LAYOUTS)
def test_mock_high_state_reads_back_through_the_vendor_table(layout):
    m = walked_model()
    values = m.high_state()
    got = vendor.unpack(vendor.HIGH_STATES[layout], wire.encode_high_state(layout, values))
    members = [f.name for f in vendor.HIGH_STATES[layout].fields]
    checked = 0
    for name, value in values.items():
        if name not in members:
            assert layout == "3.3" and name == "motorState"  # the v3.3 struct has no motors
            continue
        if name == "motorState":
            got_motors = got[name][:12]
            assert all(close(v, g) for v, g in zip(value, got_motors)), name
            assert all(mo["q"] == 0.0 for mo in got[name][12:])  # motors 12..19 unused
        else:
            assert close(value, got[name]), name
        checked += 1
    assert checked == len(values) - (layout == "3.3")
    assert vendor.buttons_held(got["wirelessRemote"]) == ["L2", "B"]
    assert got["footForce"] == tuple(values["footForce"]) and got["crc"] == 0


def test_mock_decodes_vendor_high_cmd():
    raw = vendor.pack(vendor.HIGH_CMD, {"mode": 1, "gaitType": 1, "speedLevel": 1, "footRaiseHeight": 0.02,
                                        "bodyHeight": -0.1, "postion": (1.0, 2.0), "euler": (0.1, 0.2, 0.3),
                                        "velocity": (0.4, -0.2), "yawSpeed": 0.6,
                                        "led": [{"r": 1, "g": 2, "b": 3}] * 4})
    cmd = wire.decode_high_cmd(raw)
    expected = vendor.unpack(vendor.HIGH_CMD, raw)
    for name, value in expected.items():
        assert close(value, getattr(cmd, name)), name


@pytest.mark.parametrize(
    "fields, reason",
    [({"mode": 14}, "unknown mode"), ({"gaitType": 4}, "unknown gaitType"), ({"speedLevel": 3}, "speedLevel"),
     ({"levelFlag": 0xFF}, "levelFlag"), ({"velocity": (math.nan, 0.0)}, "non-finite"),
     ({"euler": (0.0, math.inf, 0.0)}, "non-finite")],
)
def test_mock_rejects_what_the_robot_would(fields, reason):
    with pytest.raises(wire.WireError, match=reason):
        wire.decode_high_cmd(vendor.pack(vendor.HIGH_CMD, dict({"mode": 2}, **fields)))
    with pytest.raises(wire.WireError, match="113"):
        wire.decode_high_cmd(b"\x00" * 112)


def test_remote_bytes_are_the_vendors():
    for name in vendor.BUTTON_BITS:
        assert wire.remote_bytes([name]) == vendor.remote([name])
    assert wire.remote_bytes(["L2", "B"]) == vendor.remote(["L2", "B"])


def test_mock_imports_nothing_of_the_driver():
    sources = [os.path.join(PKG, "nodes", "mock_a1")]
    src_dir = os.path.join(PKG, "src", "rbd_sim")
    sources += [os.path.join(src_dir, f) for f in os.listdir(src_dir) if f.endswith(".py")]
    for path in sources:
        with open(path) as fh:
            tree = ast.parse(fh.read())
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [node.module or ""]
            assert not any(n.split(".")[0] == "rbd_a1_driver" for n in names), path
