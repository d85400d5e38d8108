"""SE(2) detour planner: the stop zone's rectangle swept along a heading lattice. ROS-free.

The robot is its stop zone (:mod:`rbd_controller.footprint`: rbd_lidar's rectangle grown for the
planned speed and turn rate, plus a margin): a pose (x, y, theta) is free when no known obstacle
lies inside that rectangle. The search is a Hybrid A* over (x, y, theta): headings in ``headings``
bins, positions continuous, one expansion per (0.1 m cell, bin). Motions are forward arcs of
``step`` metres that turn by 0, 1 or 2 bins (walking while turning) and on-the-spot turns by one bin;
their cost is time at the planned speed and turn rate. Every motion is checked along its sweep
(samples every ``resolution``) against a configuration-space map per heading bin: the obstacle
cells dilated by the rectangle rotated over the whole bin, so any heading inside a bin is covered.
A straight shot (turn on the spot towards the goal, walk, turn to the goal's heading) is tried
from the expanded poses; one free at the fastest speed ends the search, a slower one (its turn on the
spot beside the obstacle only free at a slow turn rate) is a candidate with its time: the search goes
on (at most ``IMPROVE_SECONDS``) while a quicker path can exist and answers with the quickest found.

Each motion is timed at the fastest speed (of ``speed`` x 0.5^n, then ``min_speed``) whose grown
zone stays free along it; the search itself runs in the slowest speed's space. Near obstacles the
path is slow (the robot standing close to the box after a stop can still leave), away from them
fast. ``LatticePlan.speeds`` gives the speed of each pose's motion: the follower must not be faster
there (:func:`rbd_controller.lattice_plan.speed_ahead`). Why a numpy lattice and not OMPL's SE2
space: the rbd_controller README, "Detour planner".
"""

import heapq
import math
import time
from typing import Any, Callable, List, Optional, Sequence, Tuple

import numpy as np

from rbd_controller.arena import Arena
from rbd_controller.cspace import EXACT_MARGIN, CSpace, Window, exact_points, obstacle_grid
from rbd_controller.detour import MAX_DETOUR_SPAN, GridMap, finite_points
from rbd_controller.footprint import ZoneGrowth, motion_zone
from rbd_controller.lattice_plan import LatticePlan, Pose, path_length
from rbd_controller.primitives import Primitive, primitives
from rbd_geometry.rotation import wrap_angle

#: Walking on a path, the follower's yaw rate may exceed speed x curvature by this share of its limit.
STEER_ALLOWANCE = 0.25
#: A turn on the spot costs this much more per heading bin than its time (the follower settles on each) [s].
SPOT_TURN_PENALTY = 0.3
#: Once a straight shot slower than the fastest speed is found, the search goes on this long for a quicker
#: path, then answers with the quickest found [s] (wall clock; the robot stands while it plans).
IMPROVE_SECONDS = 1.0


