"""Saturated proportional control law of the position controller (thesis Eq. 1, Table 2).

ROS-free. Velocities are in the robot frame (x forward, y left, yaw rate about z);
goals and poses are in the global frame the controller follows (map, or world in tests).

Geometric variables (Eq. 1): e_x = x_goal - x, e_y = y_goal - y, rho = sqrt(e_x^2 + e_y^2),
alpha = atan2(e_y, e_x), gamma = alpha - yaw (direction to the goal seen from the robot),
delta = yaw_goal - yaw.

Policies: pre-rotation  yaw_rate = k_alpha * gamma;
          linear        v_x = k_x * rho * cos(gamma), v_y = k_y * rho * sin(gamma);
          post-rotation yaw_rate = k_alpha * delta;
optionally, during the rotations, the position where the rotation started is held with the
same linear law (thesis: "optional pos. control", y only; x can be enabled too).
"""

import math
from typing import Tuple

Twist2D = Tuple[float, float, float]


class Gains:
    """Gains [1/s] and saturations [m/s, rad/s]; defaults are the thesis' Table 2."""

    __slots__ = ("k_x", "k_y", "k_alpha", "max_vx", "max_vy", "max_wz")

    def __init__(
        self,
        k_x: float = 2.5,
        k_y: float = 2.0,
        k_alpha: float = 1.0,
        max_vx: float = 0.3,
        max_vy: float = 0.12,
        max_wz: float = math.radians(36.0),
    ) -> None:
        for name, value in (
            ("k_x", k_x),
            ("k_y", k_y),
            ("k_alpha", k_alpha),
            ("max_vx", max_vx),
            ("max_vy", max_vy),
            ("max_wz", max_wz),
        ):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                raise ValueError("%s must be a finite number > 0, got %r" % (name, value))
        self.k_x = float(k_x)
        self.k_y = float(k_y)
        self.k_alpha = float(k_alpha)
        self.max_vx = float(max_vx)
        self.max_vy = float(max_vy)
        self.max_wz = float(max_wz)

    def __repr__(self) -> str:
        """Readable form for logs."""
        return "Gains(%s)" % ", ".join("%s=%.3f" % (k, getattr(self, k)) for k in self.__slots__)


class Errors:
    """Geometric variables of Eq. 1 between a pose and a goal."""

    __slots__ = ("e_x", "e_y", "rho", "alpha", "gamma", "delta", "ex_robot", "ey_robot")

    def __init__(self, x: float, y: float, yaw: float, gx: float, gy: float, gyaw: float) -> None:
        self.e_x = gx - x
        self.e_y = gy - y
        self.rho = math.hypot(self.e_x, self.e_y)
        self.alpha = math.atan2(self.e_y, self.e_x)
        self.gamma = wrap_angle(self.alpha - yaw)
        self.delta = wrap_angle(gyaw - yaw)
        # The position error in the robot frame: (rho cos gamma, rho sin gamma), well defined at rho = 0.
        c, s = math.cos(yaw), math.sin(yaw)
        self.ex_robot = c * self.e_x + s * self.e_y
        self.ey_robot = -s * self.e_x + c * self.e_y


def wrap_angle(angle: float) -> float:
    """Return angle wrapped to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def saturate(value: float, limit: float) -> float:
    """Clamp value to [-limit, limit]."""
    return max(-limit, min(limit, value))


def linear_command(err: Errors, gains: Gains, keep_direction: bool = True) -> Tuple[float, float]:
    """Eq. 1 linear policy: (v_x, v_y) towards the goal in the robot frame.

    Args:
        err: geometric variables.
        gains: gains and saturations.
        keep_direction: scale both components by one factor when either saturates, so the
            robot keeps walking straight at the goal (clamping each axis on its own bends the
            path whenever v_y saturates before v_x).

    Returns:
        (v_x, v_y) [m/s].
    """
    vx = gains.k_x * err.ex_robot
    vy = gains.k_y * err.ey_robot
    if keep_direction:
        scale = 1.0
        if abs(vx) > gains.max_vx:
            scale = min(scale, gains.max_vx / abs(vx))
        if abs(vy) > gains.max_vy:
            scale = min(scale, gains.max_vy / abs(vy))
        return vx * scale, vy * scale
    return saturate(vx, gains.max_vx), saturate(vy, gains.max_vy)


def rotation_command(angle_error: float, gains: Gains) -> float:
    """Eq. 1 rotation policy: yaw rate k_alpha * angle_error, saturated [rad/s]."""
    return saturate(gains.k_alpha * wrap_angle(angle_error), gains.max_wz)


def hold_command(err: Errors, gain: float, limit: float, use_x: bool, use_y: bool) -> Tuple[float, float]:
    """Position hold during a rotation (the thesis' optional position control).

    Args:
        err: geometric variables towards the point to hold.
        gain: proportional gain [1/s].
        limit: saturation of each axis [m/s].
        use_x: control the forward velocity too.
        use_y: control the sideways velocity (the thesis' y control).

    Returns:
        (v_x, v_y) [m/s], zero for axes that are not controlled.
    """
    vx = saturate(gain * err.ex_robot, limit) if use_x else 0.0
    vy = saturate(gain * err.ey_robot, limit) if use_y else 0.0
    return vx, vy
