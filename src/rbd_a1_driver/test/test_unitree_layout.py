"""The driver's HighCmd / HighState packing against the vendor's offsets (rbd_wire_oracle), both SDK layouts.

The truth is the oracle's table of vendor facts: packets assembled from it byte by byte must
decode in the driver, and the driver's packets must read back through it field by field.
"""

import math
import random

import pytest

from rbd_a1_driver import unitree_layout as ul
from rbd_wire_oracle import unitree as vendor


def test_sizes_match_the_vendor_tables():
    assert len(ul.HighCmd().pack()) == vendor.HIGH_CMD.size
    assert len(ul.HighState().pack()) == vendor.HIGH_STATE_V33.size
    assert len(ul.HighState334().pack()) == vendor.HIGH_STATE_V334.size
    assert ul.HIGH_STATE_SIZES == {"3.3": vendor.HIGH_STATE_V33.size, "3.3.4": vendor.HIGH_STATE_V334.size}
    assert ul.JOINT_NAMES == vendor.JOINT_NAMES
    assert ul.REMOTE_BUTTONS == vendor.BUTTON_BITS


def test_high_cmd_reads_back_through_the_vendor_table():
    cmd = ul.HighCmd()
    cmd.mode = 2
    cmd.gait_type = 1
    cmd.speed_level = 2
    cmd.foot_raise_height = 0.01
    cmd.body_height = -0.1
    cmd.position = (1.5, -2.5)
    cmd.euler = (0.1, 0.2, 0.3)
    cmd.velocity = (0.3, -0.12)
    cmd.yaw_speed = 0.5
    cmd.led = bytes(range(1, 13))
    cmd.crc = 0xDEADBEEF
    v = vendor.unpack(vendor.HIGH_CMD, cmd.pack())
    assert v["levelFlag"] == vendor.HIGHLEVEL
    assert (v["mode"], v["gaitType"], v["speedLevel"]) == (2, 1, 2)
    assert v["footRaiseHeight"] == pytest.approx(0.01) and v["bodyHeight"] == pytest.approx(-0.1)
    assert v["postion"] == pytest.approx((1.5, -2.5))
    assert v["euler"] == pytest.approx((0.1, 0.2, 0.3))
    assert v["velocity"] == pytest.approx((0.3, -0.12))
    assert v["yawSpeed"] == pytest.approx(0.5)
    assert [(led["r"], led["g"], led["b"]) for led in v["led"]] == [(1, 2, 3), (4, 5, 6), (7, 8, 9), (10, 11, 12)]
    assert v["crc"] == 0xDEADBEEF and v["wirelessRemote"] == (0,) * 40


def test_vendor_high_cmd_decodes():
    raw = vendor.pack(vendor.HIGH_CMD, {"mode": 1, "euler": (0.1, -0.2, 0.05), "bodyHeight": -0.05,
                                        "velocity": (0.2, 0.1), "yawSpeed": -0.3})
    cmd = ul.decode_high_cmd(raw)
    assert cmd.mode == 1 and cmd.euler == pytest.approx((0.1, -0.2, 0.05))
    assert cmd.body_height == pytest.approx(-0.05) and cmd.velocity == pytest.approx((0.2, 0.1))
    assert cmd.yaw_speed == pytest.approx(-0.3)


def vendor_state(layout_name, **extra):
    """A HighState of an SDK layout assembled from the vendor table."""
    values = {
        "mode": 2,
        "gaitType": 1,
        "imu": {"quaternion": (0.5, 0.5, -0.5, 0.5), "gyroscope": (0.01, -0.02, 0.3),
                "accelerometer": (0.1, -0.2, 9.7), "rpy": (0.05, -0.04, 1.2)},
        "position": (1.25, -0.75, 0.0),
        "bodyHeight": 0.27,
        "velocity": (0.3, -0.1, 0.0),
        "yawSpeed": 0.25,
        "footForce": (11, -22, 33, 44),
        "wirelessRemote": vendor.remote(["L2", "B"], lx=0.5),
    }
    values.update(extra)
    return vendor.pack(vendor.HIGH_STATES[layout_name], values)


