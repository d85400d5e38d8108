"""The stop zone as the robot's footprint: rbd_lidar's rectangle, grown for a motion. ROS-free.

rbd_lidar (C++, ``zone_growth.cpp`` ``grownZone``) grows each side of the stop zone by
``min(max_growth, s * reaction_time) + s * age``, ``s`` = the commanded speed towards that side +
``|wz| * rotation_lever``, ``age`` = the age of the cloud judged, bounded by rbd_lidar's
``max_cloud_age`` (0.5 s; older clouds are not judged at all). :func:`grown_zone` is the same rule
on the same parameters; ``test_footprint.py`` checks it against the numbers of rbd_lidar's own
gtest (issue 27, "safe with late data").

Sides are ordered as rbd_msgs/CollisionState's: FRONT, LEFT, BACK, RIGHT (like AvoidParams.zone).
"""

import math
from typing import Any, Callable, Sequence, Tuple

import numpy as np

Zone = Tuple[float, float, float, float]  # FRONT, LEFT, BACK, RIGHT [m]


class ZoneGrowth:
    """rbd_lidar's velocity-aware growth parameters (``velocity_aware``, ``reaction_time``, ...).

    Args:
        reaction_time: [s].
        rotation_lever: [m].
        max_growth: cap per side of the reaction-time growth [m].
        enabled: rbd_lidar's velocity_aware (False: the zone never grows).
        max_age: rbd_lidar's max_cloud_age, the oldest cloud judged [s]: bounds the age term.
    """

    def __init__(
        self, reaction_time: float = 0.7, rotation_lever: float = 0.30, max_growth: float = 0.50, enabled: bool = True,
        max_age: float = 0.5,
    ) -> None:
        values = (("reaction_time", reaction_time), ("rotation_lever", rotation_lever), ("max_growth", max_growth),
                  ("max_age", max_age))
        for name, v in values:
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise ValueError("%s must be a finite number >= 0, got %r" % (name, v))
        self.reaction_time = float(reaction_time)
        self.rotation_lever = float(rotation_lever)
        self.max_growth = float(max_growth)
        self.enabled = bool(enabled)
        self.max_age = float(max_age)



def growth_from_params(get: Callable[[str, Any], Any], ns: str = "/rbd_lidar") -> ZoneGrowth:
    """rbd_lidar's growth parameters from its namespace; get(name, default) reads one (rospy.get_param).

    Raises:
        ValueError: a value out of range (or not a number).
    """
    d = ZoneGrowth()
    return ZoneGrowth(reaction_time=float(get(ns + "/reaction_time", d.reaction_time)),
                      rotation_lever=float(get(ns + "/rotation_lever", d.rotation_lever)),
                      max_growth=float(get(ns + "/max_growth", d.max_growth)),
                      enabled=bool(get(ns + "/velocity_aware", d.enabled)),
                      max_age=float(get(ns + "/max_cloud_age", d.max_age)))

def grown_zone(zone: Sequence[float], vx: float, vy: float, wz: float, growth: ZoneGrowth, age: float = 0.0) -> Zone:
    """The stop zone grown for the body velocity (vx, vy [m/s], wz [rad/s]), as rbd_lidar grows it.

    Args:
        zone: rest zone (FRONT, LEFT, BACK, RIGHT) [m].
        vx: commanded forward velocity [m/s]; any non-finite component counts as standing still.
        vy: commanded sideways velocity [m/s].
        wz: commanded yaw rate [rad/s].
        growth: rbd_lidar's growth parameters.
        age: the age of the cloud judged [s]: distance walked unseen, added on top of the capped
            reaction growth as rbd_lidar adds it. As there, NaN or more than ``growth.max_age``
            counts as ``max_age`` (unknown means worst) and a negative age as 0.

    Returns:
        The grown zone (FRONT, LEFT, BACK, RIGHT) [m].
    """
    front, left, back, right = (float(z) for z in zone)
    if not growth.enabled:
        return front, left, back, right
    if not all(math.isfinite(v) for v in (vx, vy, wz)):
        vx = vy = wz = 0.0
    a = growth.max_age if math.isnan(age) else min(growth.max_age, max(0.0, age))
    turn = abs(wz) * growth.rotation_lever

    def grow(speed: float) -> float:
        s = max(0.0, speed) + turn  # speed towards the side [m/s]
        return min(growth.max_growth, s * growth.reaction_time) + s * a

    return front + grow(vx), left + grow(vy), back + grow(-vx), right + grow(-vy)


def motion_zone(zone: Sequence[float], speed: float, turn_rate: float, growth: ZoneGrowth, margin: float = 0.0,
                age: float = 0.0) -> Zone:
    """One zone for a whole path walked forwards at <= speed, turning at <= turn_rate, plus a margin.

    The largest zone any part of such a path makes rbd_lidar check (forwards growth and turning
    growth together), grown by ``margin`` on every side.
    """
    z = grown_zone(zone, speed, 0.0, turn_rate, growth, age)
    return (z[0] + margin, z[1] + margin, z[2] + margin, z[3] + margin)


def points_in_zone(pose: Sequence[float], zone: Sequence[float], points: np.ndarray) -> int:
    """Obstacle points (N x 2, map frame) inside the zone of a robot at pose (x, y, yaw)."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if not len(pts):
        return 0
    c, s = math.cos(pose[2]), math.sin(pose[2])
    dx, dy = pts[:, 0] - pose[0], pts[:, 1] - pose[1]
    bx, by = c * dx + s * dy, -s * dx + c * dy
    inside = (bx < zone[0]) & (by < zone[1]) & (bx > -zone[2]) & (by > -zone[3])
    return int(np.count_nonzero(inside))


def sample_path(poses: Sequence[Sequence[float]], step: float = 0.02, angle_step: float = 0.02) -> np.ndarray:
    """Poses (M x 3) along a path of poses, linear in position and heading, at most step/angle_step apart.

    Consecutive poses at one position with different headings are an on-the-spot turn.
    """
    out = [np.asarray(poses[0], dtype=np.float64)]
    for a, b in zip(poses, poses[1:]):
        dyaw = (b[2] - a[2] + math.pi) % (2.0 * math.pi) - math.pi
        n = max(1, int(math.ceil(max(math.hypot(b[0] - a[0], b[1] - a[1]) / step, abs(dyaw) / angle_step))))
        u = np.arange(1, n + 1) / n
        out.append(np.stack([a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1]), a[2] + u * dyaw], axis=1))
    return np.vstack(out)


def swept_hits(poses: Sequence[Sequence[float]], zone: Sequence[float], points: np.ndarray) -> int:
    """The largest number of obstacle points inside the zone anywhere along the path (swept check)."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if not len(pts) or not len(poses):
        return 0
    worst = 0
    for pose in sample_path(poses):
        worst = max(worst, points_in_zone(pose, zone, pts))
    return worst
