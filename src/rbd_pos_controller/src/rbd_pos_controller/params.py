"""Tolerances and options of the position controller, checked once at construction. ROS-free."""

import math
from typing import Optional

from rbd_pos_controller.control_law import Gains


class Params:
    """Tolerances and options of the position controller (defaults documented in the README)."""

    __slots__ = (
        "gains",
        "skip_rotation_distance",
        "position_tolerance",
        "align_tolerance",
        "yaw_tolerance",
        "pose_timeout",
        "rotation_x_control",
        "rotation_y_control",
        "k_hold",
        "max_v_hold",
        "keep_direction",
        "body_pose_settle",
    )

    def __init__(
        self,
        gains: Optional[Gains] = None,
        skip_rotation_distance: float = 0.4,
        position_tolerance: float = 0.02,
        align_tolerance: float = 0.05,
        yaw_tolerance: float = 0.02,
        pose_timeout: float = 0.5,
        rotation_x_control: bool = True,
        rotation_y_control: bool = True,
        k_hold: float = 5.0,
        max_v_hold: float = 0.2,
        keep_direction: bool = True,
        body_pose_settle: float = 0.0,
    ) -> None:
        self.gains = gains if gains is not None else Gains()
        for name, value in (
            ("skip_rotation_distance", skip_rotation_distance),
            ("position_tolerance", position_tolerance),
            ("align_tolerance", align_tolerance),
            ("yaw_tolerance", yaw_tolerance),
            ("pose_timeout", pose_timeout),
            ("k_hold", k_hold),
            ("max_v_hold", max_v_hold),
        ):
            if not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                raise ValueError("%s must be a finite number > 0, got %r" % (name, value))
        if not isinstance(body_pose_settle, (int, float)) or not 0.0 <= body_pose_settle < 60.0:
            raise ValueError("body_pose_settle must be in [0, 60) s, got %r" % (body_pose_settle,))
        self.skip_rotation_distance = float(skip_rotation_distance)
        self.position_tolerance = float(position_tolerance)
        self.align_tolerance = float(align_tolerance)
        self.yaw_tolerance = float(yaw_tolerance)
        self.pose_timeout = float(pose_timeout)
        self.rotation_x_control = bool(rotation_x_control)
        self.rotation_y_control = bool(rotation_y_control)
        self.k_hold = float(k_hold)
        self.max_v_hold = float(max_v_hold)
        self.keep_direction = bool(keep_direction)
        self.body_pose_settle = float(body_pose_settle)
