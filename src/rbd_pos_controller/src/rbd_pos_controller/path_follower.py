"""Path follower: pure pursuit along a path of poses, turns on the spot only where the path has them.

ROS-free. A path is a list of poses (x, y, yaw) in the controller's frame. Consecutive poses at one
position are a turn on the spot (to the second pose's heading); the others are walked, forwards,
the robot turning while it walks (pure pursuit towards a point ``lookahead`` ahead on the path).
Consecutive turns on the spot in one direction (a planner's turn in heading bins) are turned through
without slowing down at each, the planned way round.
Each run of walked segments ends on its last pose's position (the saturated proportional law of
Eq. 1 for the last centimetres); the final pose's heading is then turned to on the spot.

Saturations: forward speed <= ``max_speed`` (<= Table 2's max_vx), sideways <= max_vy (only for the
final approach), yaw rate <= max_wz x max_speed / max_vx (a slow path also turns slowly: the
detour planner grows the LiDAR zone for exactly that turn rate, rbd_controller ``lattice.py``).
Where the path bends more than the turn rate allows at max_speed, the speed drops so the robot
keeps the path's curvature; a heading error above ``turn_angle`` (a corner the path turns on the
spot, or the robot put off its path) is turned on the spot first.
"""

import math
from typing import List, Optional, Sequence, Tuple

from rbd_pos_controller.control_law import Errors, Gains, Twist2D, hold_command, saturate, wrap_angle

Pose = Tuple[float, float, float]
#: A segment shorter than this is a turn on the spot [m].
SPOT = 1e-6


class FollowerParams:
    """Tuning of the follower.

    Args:
        lookahead: pure pursuit look-ahead distance [m].
        position_tolerance: a run's end (and the path's end) is reached within this [m].
        yaw_tolerance: a turn on the spot ends within this [rad].
        turn_angle: a heading error to the look-ahead point above this is turned on the spot [rad].
        k_hold: gain of the position hold during turns on the spot [1/s].

    Raises:
        ValueError: a value not finite and > 0.
    """

    def __init__(self, lookahead: float = 0.3, position_tolerance: float = 0.03, yaw_tolerance: float = 0.03,
                 turn_angle: float = 0.6, k_hold: float = 2.0) -> None:
        for name, v in (("lookahead", lookahead), ("position_tolerance", position_tolerance),
                        ("yaw_tolerance", yaw_tolerance), ("turn_angle", turn_angle), ("k_hold", k_hold)):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                raise ValueError("%s must be a finite number > 0, got %r" % (name, v))
        self.lookahead = float(lookahead)
        self.position_tolerance = float(position_tolerance)
        self.yaw_tolerance = float(yaw_tolerance)
        self.turn_angle = float(turn_angle)
        self.k_hold = float(k_hold)


def check_path(poses: Sequence[Sequence[float]], max_speed: float, gains: Gains, max_poses: int = 2000) -> str:
    """Why a path cannot be followed ("" if it can)."""
    if not 0 < len(poses) <= max_poses:
        return "path needs 1 to %d poses, got %d" % (max_poses, len(poses))
    for p in poses:
        if len(p) != 3 or not all(isinstance(v, (int, float)) and math.isfinite(v) for v in p):
            return "path pose %r is not a finite (x, y, yaw)" % (tuple(p),)
    if isinstance(max_speed, bool) or not isinstance(max_speed, (int, float)) or not 0.0 < max_speed <= gains.max_vx:
        return "max_speed must be in (0, %.2f] m/s, got %r" % (gains.max_vx, max_speed)
    return ""