class LatticePlanner:
    """Hybrid A* over (x, y, theta) with the grown stop zone as footprint.

    Args:
        zone: rbd_lidar's rest stop zone (FRONT, LEFT, BACK, RIGHT) [m].
        growth: rbd_lidar's growth parameters.
        speed: walking speed to plan for [m/s].
        max_vx: the follower's forward saturation [m/s] (Table 2).
        max_wz: the follower's yaw-rate saturation [rad/s] (Table 2); a path followed at speed v turns
            at <= max_wz * v / max_vx (the follower's rule), and the zone grows for that turn rate.
        margin: kept free around the zone on every side, beyond the grid's own 1.5 cells [m].
        min_speed: the slowest speed the planner falls back to near obstacles [m/s].
        resolution: obstacle grid cell [m].
        headings: heading bins.
        step: length of one forward motion [m].
        window_margin: the search window extends this far beyond start and goal [m].
        max_expansions: the search gives up after this many expansions.
        max_seconds: ... or after this much wall-clock time from the call [s] (a plan's ``budget`` overrides it;
            wall clock: the planner runs in a worker thread beside the node's, CPU time would count both).
        origin: (x, y) of the point the zone is measured from in the robot's frame [m] (rbd_lidar's
            ~zone_frame: collision_zone, 0.08 m behind base_link on the A1); the poses are base_link's.
        improve_seconds: after a straight shot slower than full speed, search this much longer for a quicker path [s].

    Raises:
        ValueError: a value out of range.
    """

    def __init__(self, zone: Sequence[float] = (0.70, 0.35, 0.55, 0.35), growth: Optional[ZoneGrowth] = None,
                 speed: float = 0.3, max_vx: float = 0.3, max_wz: float = math.radians(36.0), margin: float = 0.0,
                 min_speed: float = 0.06, resolution: float = 0.04, headings: int = 48, step: float = 0.2,
                 window_margin: float = 2.0, max_expansions: int = 6000,
                 origin: Sequence[float] = (0.0, 0.0), max_seconds: float = 5.0,
                 improve_seconds: float = IMPROVE_SECONDS) -> None:
        if len(zone) != 4 or not all(math.isfinite(z) and z >= 0 for z in zone):
            raise ValueError("zone needs 4 finite sides >= 0, got %r" % (zone,))
        if not (0 < min_speed <= speed <= max_vx and 0 < max_wz and 0 <= margin and 0 < resolution <= 0.2
                and 8 <= headings <= 128 and resolution <= step):
            raise ValueError("need 0 < min_speed <= speed <= max_vx, max_wz > 0, margin >= 0, 0 < resolution <= 0.2, "
                             "resolution <= step and 8 <= headings <= 128")
        self.zone = tuple(float(z) for z in zone)
        self.growth = growth if growth is not None else ZoneGrowth()
        self.speed = float(speed)
        self.max_vx = float(max_vx)
        self.max_seconds = float(max_seconds)
        self.improve_seconds = float(improve_seconds)
        self._any_heading = False
        self._deadline = math.inf
        self.origin = (float(origin[0]), float(origin[1]))
        if not all(math.isfinite(v) and abs(v) < 1.0 for v in self.origin):
            raise ValueError("origin must be finite and within 1 m of the robot, got %r" % (origin,))
        self.max_wz = float(max_wz)
        self._kernels = {}  # type: Dict[Tuple[Tuple[float, ...], int], np.ndarray]
        self._prims = {}  # type: Dict[float, List[Any]]
        self.margin = float(margin)
        self.min_speed = float(min_speed)
        self.resolution = float(resolution)
        self.headings = int(headings)
        self.step = float(step)
        self.window_margin = float(window_margin)
        self.max_expansions = int(max_expansions)
        self.bin = 2.0 * math.pi / self.headings

    def speeds(self) -> List[float]:
        """The speeds tried, fastest first."""
        out, s = [], self.speed
        while s >= 2.0 * self.min_speed - 1e-9:
            out.append(s)
            s *= 0.5
        return out + [self.min_speed]

    def turn_rate(self, speed: float) -> float:
        """The follower's yaw-rate limit when following at speed [rad/s]."""
        return self.max_wz * min(1.0, speed / self.max_vx)

    def turn_zone_for(self, speed: float, age: float = 0.0) -> Tuple[float, float, float, float]:
        """The rectangle kept free while turning on the spot at the follower's turn rate for speed."""
        return self._shift(motion_zone(self.zone, 0.0, self.turn_rate(speed), self.growth, self.margin, age))

    def turn_room(self, speed: Optional[float] = None) -> Tuple[float, float, float, float]:
        """Per side (FRONT, LEFT, BACK, RIGHT), how far beyond rbd_lidar's rest zone an obstacle must lie for a turn.

        A turn on the spot at the follower's turn rate for speed (None: the fastest) sweeps the turning zone's
        corners round a circle about base_link; an obstacle on a side (measured along that side from the zone's
        origin, as rbd_lidar's min_distance) at least rest zone + this keeps that circle free [m]. The escape
        backs off this far where it can (:func:`rbd_controller.escape.plan_escape`): beside the box the detour
        then starts with a quick turn instead of one at the slowest speed's turn rate.
        """
        f, left, b, right = self.turn_zone_for(self.speed if speed is None else speed)
        reach = math.hypot(max(f, b), max(left, right)) + EXACT_MARGIN
        rest = self._shift(self.zone)
        return tuple(max(0.0, reach - z) for z in rest)  # type: ignore[return-value]

    def _shift(self, zone: Sequence[float]) -> Tuple[float, float, float, float]:
        """A zone measured from origin as limits around the robot's own frame."""
        ox, oy = self.origin
        return (zone[0] + ox, zone[1] + oy, zone[2] - ox, zone[3] - oy)

    def walk_zone_for(self, speed: float, curvature: float, age: float = 0.0) -> Tuple[float, float, float, float]:
        """The rectangle kept free walking at speed on a curvature [1/m].

        The yaw rate is speed x curvature plus STEER_ALLOWANCE of the turn rate (the follower's corrections).
        """
        wz = min(self.turn_rate(speed), speed * abs(curvature) + STEER_ALLOWANCE * self.turn_rate(speed))
        return self._shift(motion_zone(self.zone, speed, wz, self.growth, self.margin, age))

    def _walk_zones(self, speed: float, age: float) -> Callable[[float], Sequence[float]]:
        cache = {}  # type: Dict[float, Tuple[float, float, float, float]]

        def zone(curvature: float) -> Tuple[float, float, float, float]:
            key = round(abs(curvature), 6)
            if key not in cache:
                cache[key] = self.walk_zone_for(speed, curvature, age)
            return cache[key]

        return zone

    def zone_for(self, speed: float, age: float = 0.0) -> Tuple[float, float, float, float]:
        """The rectangle kept free for a path walked at speed (grown as rbd_lidar would, + margin)."""
        return self._shift(motion_zone(self.zone, speed, self.turn_rate(speed), self.growth, self.margin, age))

    # ------------------------------------------------------------------ entry
    def plan(self, start: Sequence[float], goal: Sequence[float], grid: Optional[GridMap] = None,
             points: Sequence[Sequence[float]] = (), arena: Optional[Arena] = None,
             age: float = 0.0, any_heading: bool = False, budget: Optional[float] = None) -> LatticePlan:
        """Plan from the start pose to the goal pose (map frame); never raises.

        Args:
            start: robot pose (x, y, yaw) [m, m, rad].
            goal: pose to reach (x, y, yaw), the heading included.
            grid: the LiDAR map (may be None).
            points: obstacle points [m].
            arena: the robot's centre stays inside (None: no limit).
            age: age of the newest cloud the points come from [s]: grows the zone like speed x age.
            any_heading: the goal's position with any heading (the path ends facing the way it walked;
                the trick pose re-sent afterwards turns to its own heading).
            budget: wall-clock seconds for the search from this call (None: ``max_seconds``); past it the
                answer is "no path" with "budget" in the reason.

        Returns:
            A LatticePlan; ``ok`` False with the reason when no speed gives a free start, goal and path.
        """
        t0 = time.process_time()
        limit = self.max_seconds if budget is None or not math.isfinite(budget) or budget <= 0 else float(budget)
        self._deadline = time.monotonic() + limit
        self._any_heading = bool(any_heading)
        try:
            plan = self._plan(start, goal, grid, points, arena, age)
        except (ArithmeticError, IndexError, MemoryError, TypeError, ValueError) as err:
            # Unreachable by the property tests; a planner error must never kill the controller.
            plan = LatticePlan(False, [], 0.0, math.nan, "planner error: %s: %s" % (type(err).__name__, err))
        plan.seconds = time.process_time() - t0
        return plan

    def _plan(self, start: Sequence[float], goal: Sequence[float], grid: Optional[GridMap],
              points: Sequence[Sequence[float]], arena: Optional[Arena], age: float) -> LatticePlan:
        if len(start) != 3 or len(goal) != 3 or not all(math.isfinite(float(v)) for v in list(start) + list(goal)):
            return LatticePlan(False, [], 0.0, math.nan, "start or goal not a finite (x, y, yaw): %r -> %r"
                               % (start, goal))
        start = (float(start[0]), float(start[1]), wrap_angle(float(start[2])))
        goal = (float(goal[0]), float(goal[1]), wrap_angle(float(goal[2])))
        direct = math.hypot(goal[0] - start[0], goal[1] - start[1])
        if direct > MAX_DETOUR_SPAN:
            return LatticePlan(False, [], 0.0, direct, "goal %.1f m away: beyond %.0f m" % (direct, MAX_DETOUR_SPAN))
        if arena is not None and not arena.contains(goal[0], goal[1]):
            return LatticePlan(False, [], 0.0, direct, "goal outside the arena")
        if not math.isfinite(age) or age < 0:
            age = 0.0
        pts = finite_points(points)
        window = self._window(start, goal)
        obstacles = obstacle_grid(window, self.resolution, grid, pts)
        exact = exact_points(window, self.resolution, grid, pts)
        speeds = self.speeds()
        spaces = [CSpace(window, obstacles, self.zone_for(v, age), self.bin, self.headings, arena, self.resolution,
                         self._kernels, exact, self.turn_zone_for(v, age), self._walk_zones(v, age)) for v in speeds]
        slowest = spaces[-1]
        if self._any_heading:
            free = [h for h in np.arange(self.headings) * self.bin if slowest.free_pose((goal[0], goal[1], h))]
            if not free:
                return LatticePlan(False, [], 0.0, direct, "goal blocked: an obstacle in the zone at the goal")
        elif not slowest.free_pose(goal):
            return LatticePlan(False, [], 0.0, direct, "goal blocked: an obstacle in the zone at the goal pose")
        if not slowest.free_pose(start):
            return LatticePlan(False, [], 0.0, direct, "start inside the zone even at %.2f m/s" % speeds[-1])
        poses, seg_speeds, n = self._search(spaces, speeds, start, goal)
        if poses is None:
            spent = " (wall-clock budget spent)" if time.monotonic() >= self._deadline else ""
            return LatticePlan(False, [], 0.0, direct, "no path around the obstacle (%d expansions%s)" % (n, spent),
                               expanded=n)
        length = path_length(start, poses)
        plan = LatticePlan(True, poses, length, direct, "%d poses, %.2f m, %.2f-%.2f m/s" % (
            len(poses), length, min(seg_speeds), max(seg_speeds)), max(seg_speeds),
            self.zone_for(max(seg_speeds), age), n)
        plan.speeds = seg_speeds
        path = [start] + poses
        plan.zones = [self.turn_zone_for(v, age) if math.hypot(b[0] - a[0], b[1] - a[1]) < 1e-9 else
                      self.walk_zone_for(v, wrap_angle(b[2] - a[2]) / max(math.hypot(b[0] - a[0], b[1] - a[1]), 1e-9),
                                         age)
                      for a, b, v in zip(path, path[1:], seg_speeds)]
        return plan

    def _window(self, start: Pose, goal: Pose) -> Window:
        m, res = self.window_margin, self.resolution
        x0, y0 = min(start[0], goal[0]) - m, min(start[1], goal[1]) - m
        x1, y1 = max(start[0], goal[0]) + m, max(start[1], goal[1]) + m
        return x0, y0, int(math.ceil((x1 - x0) / res)), int(math.ceil((y1 - y0) / res))

    # ------------------------------------------------------------------ search
    def _primitives_cached(self, speed: float) -> List[List[Primitive]]:
        key = round(speed, 9)
        if key not in self._prims:
            self._prims[key] = self._primitives(speed)
        return self._prims[key]

    def _primitives(self, speed: float) -> List[List[Primitive]]:
        return primitives(self.step, self.headings, speed, self.turn_rate(speed), SPOT_TURN_PENALTY)

    def _level(self, spaces: List[CSpace], check: Callable[[CSpace], bool]) -> int:
        """Index of the fastest space in which check(space) holds; len(spaces) if none.

        The zones grow with the speed (a motion free at a speed is free at every slower one): the
        fastest is tried first (most motions, away from obstacles), then the slowest (a blocked motion
        costs two checks, not one per speed), then those between.
        """
        if check(spaces[0]):
            return 0
        if len(spaces) > 1 and not check(spaces[-1]):
            return len(spaces)
        for i in range(1, len(spaces) - 1):
            if check(spaces[i]):
                return i
        return len(spaces) - 1 if len(spaces) > 1 else len(spaces)

    def _search(self, spaces: List[CSpace], speeds: List[float], start: Pose,
                goal: Pose) -> Tuple[Optional[List[Pose]], List[float], int]:
        """Hybrid A* in the slowest speed's space; each motion is timed at the fastest speed it is free for.

        The answer is the quickest path found: a straight shot at full speed at once; else the search goes
        on past slower shots until no open node can beat the best (f >= its time), IMPROVE_SECONDS after the
        first one, the budget or max_expansions, whichever comes first.
        """
        nb = self.headings
        space = spaces[-1]
        heur = space.heuristic(goal, speeds[0])
        if not math.isfinite(heur(start[0], start[1])):
            return None, [], 0
        # A shot at full speed ends the search; a slower one is a candidate (see the docstring).
        best = None  # type: Optional[Tuple[float, int, List[Pose], List[float]]]  # (time, node, poses, speeds)
        shot = self._shot(spaces, speeds, start, goal)
        if shot is not None:
            if shot[3]:
                return shot[0], shot[1], 0
            best = (shot[2], 0, shot[0], shot[1])
        prims = [self._primitives_cached(v) for v in speeds]
        k0 = int(round(start[2] / self.bin)) % nb
        # The start's own heading may lie between bins: turn on the spot to the nearest bin first.
        first = (start[0], start[1], k0)
        nodes = [(start, None, 0.0)]  # (pose, parent index, speed of the motion into it)
        if abs(wrap_angle(start[2] - k0 * self.bin)) > 1e-9:
            turn = [start, (start[0], start[1], k0 * self.bin)]
            lvl = self._level(spaces, lambda sp: sp.free_path(turn))
            if lvl == len(spaces):
                return None, [], 0
            nodes.append(((start[0], start[1], k0 * self.bin), 0, speeds[lvl]))
        cres = 0.1
        heap = [(heur(first[0], first[1]), 0.0, len(nodes) - 1, first)]
        closed = set()
        expanded = 0
        deadline = self._deadline if best is None else min(self._deadline, time.monotonic() + self.improve_seconds)
        while heap and expanded < self.max_expansions and time.monotonic() < deadline:
            f, g, idx, (x, y, k) = heapq.heappop(heap)
            if best is not None and f >= best[0]:
                break  # nothing left can be quicker than the best shot (the heuristic never overestimates)
            key = (int(math.floor(x / cres)), int(math.floor(y / cres)), k)
            if key in closed:
                continue
            closed.add(key)
            expanded += 1
            pose = (x, y, wrap_angle(k * self.bin))
            if expanded % 2 == 1 or math.hypot(goal[0] - x, goal[1] - y) < 1.0:
                shot = self._shot(spaces, speeds, pose, goal)
                if shot is not None and (best is None or g + shot[2] < best[0]):
                    if best is None and not shot[3]:
                        deadline = min(deadline, time.monotonic() + self.improve_seconds)
                    best = (g + shot[2], idx, shot[0], shot[1])
                    if shot[3]:
                        break
            for j, (dx, dy, dk, _, samples, curv) in enumerate(prims[-1][k]):
                nk = (k + dk) % nb
                nx, ny = x + dx, y + dy
                nkey = (int(math.floor(nx / cres)), int(math.floor(ny / cres)), nk)
                if nkey in closed:
                    continue
                if dx == 0.0 and dy == 0.0:
                    lvl = self._level(spaces, lambda sp, x=x, y=y, hs=samples[:, 2]: sp.free_turn(x, y, hs))
                else:
                    lvl = self._level(
                        spaces, lambda sp, x=x, y=y, smp=samples, cv=curv: sp.free_samples(x, y, smp, cv))
                if lvl == len(spaces):
                    continue
                h = heur(nx, ny)
                if not math.isfinite(h):
                    continue
                cost = prims[lvl][k][j][3]
                nodes.append(((nx, ny, wrap_angle(nk * self.bin)), idx, speeds[lvl]))
                heapq.heappush(heap, (g + cost + h, g + cost, len(nodes) - 1, (nx, ny, nk)))
        if best is None:
            return None, [], expanded
        poses, vs = self._unwind(nodes, best[1])
        return poses + best[2], vs + best[3], expanded

    @staticmethod
    def _unwind(nodes: List[Any], idx: int) -> Tuple[List[Pose], List[float]]:
        poses, vs = [], []
        while idx is not None:
            pose, parent, v = nodes[idx]
            poses.append(pose)
            vs.append(v)
            idx = parent
        return poses[::-1][1:], vs[::-1][1:]  # without the start

    def _shot(self, spaces: List[CSpace], speeds: List[float], pose: Pose,
              goal: Pose) -> Optional[Tuple[List[Pose], List[float], float, bool]]:
        """Turn on the spot towards the goal, walk straight, turn to the goal's heading.

        Returns:
            None when its sweep is not free at the slowest speed, else (poses, speed of each motion, its time
            [s] as the search counts it, True when every motion is free at the fastest speed).
        """
        dist = math.hypot(goal[0] - pose[0], goal[1] - pose[1])
        if self._any_heading:
            face = math.atan2(goal[1] - pose[1], goal[0] - pose[0]) if dist >= 0.05 else pose[2]
            goal = (goal[0], goal[1], face)
        if dist < 0.05:  # walk the last centimetres, then turn on the spot (what the follower does)
            path = [pose, (goal[0], goal[1], pose[2]), goal]
        else:
            face = math.atan2(goal[1] - pose[1], goal[0] - pose[0])
            path = [pose, (pose[0], pose[1], face), (goal[0], goal[1], face), goal]
        if not spaces[-1].free_path(path):
            return None
        out, vs = [], []
        cost, fastest = 0.0, True
        for prev, p in zip(path, path[1:]):
            dist, turn = math.hypot(p[0] - prev[0], p[1] - prev[1]), abs(wrap_angle(p[2] - prev[2]))
            if dist < 1e-9 and turn < 1e-3:
                continue  # no turn needed
            lvl = min(self._level(spaces, lambda sp, seg=(prev, p): sp.free_path(seg)), len(speeds) - 1)
            out.append(p)
            vs.append(speeds[lvl])
            fastest = fastest and lvl == 0
            # As the primitives count it: walking at the speed, a turn on the spot at its turn rate plus
            # SPOT_TURN_PENALTY per heading bin.
            cost += (dist / speeds[lvl] if dist >= 1e-9 else
                     turn / self.turn_rate(speeds[lvl]) + SPOT_TURN_PENALTY * turn / self.bin)
        if not out:
            out, vs = [goal], [speeds[-1]]
        return out, vs, cost, fastest
