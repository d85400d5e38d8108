"""A goal of the position controller: its refusal and its reading from a message (the pose: rbd_geometry.goal).

ROS-free: :func:`goal_from_pose` takes any object with the fields of geometry_msgs/Pose.
"""

import math
from typing import Any

from rbd_geometry.goal import Goal
from rbd_geometry.rotation import quat_to_rpy

#: How far |q| of a goal's orientation may be from 1 (float32 senders, hand-typed goals).
UNIT_TOLERANCE = 1e-3


class GoalRejectedError(ValueError):
    """Raised by set_goal when a goal cannot be accepted; the message says why."""


def goal_from_pose(pose: Any) -> Goal:
    """The goal a geometry_msgs/Pose asks for (/rbd_pos_controller/set_position).

    Position x, y is the goal, position z the body height change; the orientation gives the
    heading (yaw) and the body roll and pitch.

    Raises:
        GoalRejectedError: the orientation is not a unit quaternion (zero, non-finite, or |q| off
            1 by more than UNIT_TOLERANCE): such a goal is malformed, not heading 0.
    """
    q = pose.orientation
    norm = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
    if not math.isfinite(norm) or abs(norm - 1.0) > UNIT_TOLERANCE:
        raise GoalRejectedError("orientation is not a unit quaternion (norm %r)" % norm)
    roll, pitch, yaw = quat_to_rpy(q)
    p = pose.position
    return Goal(p.x, p.y, yaw, roll=roll, pitch=pitch, body_height=p.z)
