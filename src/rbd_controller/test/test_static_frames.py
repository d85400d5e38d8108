"""StaticFrames: the controller's sensor mounts from /tf_static without tf2."""

import math

import pytest

from rbd_controller.static_frames import StaticFrames
from rbd_geometry.rotation import yaw_to_quat as _yaw_q


def test_a_chain_of_mounts_composes_translation_and_yaw():
    frames = StaticFrames()
    frames.add("base_link", "trunk", (0.1, 0.0, 0.2), _yaw_q(math.pi / 2))
    frames.add("/trunk", "os1_sensor", (0.3, 0.0, 0.1), _yaw_q(math.pi / 4))
    x, y, yaw = frames.lookup("base_link", "os1_sensor")
    # trunk turned 90 deg: its +x is base_link's +y
    assert (x, y) == pytest.approx((0.1, 0.3))
    assert yaw == pytest.approx(3 * math.pi / 4)


def test_lookup_from_a_child_frame_inverts_the_chain():
    frames = StaticFrames()
    frames.add("base_link", "laser", (1.0, 0.0, 0.0), _yaw_q(math.pi / 2))
    x, y, yaw = frames.lookup("laser", "base_link")
    assert (x, y) == pytest.approx((0.0, 1.0))
    assert yaw == pytest.approx(-math.pi / 2)


def test_roll_of_a_mount_leaves_the_planar_pose():
    frames = StaticFrames()
    roll = (math.sin(0.25), 0.0, 0.0, math.cos(0.25))  # 0.5 rad about x
    frames.add("base_link", "cam", (0.2, -0.1, 0.4), roll)
    assert frames.lookup("base_link", "cam") == pytest.approx((0.2, -0.1, 0.0))


def test_a_frame_upside_down_turns_its_childs_yaw_and_offsets_the_other_way():
    # A LiDAR mounted upside down (pi about x): its +y is base_link's -y and its +z is -z, so a
    # child turned +90 deg about the LiDAR's z faces -90 deg in base_link.
    frames = StaticFrames()
    frames.add("base_link", "lidar", (0.0, 0.0, 0.5), (1.0, 0.0, 0.0, 0.0))
    frames.add("lidar", "beam", (0.0, 0.3, 0.0), _yaw_q(math.pi / 2))
    assert frames.lookup("base_link", "beam") == pytest.approx((0.0, -0.3, -math.pi / 2))


def test_unconnected_frames_and_loops_give_none():
    frames = StaticFrames()
    assert frames.lookup("base_link", "os1_sensor") is None
    frames.add("odom", "os1_sensor", (0, 0, 0), (0, 0, 0, 1))
    assert frames.lookup("base_link", "os1_sensor") is None
    frames.add("a", "b", (0, 0, 0), (0, 0, 0, 1))
    frames.add("b", "a", (0, 0, 0), (0, 0, 0, 1))
    assert frames.lookup("a", "b") is None


def test_a_later_transform_of_the_same_child_replaces_the_first():
    frames = StaticFrames()
    frames.add("base_link", "laser", (1.0, 0.0, 0.0), (0, 0, 0, 1))
    frames.add("base_link", "laser", (2.0, 0.0, 0.0), (0, 0, 0, 2))  # (normalised)
    assert frames.lookup("base_link", "laser") == pytest.approx((2.0, 0.0, 0.0))


@pytest.mark.parametrize(
    "translation, rotation", [((0, 0, float("nan")), (0, 0, 0, 1)), ((0, 0, 0), (0, 0, 0, 0)), ((0, 0), (0, 0, 0, 1))]
)
def test_bad_transforms_are_refused(translation, rotation):
    with pytest.raises(ValueError):
        StaticFrames().add("base_link", "laser", translation, rotation)