class PathFollower:
    """Follows one path; command() gives the velocity for the current pose.

    Args:
        poses: the path, start excluded (the robot's pose is the start), goal last.
        max_speed: forward speed limit [m/s].
        gains: Table 2's saturations (and k_x, k_y, k_alpha for the ends of runs and turns).
        params: follower tuning.
    """

    def __init__(self, poses: Sequence[Sequence[float]], max_speed: float, gains: Gains,
                 params: Optional[FollowerParams] = None) -> None:
        self.poses = [(float(p[0]), float(p[1]), float(p[2])) for p in poses]
        self.max_speed = float(max_speed)
        self.gains = gains
        self.params = params if params is not None else FollowerParams()
        self.max_wz = gains.max_wz * min(1.0, self.max_speed / gains.max_vx)
        self.index = 0  # next pose to reach
        self.done = False
        self._start = None  # type: Optional[Pose]  # where the current walk run starts
        self._hold = None  # type: Optional[Tuple[float, float]]

    # ---------------------------------------------------------------- path geometry
    def _prev(self, pose: Pose) -> Pose:
        return self.poses[self.index - 1] if self.index > 0 else (self._start or pose)

    def _run_end(self) -> int:
        """Index of the last pose of the walk run starting at self.index."""
        j = self.index
        while j + 1 < len(self.poses) and _dist(self.poses[j], self.poses[j + 1]) > SPOT:
            j += 1
        return j

    def _is_turn(self, pose: Pose) -> bool:
        return _dist(self._prev(pose), self.poses[self.index]) <= SPOT

    def _progress(self, pose: Pose, end: int) -> None:
        """Move self.index along the walk run past the poses the robot has passed."""
        while self.index < end:
            a, b, c = self._prev(pose), self.poses[self.index], self.poses[self.index + 1]
            u1, u2 = _project(pose, a, b), _project(pose, b, c)
            if u1 >= 1.0 - 1e-9 or (u2 > 0.0 and _dist_to(pose, b, c, u2) <= _dist_to(pose, a, b, u1)):
                self.index += 1
                continue
            break

    def _lookahead_point(self, pose: Pose, end: int) -> Tuple[Tuple[float, float], float]:
        """The point lookahead ahead of the robot's projection on the run, and the distance left to the end."""
        pts = [self._prev(pose)[:2]] + [p[:2] for p in self.poses[self.index: end + 1]]
        lengths = [_dist(a, b) for a, b in zip(pts, pts[1:])]
        s0 = _project(pose, pts[0], pts[1]) * lengths[0]
        total = sum(lengths)
        return _point_at(pts, lengths, min(total, s0 + self.params.lookahead)), total - s0

    # ---------------------------------------------------------------- control
    def command(self, pose: Sequence[float]) -> Twist2D:
        """Velocity (v_x, v_y, yaw rate) for the robot at pose (x, y, yaw); zero once done."""
        pose = (float(pose[0]), float(pose[1]), float(pose[2]))
        if self._start is None:
            self._start = pose
        for _ in range(len(self.poses) + 2):
            if self.done:
                return (0.0, 0.0, 0.0)
            if self._is_turn(pose):
                cmd = self._turn(pose)
            else:
                cmd = self._walk(pose)
            if cmd is not None:
                return cmd
        return (0.0, 0.0, 0.0)

    def _advance(self, pose: Pose) -> None:
        self.index += 1
        self._hold = None
        if self.index >= len(self.poses):
            self.done = True

    def _turn_steps(self) -> List[float]:
        """The heading steps [rad] of the turns on the spot that follow the current pose at its position."""
        steps = []
        j = self.index
        while j + 1 < len(self.poses) and _dist(self.poses[j], self.poses[j + 1]) <= SPOT:
            steps.append(wrap_angle(self.poses[j + 1][2] - self.poses[j][2]))
            j += 1
        return steps

    def _turn(self, pose: Pose) -> Optional[Twist2D]:
        target = self.poses[self.index]
        delta = wrap_angle(target[2] - pose[2])
        steps = self._turn_steps()
        # More turns on the spot in the same direction follow (a planner's turn in heading bins): turn through
        # this pose's heading without slowing down (it is passed once reached or overshot in that direction)
        # and aim the rate at the end of the whole turn, taken the planned way round.
        through = bool(steps) and steps[0] != 0.0 and delta * steps[0] >= 0.0
        if abs(delta) <= self.params.yaw_tolerance or (bool(steps) and delta * steps[0] < 0.0):
            self._advance(pose)
            return None
        ahead = 0.0
        if through:
            for step in steps:
                if step * steps[0] <= 0.0:
                    break
                ahead += step
        if self._hold is None:
            self._hold = (target[0], target[1])
        wz = saturate(self.gains.k_alpha * (delta + ahead), self.max_wz)
        err = Errors(pose[0], pose[1], pose[2], self._hold[0], self._hold[1], pose[2])
        vx, vy = hold_command(err, self.params.k_hold, min(self.max_speed, self.gains.max_vy), True, True)
        return (vx, vy, wz)

    def _walk(self, pose: Pose) -> Optional[Twist2D]:
        end = self._run_end()
        goal = self.poses[end]
        p = self.params
        rho = _dist(pose, goal)
        if rho <= p.position_tolerance:
            # Run done: skip its poses; a final heading (the path's last pose) is turned to on the spot.
            self.index = end
            if end == len(self.poses) - 1:
                if abs(wrap_angle(goal[2] - pose[2])) <= p.yaw_tolerance:
                    self._advance(pose)
                    return None
                self.poses.append(goal)  # one more pose at the same position: a turn to its heading
            self._advance(pose)
            return None
        self._progress(pose, end)
        (lx, ly), left = self._lookahead_point(pose, end)
        c, s = math.cos(pose[2]), math.sin(pose[2])
        bx, by = c * (lx - pose[0]) + s * (ly - pose[1]), -s * (lx - pose[0]) + c * (ly - pose[1])
        alpha = math.atan2(by, bx)
        if abs(alpha) > p.turn_angle:
            # A corner turned on the spot (or the robot is off its path): turn towards the look-ahead point.
            return (0.0, 0.0, saturate(self.gains.k_alpha * alpha, self.max_wz))
        if left < p.lookahead:
            # The last centimetres: Eq. 1's linear law towards the run's end (straight in, small v_y).
            err = Errors(pose[0], pose[1], pose[2], goal[0], goal[1], pose[2])
            g = self.gains
            vx, vy = g.k_x * err.ex_robot, g.k_y * err.ey_robot
            scale = min(1.0, self.max_speed / max(abs(vx), 1e-9), g.max_vy / max(abs(vy), 1e-9))
            return (vx * scale, vy * scale, 0.0)
        dist = math.hypot(bx, by)
        curvature = 2.0 * by / max(dist * dist, 1e-9)
        v = min(self.max_speed, self.gains.k_x * left)
        if abs(curvature) * v > self.max_wz:
            v = self.max_wz / abs(curvature)  # keep the path's curvature: slower, not wider
        return (v, 0.0, v * curvature)


def _dist(a: Sequence[float], b: Sequence[float]) -> float:
    return math.hypot(b[0] - a[0], b[1] - a[1])


def _dist_to(p: Sequence[float], a: Sequence[float], b: Sequence[float], u: float) -> float:
    return math.hypot(a[0] + u * (b[0] - a[0]) - p[0], a[1] + u * (b[1] - a[1]) - p[1])


def _project(p: Sequence[float], a: Sequence[float], b: Sequence[float]) -> float:
    dx, dy = b[0] - a[0], b[1] - a[1]
    len2 = dx * dx + dy * dy
    if len2 <= 0.0:
        return 0.0
    return max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2))


def _point_at(pts: List[Tuple[float, float]], lengths: List[float], s: float) -> Tuple[float, float]:
    for a, b, length in zip(pts, pts[1:], lengths):
        if s <= length or length <= 0.0:
            u = 0.0 if length <= 0.0 else s / length
            return (a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1]))
        s -= length
    return pts[-1]
