"""SDK v3.3 HighCmd / HighState packing: sizes, offsets, round trips, rejection of bad packets."""

import math
import random
import struct

import pytest

from rbd_a1_driver import unitree_layout as ul


def test_sizes_match_sdk_v33():
    assert struct.calcsize(ul.HIGH_CMD_FORMAT) == 113
    assert struct.calcsize(ul.HIGH_STATE_FORMAT) == 265
    assert len(ul.HighCmd().pack()) == 113
    assert len(ul.HighState().pack()) == 265


def test_high_cmd_field_offsets():
    # Offsets computed from comm.h v3.3 with #pragma pack(1): header 10 B, mode at 10,
    # gaitType 11, speedLevel 12, footRaiseHeight 13, bodyHeight 17, postion 21, euler 29,
    # velocity 41, yawSpeed 49, LED 53, wirelessRemote 65, reserve 105, crc 109.
    cmd = ul.HighCmd()
    cmd.mode = 2
    cmd.gait_type = 1
    cmd.speed_level = 2
    cmd.body_height = -0.1
    cmd.euler = (0.1, 0.2, 0.3)
    cmd.velocity = (0.3, -0.12)
    cmd.yaw_speed = 0.5
    cmd.crc = 0xDEADBEEF
    raw = cmd.pack()
    assert raw[0] == ul.HIGHLEVEL
    assert raw[10] == 2 and raw[11] == 1 and raw[12] == 2
    assert struct.unpack_from("<f", raw, 17)[0] == pytest.approx(-0.1)
    assert struct.unpack_from("<3f", raw, 29) == pytest.approx((0.1, 0.2, 0.3))
    assert struct.unpack_from("<2f", raw, 41) == pytest.approx((0.3, -0.12))
    assert struct.unpack_from("<f", raw, 49)[0] == pytest.approx(0.5)
    assert struct.unpack_from("<I", raw, 109)[0] == 0xDEADBEEF


def test_high_state_field_offsets():
    s = ul.HighState()
    s.mode = 1
    s.quaternion = (0.5, 0.5, 0.5, 0.5)
    s.rpy = (0.1, -0.2, 3.0)
    s.position = (1.0, 2.0, 0.0)
    s.body_height = 0.2
    s.velocity = (0.3, 0.1, 0.0)
    s.yaw_speed = -0.4
    raw = s.pack()
    assert raw[10] == 1
    assert struct.unpack_from("<4f", raw, 15) == pytest.approx((0.5, 0.5, 0.5, 0.5))  # IMU starts at 15
    assert struct.unpack_from("<3f", raw, 55) == pytest.approx((0.1, -0.2, 3.0))  # rpy
    assert struct.unpack_from("<3f", raw, 73) == pytest.approx((1.0, 2.0, 0.0))  # position
    assert struct.unpack_from("<f", raw, 85)[0] == pytest.approx(0.2)  # bodyHeight
    assert struct.unpack_from("<3f", raw, 89) == pytest.approx((0.3, 0.1, 0.0))  # velocity
    assert struct.unpack_from("<f", raw, 101)[0] == pytest.approx(-0.4)  # yawSpeed


def test_round_trips():
    cmd = ul.HighCmd()
    cmd.mode, cmd.gait_type, cmd.velocity, cmd.yaw_speed = 2, 1, (0.25, 0.0), -0.5
    back = ul.decode_high_cmd(cmd.pack())
    assert back.mode == 2 and back.gait_type == 1
    assert back.velocity == pytest.approx((0.25, 0.0)) and back.yaw_speed == pytest.approx(-0.5)
    s = ul.HighState()
    s.position = (0.5, -0.25, 0.0)
    s.gyroscope = (0.0, 0.1, 0.2)
    back = ul.HighState.unpack(s.pack())
    assert back.position == pytest.approx(s.position) and back.gyroscope == pytest.approx(s.gyroscope)


@pytest.mark.parametrize("size", [0, 1, 112, 114, 143, 265])
def test_wrong_size_rejected(size):
    with pytest.raises(ul.LayoutError, match="113"):
        ul.decode_high_cmd(b"\x00" * size)


def _cmd_with(**fields):
    cmd = ul.HighCmd()
    cmd.mode, cmd.gait_type = 2, 1
    for k, v in fields.items():
        setattr(cmd, k, v)
    return cmd.pack()


@pytest.mark.parametrize(
    "fields, reason",
    [
        ({"mode": 14}, "unknown mode"),
        ({"mode": 255}, "unknown mode"),
        ({"gait_type": 7}, "unknown gaitType"),
        ({"speed_level": 9}, "unknown speedLevel"),
        ({"level_flag": 0xFF}, "levelFlag"),
        ({"velocity": (float("nan"), 0.0)}, "non-finite"),
        ({"yaw_speed": float("inf")}, "non-finite"),
        ({"euler": (0.0, float("-inf"), 0.0)}, "non-finite"),
        ({"body_height": float("nan")}, "non-finite"),
    ],
)
def test_bad_values_rejected(fields, reason):
    with pytest.raises(ul.LayoutError, match=reason):
        ul.decode_high_cmd(_cmd_with(**fields))


def test_random_garbage_rejected():
    rng = random.Random(7)
    for _ in range(2000):
        raw = bytes(rng.getrandbits(8) for _ in range(113))
        with pytest.raises(ul.LayoutError):
            ul.decode_high_cmd(raw)


def test_high_state_wrong_size_and_nan_rejected():
    with pytest.raises(ul.LayoutError):
        ul.HighState.unpack(b"\x00" * 256)  # the v3.2 size
    s = ul.HighState()
    s.position = (math.nan, 0.0, 0.0)
    with pytest.raises(ul.LayoutError):
        ul.HighState.unpack(s.pack())
