"""A detour plan of the SE(2) lattice and what following it asks: its speeds, progress and zones. ROS-free.

:class:`LatticePlan` is what :class:`rbd_controller.lattice.LatticePlanner` answers: the poses, the speed
each motion is planned for and the rectangle kept free along it. The follower must not walk faster than
:func:`speed_ahead` says; :func:`progress_index` tells which pose is next and :func:`remaining_clear`
whether the rest of the plan still keeps its zones free of new obstacle points.
"""

import math
from typing import List, Sequence, Tuple

from rbd_controller.detour import finite_points
from rbd_controller.footprint import swept_hits
from rbd_geometry.rotation import wrap_angle

Pose = Tuple[float, float, float]


class LatticePlan:
    """A planner answer.

    Attributes:
        ok: a path was found.
        poses: (x, y, yaw) to follow, without the start, the goal last.
        length: path length [m].
        direct: straight start-goal distance [m].
        reason: why it failed (or a summary).
        speed: the fastest speed of the path [m/s] (0 when not ok).
        zone: the rectangle (FRONT, LEFT, BACK, RIGHT) [m] for that speed.
        speeds: per pose, the speed the motion into it is planned for [m/s]: near obstacles the
            path is slower (a smaller zone), away from them faster.
        zones: per pose, the rectangle kept free along the motion into it.
        expanded: search expansions.
        seconds: planning time (process time) [s].
    """

    def __init__(self, ok: bool, poses: List[Pose], length: float, direct: float, reason: str, speed: float = 0.0,
                 zone: Sequence[float] = (), expanded: int = 0, seconds: float = 0.0) -> None:
        self.ok = ok
        self.poses = poses
        self.length = length
        self.direct = direct
        self.reason = reason
        self.speed = speed
        self.zone = tuple(zone)
        self.expanded = expanded
        self.seconds = seconds
        self.speeds = []  # type: List[float]
        self.zones = []  # type: List[Tuple[float, float, float, float]]

    def __repr__(self) -> str:
        """Readable form for logs."""
        return "LatticePlan(ok=%s, %d poses, %.2f m vs %.2f m direct at %.2f m/s, %s)" % (
            self.ok, len(self.poses), self.length, self.direct, self.speed, self.reason)


def path_length(start: Sequence[float], poses: Sequence[Sequence[float]]) -> float:
    """Length of the polyline start -> poses [m]."""
    total, prev = 0.0, start
    for p in poses:
        total += math.hypot(p[0] - prev[0], p[1] - prev[1])
        prev = p
    return total


def speed_ahead(plan: LatticePlan, index: int, lookahead: int = 3) -> float:
    """The speed limit for following plan.poses from pose index on: the slowest of the next poses [m/s]."""
    vs = plan.speeds[max(0, index): max(0, index) + max(1, lookahead)]
    return min(vs) if vs else 0.0


def progress_index(plan: LatticePlan, pose: Sequence[float], current: int = 0, reached: float = 0.15,
                   turned: float = 0.15) -> int:
    """Index of the plan's next pose for a robot at pose (x, y, yaw), never behind current.

    A pose reached by walking is passed when the robot is within ``reached`` of it, or closer to the
    segment after it than to the segment before it (and past its start). A pose reached by a turn on
    the spot (at the position of the pose before it), and a pose a turn on the spot follows, is
    passed when the robot stands within ``reached`` of it facing its heading (within ``turned``
    rad), or has walked on to the first walking segment after the turns: the speed limit of a slow
    turn then no longer holds the rest of the path back.
    """
    poses = plan.poses
    i = max(0, current)
    while i < len(poses) - 1:
        a = poses[i - 1] if i > 0 else poses[0]
        b, c = poses[i], poses[i + 1]
        near = math.hypot(pose[0] - b[0], pose[1] - b[1]) <= reached
        facing = len(pose) < 3 or abs(wrap_angle(pose[2] - b[2])) <= turned
        turn_after, turn_into = _same(b, c), i > 0 and _same(a, b)
        if turn_after or turn_into:
            if near and facing:
                i += 1
                continue
            j = i
            while j < len(poses) - 1 and _same(poses[j], poses[j + 1]):
                j += 1  # the last pose of the turns at b's position
            if j < len(poses) - 1 and not near:
                u, d = _segment(pose, poses[j], poses[j + 1])
                _, d0 = _segment(pose, poses[i - 1] if i > 0 else b, b) if not turn_into else (0.0, math.inf)
                if u > 0.0 and d < d0:
                    i = j + 1  # walked on past the turns
                    continue
            break
        if near and not _same(c, b):
            i += 1
            continue
        u2, d2 = _segment(pose, b, c)
        _, d1 = _segment(pose, a, b)
        if u2 > 0.0 and d2 < d1:
            i += 1
            continue
        break
    return i


def _same(p: Sequence[float], q: Sequence[float]) -> bool:
    """Two poses at one position (a turn on the spot between them)."""
    return math.hypot(q[0] - p[0], q[1] - p[1]) <= 1e-9


def remaining_clear(plan: LatticePlan, progress: int, pose: Sequence[float], points: Sequence[Sequence[float]],
                    threshold: int = 1) -> bool:
    """True if the rest of the plan, from the robot's pose, keeps fewer than threshold points in its zones.

    The zones are the plan's own, per motion, swept along it.
    """
    pts = finite_points(points)
    if not len(pts) or progress >= len(plan.poses):
        return True
    path = [tuple(pose[:3])] + list(plan.poses[progress:])
    for zone, a, b in zip(plan.zones[progress:], path, path[1:]):
        if swept_hits([a, b], zone, pts) >= threshold:
            return False
    return True


def _segment(p: Sequence[float], a: Sequence[float], b: Sequence[float]) -> Tuple[float, float]:
    """(projection parameter in [0, 1], distance) of p on the segment a-b."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    len2 = dx * dx + dy * dy
    u = 0.0 if len2 <= 0.0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2))
    return u, math.hypot(a[0] + u * dx - p[0], a[1] + u * dy - p[1])
