"""goal_from_pose: what /set_position's pose asks for; a malformed orientation is refused, never heading 0."""

import math
from types import SimpleNamespace

import pytest

from rbd_pos_controller.controller import PositionController
from rbd_pos_controller.fsm import State
from rbd_pos_controller.goal import GoalRejectedError, goal_from_pose


def _pose(x, y, z, q):
    return SimpleNamespace(position=SimpleNamespace(x=x, y=y, z=z),
                           orientation=SimpleNamespace(x=q[0], y=q[1], z=q[2], w=q[3]))


def test_position_heading_and_body_pitch_of_a_pose():
    # pitch 0.2 then yaw 1.0, composed by hand: q = q_z(1.0) * q_y(0.2)
    cy, sy, cp, sp = math.cos(0.5), math.sin(0.5), math.cos(0.1), math.sin(0.1)
    goal = goal_from_pose(_pose(1.5, -0.5, -0.05, (-sy * sp, cy * sp, sy * cp, cy * cp)))
    assert (goal.x, goal.y, goal.body_height) == (1.5, -0.5, -0.05)
    assert (goal.roll, goal.pitch, goal.yaw) == pytest.approx((0.0, 0.2, 1.0))


def test_a_nearly_unit_quaternion_is_taken_normalised():
    s = math.sqrt(0.5) * 1.0005
    assert goal_from_pose(_pose(0.0, 0.0, 0.0, (0.0, 0.0, s, s))).yaw == pytest.approx(math.pi / 2)


@pytest.mark.parametrize("q", [(0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 3.0), (0.0, 0.0, 0.0, 0.99),
                               (float("nan"), 0.0, 0.0, 1.0), (0.0, float("inf"), 0.0, 1.0)])
def test_a_zero_non_unit_or_non_finite_orientation_is_refused_and_nothing_moves(q):
    ctl = PositionController()
    ctl.update_pose(0.0, 0.0, 0.0, 0.0)
    with pytest.raises(GoalRejectedError, match="unit quaternion"):
        ctl.set_goal(goal_from_pose(_pose(1.0, 0.0, 0.0, q)), 0.0)
    assert ctl.state == State.WAITING_FOR_POSE
    assert ctl.step(0.05) == (0.0, 0.0, 0.0)


def test_poses_with_a_zero_orientation_count_as_none_and_the_controller_stops():
    from rbd_geometry.rotation import yaw_or_nan  # what the node turns a pose's orientation into

    ctl = PositionController()
    ctl.update_pose(0.0, 0.0, 0.0, 0.0)
    ctl.set_goal(goal_from_pose(_pose(2.0, 0.0, 0.0, (0.0, 0.0, 0.0, 1.0))), 0.0)
    assert ctl.step(0.05) != (0.0, 0.0, 0.0)
    zero = SimpleNamespace(x=0.0, y=0.0, z=0.0, w=0.0)
    t = 0.1
    while t < 1.0:
        assert not ctl.update_pose(0.1, 0.0, yaw_or_nan(zero), t)
        t += 0.05
    assert ctl.step(t) == (0.0, 0.0, 0.0)  # the last good pose is older than pose_timeout
