"""Directional zone guard for avoidance motions (GUARDED goals). ROS-free.

A trick motion stops as soon as anything is in the LiDAR stop zone (rbd_lidar's collision
flag). An avoidance motion (stepping back from a wall, away from a visitor) starts with
something *in* the zone, so it is gated on the same zone per side instead: a command may move
only if every side it heads towards is clear. The zone is rbd_lidar's own (each side grown by
the commanded velocity, so it is the velocity-aware zone of the motion); a side counts as
occupied with at least ``point_threshold`` critical points, the same rule that sets the
collision flag. A blocked side is released only after ``clear_scans`` consecutive clear
readings (the collision flag's hysteresis), no reading within ``timeout`` or a stale/invalid
reading blocks every motion, and turning (which sweeps every side) needs all four sides clear.
"""

import math
from typing import Sequence, Set, Tuple

FRONT, LEFT, BACK, RIGHT = 0, 1, 2, 3  # rbd_msgs/CollisionState side indices
SIDE_NAMES = ("front", "left", "back", "right")

Twist2D = Tuple[float, float, float]
ZERO = (0.0, 0.0, 0.0)  # type: Twist2D


def sides_towards(vx: float, vy: float, wz: float, eps: float = 1e-4) -> Set[int]:
    """Sides of the zone a body velocity moves towards.

    Args:
        vx: forward velocity [m/s].
        vy: leftward velocity [m/s].
        wz: yaw rate [rad/s]; any turn sweeps every side.
        eps: velocities below this count as zero.

    Returns:
        Set of side indices (FRONT, LEFT, BACK, RIGHT).
    """
    if abs(wz) > eps:
        return {FRONT, LEFT, BACK, RIGHT}
    out = set()
    if vx > eps:
        out.add(FRONT)
    elif vx < -eps:
        out.add(BACK)
    if vy > eps:
        out.add(LEFT)
    elif vy < -eps:
        out.add(RIGHT)
    return out


class ZoneGuard:
    """Per-side occupancy with hysteresis, fed with every /rbd_lidar/state.

    Args:
        point_threshold: critical points that make a side occupied (rbd_lidar ~point_threshold).
        clear_scans: consecutive clear readings that release a side (rbd_lidar ~hysteresis_scans).
        timeout: a reading older than this blocks every motion [s] (3 scan periods at 10 Hz).

    Raises:
        ValueError: non-positive threshold, clear_scans or timeout.
    """

    def __init__(self, point_threshold: int = 5, clear_scans: int = 3, timeout: float = 0.35) -> None:
        if int(point_threshold) < 1 or int(clear_scans) < 1:
            raise ValueError("point_threshold and clear_scans must be >= 1")
        if not math.isfinite(timeout) or timeout <= 0.0:
            raise ValueError("timeout must be a finite number > 0, got %r" % (timeout,))
        self.point_threshold = int(point_threshold)
        self.clear_scans = int(clear_scans)
        self.timeout = float(timeout)
        self.time = None  # type: Optional[float]
        self.valid = False
        self._clear_run = [0, 0, 0, 0]
        self.readings = 0

    def update(self, now: float, points: Sequence[int], stale: bool = False, error: str = "") -> None:
        """One zone reading received at ``now`` [s]: critical points per side, stale flag, error text."""
        self.readings += 1
        self.time = now
        self.valid = not stale and not error and len(points) == 4
        for side in range(4):
            occupied = not self.valid or int(points[side]) >= self.point_threshold
            self._clear_run[side] = 0 if occupied else self._clear_run[side] + 1

    def fresh(self, now: float) -> bool:
        """True when the last reading is valid and younger than the timeout."""
        return self.valid and self.time is not None and 0.0 <= now - self.time <= self.timeout

    def blocked_sides(self, now: float) -> Set[int]:
        """Sides that are occupied or not yet clear for clear_scans readings (all when not fresh)."""
        if not self.fresh(now):
            return {FRONT, LEFT, BACK, RIGHT}
        return {s for s in range(4) if self._clear_run[s] < self.clear_scans}

    def allows(self, cmd: Twist2D, now: float) -> bool:
        """True when the command heads to no blocked side (a zero command is always allowed)."""
        return not (sides_towards(*cmd) & self.blocked_sides(now))

    def filter(self, cmd: Twist2D, now: float) -> Twist2D:
        """The command itself if allowed, else zero velocity."""
        return cmd if self.allows(cmd, now) else ZERO


def cap_speed(vx: float, vy: float, max_speed: float) -> Tuple[float, float]:
    """Scale (vx, vy) down so its magnitude is at most max_speed [m/s] (direction kept)."""
    speed = math.hypot(vx, vy)
    if speed <= max_speed or speed == 0.0:
        return vx, vy
    k = max_speed / speed
    return vx * k, vy * k
