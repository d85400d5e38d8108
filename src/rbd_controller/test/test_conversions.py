"""conversions.yaw_of: the heading the node hands to perception; a malformed quaternion is no pose."""

import math
from types import SimpleNamespace

import pytest

from rbd_controller.conversions import yaw_of
from rbd_controller.perception import AvoidParams, Perception


def _q(x, y, z, w):
    return SimpleNamespace(x=x, y=y, z=z, w=w)


def test_heading_of_a_turn_about_z():
    # 120 deg about z, written from the half angle by hand
    assert yaw_of(_q(0.0, 0.0, math.sin(math.radians(60)), math.cos(math.radians(60)))) == pytest.approx(
        math.radians(120))


@pytest.mark.parametrize("bad", [_q(0.0, 0.0, 0.0, 0.0), _q(0.0, 0.0, float("nan"), 1.0), _q(float("inf"), 0, 0, 1)])
def test_a_zero_or_non_finite_quaternion_is_nan_and_perception_keeps_no_pose(bad):
    assert math.isnan(yaw_of(bad))  # heading 0 would place the robot's obstacles wrongly
    perception = Perception(AvoidParams())
    perception.on_pose(1.0, 0.5, 0.5, yaw_of(bad))
    assert perception.pose is None