@pytest.mark.parametrize("layout_name", ["3.3", "3.3.4"])
def test_vendor_high_state_decodes_in_auto_mode(layout_name):
    decoder = ul.StateDecoder("auto")
    s = decoder.decode(vendor_state(layout_name))
    assert s.SDK == layout_name and decoder.layout == layout_name and decoder.source == "auto"
    assert s.mode == 2 and s.gait_type == 1
    assert s.quaternion == pytest.approx((0.5, 0.5, -0.5, 0.5))
    assert s.gyroscope == pytest.approx((0.01, -0.02, 0.3))
    assert s.accelerometer == pytest.approx((0.1, -0.2, 9.7))
    assert s.rpy == pytest.approx((0.05, -0.04, 1.2))
    assert s.position == pytest.approx((1.25, -0.75, 0.0))
    assert s.body_height == pytest.approx(0.27)
    assert s.velocity == pytest.approx((0.3, -0.1, 0.0)) and s.yaw_speed == pytest.approx(0.25)
    assert s.foot_force == (11, -22, 33, 44)
    assert s.buttons() == ul.button_mask(("L2", "B")) == 0x0220


@pytest.mark.parametrize("layout_name", ["3.3", "3.3.4"])
@pytest.mark.parametrize("held", [(), ("L2", "B"), ("R1", "left"), ("start", "select", "A")])
def test_state_buttons_reads_btn_of_a_raw_vendor_high_state(layout_name, held):
    data = vendor_state(layout_name, wirelessRemote=vendor.remote(list(held), lx=-0.7, ry=0.3), crc=0xFFFFFFFF)
    expected = 0
    for name in held:
        expected |= 1 << vendor.BUTTON_BITS[name]
    assert ul.state_buttons(data) == expected


@pytest.mark.parametrize("size", [0, 113, 264, 266, 1024, 1026])
def test_state_buttons_of_a_packet_of_unknown_size_is_none(size):
    assert ul.state_buttons(b"\xff" * size) is None


def test_vendor_motor_states_decode_in_sdk_order():
    motors = [{"q": 0.1 * i, "dq": -0.01 * i, "tauEst": 0.5 * i, "ddq": 99.0, "q_raw": 98.0} for i in range(20)]
    s = ul.StateDecoder().decode(vendor_state("3.3.4", motorState=motors))
    q, dq, tau = s.joints()
    assert q == pytest.approx([0.1 * i for i in range(12)])
    assert dq == pytest.approx([-0.01 * i for i in range(12)])
    assert tau == pytest.approx([0.5 * i for i in range(12)])


@pytest.mark.parametrize("size", [0, 1, 113, 256, 264, 266, 319, 1024, 1026, 2048])
def test_unknown_sizes_rejected_naming_the_known_ones(size):
    decoder = ul.StateDecoder("auto")
    with pytest.raises(ul.LayoutError) as err:
        decoder.decode(b"\x00" * size)
    assert "%d B" % size in str(err.value)
    assert "265 B" in str(err.value) and "1025 B" in str(err.value)
    assert decoder.wrong_size == 1 and decoder.layout is None and decoder.last_size == size


@pytest.mark.parametrize("forced, other", [("3.3", "3.3.4"), ("3.3.4", "3.3")])
def test_forced_layout_rejects_the_other_size(forced, other):
    decoder = ul.StateDecoder(forced)
    assert decoder.source == "forced" and decoder.layout == forced
    assert decoder.decode(vendor_state(forced)).SDK == forced
    with pytest.raises(ul.LayoutError, match="forces"):
        decoder.decode(vendor_state(other))
    assert decoder.wrong_size == 1 and decoder.good == 1 and decoder.layout == forced


def test_auto_follows_each_packet_size():
    decoder = ul.StateDecoder()
    assert decoder.decode(vendor_state("3.3")).SDK == "3.3"
    assert decoder.decode(vendor_state("3.3.4")).SDK == "3.3.4"
    assert decoder.layout == "3.3.4" and decoder.good == 2


@pytest.mark.parametrize("bad", ["3.3.3", "v3.3", "", "3.2"])
def test_bad_sdk_layout_parameter(bad):
    with pytest.raises(ValueError, match="sdk_layout"):
        ul.StateDecoder(bad)


def test_button_mask_and_remote_bits():
    assert ul.button_mask(("R1",)) == 1 and ul.button_mask(("left",)) == 0x8000
    for name in vendor.BUTTON_BITS:
        assert ul.remote_buttons(vendor.remote([name])) == ul.button_mask((name,))
    with pytest.raises(ValueError, match="unknown remote button"):
        ul.button_mask(("L3",))


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


@pytest.mark.parametrize("layout_name", ["3.3", "3.3.4"])
def test_high_state_nan_rejected(layout_name):
    with pytest.raises(ul.LayoutError, match="non-finite"):
        ul.StateDecoder().decode(vendor_state(layout_name, position=(math.nan, 0.0, 0.0)))
    with pytest.raises(ul.LayoutError, match="non-finite"):
        ul.StateDecoder().decode(vendor_state(layout_name, yawSpeed=math.inf))
