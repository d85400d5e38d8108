"""The oracle's own facts against the offsets INTERFACES.md §2 publishes, and its packer.

A typo in an oracle offset fails here twice: against the published number, and as a gap or
overlap in the packed struct (each member must start where the previous one ended).
"""

import struct

import pytest

from rbd_wire_oracle import unitree as vendor

# INTERFACES.md §2 "Correction — SDK 3.3.3 / 3.3.4": byte offsets computed from the 3.3.4 header.
PUBLISHED_V334 = {
    "imu": 10, "motorState": 63, "footForce": 823, "mode": 839, "progress": 840, "gaitType": 844,
    "position": 849, "bodyHeight": 861, "velocity": 865, "yawSpeed": 877, "footPosition2Body": 881,
    "wirelessRemote": 977, "crc": 1021,
}
# INTERFACES.md §2 table: packed sizes (computed) of v3.3 / v3.3.1, and the IMU's 53 B.
PUBLISHED_SIZES = {"HighCmd": 113, "HighState v3.3": 265, "HighState 3.3.4": 1025, "IMU": 53, "MotorState": 38}
# INTERFACES.md §2 remote: head u8[2], btn u16, then f32 lx, rx, ry, L2, ly, idle u8[16]: 24 of 40 B used.
PUBLISHED_REMOTE = {"head": 0, "btn": 2, "lx": 4, "rx": 8, "ry": 12, "L2": 16, "ly": 20, "idle": 24}


def test_published_offsets_334():
    for name, offset in PUBLISHED_V334.items():
        assert vendor.HIGH_STATE_V334[name].offset == offset, name


def test_published_sizes():
    assert vendor.HIGH_CMD.size == PUBLISHED_SIZES["HighCmd"]
    assert vendor.HIGH_STATE_V33.size == PUBLISHED_SIZES["HighState v3.3"]
    assert vendor.HIGH_STATE_V334.size == PUBLISHED_SIZES["HighState 3.3.4"]
    assert vendor.IMU.size == PUBLISHED_SIZES["IMU"]
    assert vendor.MOTOR_STATE.size == PUBLISHED_SIZES["MotorState"]
    # 20 motors of 38 B between motorState (63) and footForce (823)
    assert 63 + 20 * 38 == 823


def test_remote_layout():
    for name, offset in PUBLISHED_REMOTE.items():
        assert vendor.REMOTE[name].offset == offset, name
    assert vendor.REMOTE.size == 40
    assert vendor.BUTTON_BITS["L2"] == 5 and vendor.BUTTON_BITS["B"] == 9
    assert sorted(vendor.BUTTON_BITS.values()) == list(range(16))


@pytest.mark.parametrize(
    "layout",
    [vendor.HIGH_CMD, vendor.HIGH_STATE_V33, vendor.HIGH_STATE_V334, vendor.IMU, vendor.MOTOR_STATE,
     vendor.REMOTE, vendor.LED, vendor.CARTESIAN],
    ids=lambda layout: layout.name,
)
def test_members_are_contiguous(layout):
    assert vendor.gaps(layout) == []


def test_gaps_finds_a_typo():
    broken = vendor.Layout("broken", 9, [vendor.Field("a", "uint8_t", 1, 0), vendor.Field("b", "float", 1, 2),
                                         vendor.Field("c", "uint16_t", 1, 5)])
    assert vendor.gaps(broken) == [(1, 1), (6, -1), (7, 2)]


def test_nested_offsets():
    s = vendor.HIGH_STATE_V334
    assert s.offset("imu.rpy") == 50
    assert s.offset("motorState[0].q") == 64
    assert s.offset("motorState[11].tauEst") == 63 + 11 * 38 + 13
    assert vendor.HIGH_STATE_V33.offset("imu.quaternion") == 15
    assert vendor.HIGH_CMD.offset("led[2].g") == 53 + 2 * 3 + 1


def test_pack_writes_each_field_at_its_offset():
    raw = vendor.pack(vendor.HIGH_STATE_V334, {
        "mode": 2,
        "position": (1.0, -2.0, 0.5),
        "imu": {"quaternion": (1.0, 0.0, 0.0, 0.0)},
        "motorState": [{"q": 0.1 * i} for i in range(12)],
        "footForce": (10, -20, 30, 40),
        "wirelessRemote": vendor.remote(["L2", "B"]),
    })
    assert len(raw) == 1025
    assert raw[839] == 2
    assert struct.unpack_from("<3f", raw, 849) == (1.0, -2.0, 0.5)
    assert struct.unpack_from("<f", raw, 10)[0] == 1.0
    assert struct.unpack_from("<f", raw, 63 + 5 * 38 + 1)[0] == pytest.approx(0.5)
    assert struct.unpack_from("<4h", raw, 823) == (10, -20, 30, 40)
    assert struct.unpack_from("<H", raw, 977 + 2)[0] == (1 << 5) | (1 << 9)
    back = vendor.unpack(vendor.HIGH_STATE_V334, raw)
    assert back["motorState"][5]["q"] == pytest.approx(0.5) and back["motorState"][12]["q"] == 0.0
    assert vendor.buttons_held(back["wirelessRemote"]) == ["L2", "B"]


def test_pack_rejects_wrong_counts_and_unpack_wrong_sizes():
    with pytest.raises(ValueError):
        vendor.pack(vendor.HIGH_CMD, {"velocity": (0.1, 0.2, 0.3)})
    with pytest.raises(ValueError, match="113"):
        vendor.unpack(vendor.HIGH_CMD, b"\x00" * 112)


def test_joint_names_in_motor_order():
    assert vendor.JOINT_NAMES[:4] == ("FR_hip_joint", "FR_thigh_joint", "FR_calf_joint", "FL_hip_joint")
    assert vendor.JOINT_NAMES[-1] == "RL_calf_joint" and len(vendor.JOINT_NAMES) == 12
