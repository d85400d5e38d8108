"""A goal of the position controller: the pose it walks to, its refusal, and its reading from a message.

ROS-free: :func:`goal_from_pose` takes any object with the fields of geometry_msgs/Pose.
"""

import math
from typing import Any

from rbd_geometry.rotation import quat_to_rpy

#: How far |q| of a goal's orientation may be from 1 (float32 senders, hand-typed goals).
UNIT_TOLERANCE = 1e-3


class GoalRejectedError(ValueError):
    """Raised by set_goal when a goal cannot be accepted; the message says why."""


class Goal:
    """A goal pose: position [m], heading [rad], body roll/pitch [rad], body height change [m]."""

    __slots__ = ("x", "y", "yaw", "roll", "pitch", "body_height")

    def __init__(
        self, x: float, y: float, yaw: float, roll: float = 0.0, pitch: float = 0.0, body_height: float = 0.0
    ) -> None:
        self.x = x
        self.y = y
        self.yaw = yaw
        self.roll = roll
        self.pitch = pitch
        self.body_height = body_height

    def __repr__(self) -> str:
        """Readable form for logs."""
        return "Goal(x=%.3f, y=%.3f, yaw=%.3f, roll=%.3f, pitch=%.3f, body_height=%.3f)" % (
            self.x,
            self.y,
            self.yaw,
            self.roll,
            self.pitch,
            self.body_height,
        )


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
