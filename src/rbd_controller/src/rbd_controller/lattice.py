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
from the expanded poses and ends the search when its sweep is free.

Each motion is timed at the fastest speed (of ``speed`` x 0.5^n, then ``min_speed``) whose grown
zone stays free along it; the search itself runs in the slowest speed's space. Near obstacles the
path is slow (the robot standing close to the box after a stop can still leave), away from them
fast. ``LatticePlan.speeds`` gives the speed of each pose's motion: the follower must not be faster
there (:func:`speed_ahead`). Why a numpy lattice and not OMPL's SE2
space: the rbd_controller README, "Detour planner".
"""

import heapq
import math
import time
from typing import Any, Callable, List, Optional, Sequence, Tuple

import numpy as np

from rbd_controller.arena import Arena
from rbd_controller.detour import MAX_DETOUR_SPAN, GridMap, dilate, finite_points
from rbd_controller.footprint import ZoneGrowth, motion_zone, sample_path, swept_hits

Pose = Tuple[float, float, float]
Window = Tuple[float, float, int, int]  # x0, y0 [m], width, height [cells]
#: The exact check of a pose the grid flags keeps this much more around the zone: the sweep between two
#: samples (<= 0.02 m, on the spot <= 0.01 rad apart) [m]. Map cells are checked by corners and centre.
EXACT_MARGIN = 0.015
#: Walking on a path, the follower's yaw rate may exceed speed x curvature by this share of its limit.
STEER_ALLOWANCE = 0.25


def wrap(angle: float) -> float:
    """Angle wrapped to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


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
        max_seconds: ... or after this much CPU time [s].
        origin: (x, y) of the point the zone is measured from in the robot's frame [m] (rbd_lidar's
            ~zone_frame: collision_zone, 0.08 m behind base_link on the A1); the poses are base_link's.

    Raises:
        ValueError: a value out of range.
    """

    def __init__(self, zone: Sequence[float] = (0.70, 0.35, 0.55, 0.35), growth: Optional[ZoneGrowth] = None,
                 speed: float = 0.3, max_vx: float = 0.3, max_wz: float = math.radians(36.0), margin: float = 0.0,
                 min_speed: float = 0.06, resolution: float = 0.04, headings: int = 48, step: float = 0.2,
                 window_margin: float = 2.0, max_expansions: int = 6000,
                 origin: Sequence[float] = (0.0, 0.0), max_seconds: float = 5.0) -> None:
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
             age: float = 0.0, any_heading: bool = False) -> LatticePlan:
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

        Returns:
            A LatticePlan; ``ok`` False with the reason when no speed gives a free start, goal and path.
        """
        t0 = time.process_time()
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
        start = (float(start[0]), float(start[1]), wrap(float(start[2])))
        goal = (float(goal[0]), float(goal[1]), wrap(float(goal[2])))
        direct = math.hypot(goal[0] - start[0], goal[1] - start[1])
        if direct > MAX_DETOUR_SPAN:
            return LatticePlan(False, [], 0.0, direct, "goal %.1f m away: beyond %.0f m" % (direct, MAX_DETOUR_SPAN))
        if arena is not None and not arena.contains(goal[0], goal[1]):
            return LatticePlan(False, [], 0.0, direct, "goal outside the arena")
        if not math.isfinite(age) or age < 0:
            age = 0.0
        pts = finite_points(points)
        window = self._window(start, goal)
        obstacles = self._obstacles(window, grid, pts)
        exact = self._exact_points(window, grid, pts)
        self._deadline = time.process_time() + self.max_seconds
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
            return LatticePlan(False, [], 0.0, direct, "no path around the obstacle (%d expansions)" % n, expanded=n)
        length = path_length(start, poses)
        plan = LatticePlan(True, poses, length, direct, "%d poses, %.2f m, %.2f-%.2f m/s" % (
            len(poses), length, min(seg_speeds), max(seg_speeds)), max(seg_speeds),
            self.zone_for(max(seg_speeds), age), n)
        plan.speeds = seg_speeds
        path = [start] + poses
        plan.zones = [self.turn_zone_for(v, age) if math.hypot(b[0] - a[0], b[1] - a[1]) < 1e-9 else
                      self.walk_zone_for(v, wrap(b[2] - a[2]) / max(math.hypot(b[0] - a[0], b[1] - a[1]), 1e-9), age)
                      for a, b, v in zip(path, path[1:], seg_speeds)]
        return plan

    def _window(self, start: Pose, goal: Pose) -> Window:
        m, res = self.window_margin, self.resolution
        x0, y0 = min(start[0], goal[0]) - m, min(start[1], goal[1]) - m
        x1, y1 = max(start[0], goal[0]) + m, max(start[1], goal[1]) + m
        return x0, y0, int(math.ceil((x1 - x0) / res)), int(math.ceil((y1 - y0) / res))

    def _obstacles(self, window: Window, grid: Optional[GridMap], pts: np.ndarray) -> np.ndarray:
        x0, y0, w, h = window
        res = self.resolution
        obstacles = np.zeros((h, w), dtype=bool)
        if grid is not None and grid.occupied.ndim == 2 and grid.occupied.size:
            xs, ys = x0 + (np.arange(w) + 0.5) * res, y0 + (np.arange(h) + 0.5) * res
            gc = np.floor((xs - grid.origin[0]) / grid.resolution).astype(np.int64)
            gr = np.floor((ys - grid.origin[1]) / grid.resolution).astype(np.int64)
            gh, gw = grid.occupied.shape
            vc, vr = (gc >= 0) & (gc < gw), (gr >= 0) & (gr < gh)
            obstacles[np.ix_(vr, vc)] |= grid.occupied[np.ix_(gr[vr], gc[vc])]
            # A map cell larger than ours: mark every one of our cells it overlaps (its corners too).
            if grid.resolution > res:
                r, c = np.nonzero(grid.occupied)
                for fx in (0.0, 1.0):
                    for fy in (0.0, 1.0):
                        cx = np.floor((grid.origin[0] + (c + fx) * grid.resolution - x0) / res - 1e-9 * fx)
                        cy = np.floor((grid.origin[1] + (r + fy) * grid.resolution - y0) / res - 1e-9 * fy)
                        ok = (cx >= 0) & (cx < w) & (cy >= 0) & (cy < h)
                        obstacles[cy[ok].astype(np.int64), cx[ok].astype(np.int64)] = True
        if len(pts):
            c = np.floor((pts[:, 0] - x0) / res).astype(np.int64)
            r = np.floor((pts[:, 1] - y0) / res).astype(np.int64)
            ok = (c >= 0) & (c < w) & (r >= 0) & (r < h)
            obstacles[r[ok], c[ok]] = True
        return obstacles

    def _exact_points(self, window: Window, grid: Optional[GridMap], pts: np.ndarray) -> np.ndarray:
        """The obstacles as points: the scan points, and each occupied map cell's centre and corners.

        Only those in the window, rounded to 5 mm and deduplicated (a scan holds thousands of points
        on the walls around; the exact check's cost grows with them).
        """
        x0, y0, w, h = window
        pts = pts.reshape(-1, 2)
        inside = (pts[:, 0] >= x0) & (pts[:, 0] <= x0 + w * self.resolution) & (pts[:, 1] >= y0) & (
            pts[:, 1] <= y0 + h * self.resolution)
        out = [np.unique(np.round(pts[inside] / 0.005), axis=0) * 0.005]
        if grid is not None and grid.occupied.ndim == 2 and grid.occupied.size:
            x0, y0, w, h = window
            r, c = np.nonzero(grid.occupied)
            gx, gy = grid.origin[0] + c * grid.resolution, grid.origin[1] + r * grid.resolution
            near = (gx > x0 - 1.0) & (gx < x0 + w * self.resolution + 1.0) & (gy > y0 - 1.0) & (
                gy < y0 + h * self.resolution + 1.0)
            gx, gy = gx[near], gy[near]
            for fx, fy in ((0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.5)):
                out.append(np.stack([gx + fx * grid.resolution, gy + fy * grid.resolution], axis=1))
        return np.concatenate(out).reshape(-1, 2)

    # ------------------------------------------------------------------ search
    def _primitives_cached(self, speed: float) -> List[List[Tuple[float, float, int, float, np.ndarray, float]]]:
        key = round(speed, 9)
        if key not in self._prims:
            self._prims[key] = self._primitives(speed)
        return self._prims[key]

    def _primitives(self, speed: float) -> List[List[Tuple[float, float, int, float, np.ndarray]]]:
        """Per heading bin: (dx, dy, dbin, cost [s], samples M x 3 relative (dx, dy, heading), curvature [1/m]).

        On-the-spot turns have dx = dy = 0 and an infinite curvature.
        """
        out = []
        step, nb = self.step, self.headings
        for k in range(nb):
            th = k * self.bin
            prims = []
            for dk in (-2, -1, 0, 1, 2):
                turn = dk * self.bin
                # Samples <= 0.02 m and <= 0.01 rad apart (EXACT_MARGIN covers what lies between).
                n = max(2, int(math.ceil(step / 0.02)), int(math.ceil(abs(turn) / 0.01)))
                s = np.arange(1, n + 1) / n * step
                if dk == 0:
                    xs, ys, hs = s * math.cos(th), s * math.sin(th), np.full(n, th)
                else:
                    kappa = turn / step
                    hs = th + kappa * s
                    xs = (np.sin(hs) - math.sin(th)) / kappa
                    ys = (math.cos(th) - np.cos(hs)) / kappa
                cost = max(step / speed, abs(turn) / self.turn_rate(speed)) + 0.05 * abs(dk)
                prims.append((float(xs[-1]), float(ys[-1]), dk, cost, np.stack([xs, ys, hs], axis=1), turn / step))
            for dk in (-1, 1):
                m = max(2, int(math.ceil(self.bin / 0.01)))
                hs = th + dk * self.bin * np.arange(1, m + 1) / m
                samples = np.stack([np.zeros(m), np.zeros(m), hs], axis=1)
                prims.append((0.0, 0.0, dk, self.bin / self.turn_rate(speed) + 0.3, samples, math.inf))
            out.append(prims)
        return out

    def _level(self, spaces: List["CSpace"], check: Callable[["CSpace"], bool]) -> int:
        """Index of the fastest space in which check(space) holds; len(spaces) if none."""
        for i, space in enumerate(spaces):
            if check(space):
                return i
        return len(spaces)

    def _search(self, spaces: List["CSpace"], speeds: List[float], start: Pose,
                goal: Pose) -> Tuple[Optional[List[Pose]], List[float], int]:
        """Hybrid A* in the slowest speed's space; each motion is timed at the fastest speed it is free for."""
        nb = self.headings
        space = spaces[-1]
        heur = space.heuristic(goal, speeds[0])
        if not math.isfinite(heur(start[0], start[1])):
            return None, [], 0
        shot = self._shot(spaces, speeds, start, goal)
        if shot is not None:
            return shot[0], shot[1], 0
        prims = [self._primitives_cached(v) for v in speeds]
        k0 = int(round(start[2] / self.bin)) % nb
        # The start's own heading may lie between bins: turn on the spot to the nearest bin first.
        first = (start[0], start[1], k0)
        nodes = [(start, None, 0.0)]  # (pose, parent index, speed of the motion into it)
        if abs(wrap(start[2] - k0 * self.bin)) > 1e-9:
            turn = [start, (start[0], start[1], k0 * self.bin)]
            lvl = self._level(spaces, lambda sp: sp.free_path(turn))
            if lvl == len(spaces):
                return None, [], 0
            nodes.append(((start[0], start[1], k0 * self.bin), 0, speeds[lvl]))
        cres = 0.1
        heap = [(heur(first[0], first[1]), 0.0, len(nodes) - 1, first)]
        closed = set()
        expanded = 0
        while heap and expanded < self.max_expansions and time.process_time() < self._deadline:
            _, g, idx, (x, y, k) = heapq.heappop(heap)
            key = (int(math.floor(x / cres)), int(math.floor(y / cres)), k)
            if key in closed:
                continue
            closed.add(key)
            expanded += 1
            pose = (x, y, wrap(k * self.bin))
            if expanded % 2 == 1 or math.hypot(goal[0] - x, goal[1] - y) < 1.0:
                shot = self._shot(spaces, speeds, pose, goal)
                if shot is not None:
                    poses, vs = self._unwind(nodes, idx)
                    return poses + shot[0], vs + shot[1], expanded
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
                nodes.append(((nx, ny, wrap(nk * self.bin)), idx, speeds[lvl]))
                heapq.heappush(heap, (g + cost + h, g + cost, len(nodes) - 1, (nx, ny, nk)))
        return None, [], expanded

    @staticmethod
    def _unwind(nodes: List[Any], idx: int) -> Tuple[List[Pose], List[float]]:
        poses, vs = [], []
        while idx is not None:
            pose, parent, v = nodes[idx]
            poses.append(pose)
            vs.append(v)
            idx = parent
        return poses[::-1][1:], vs[::-1][1:]  # without the start

    def _shot(self, spaces: List["CSpace"], speeds: List[float], pose: Pose,
              goal: Pose) -> Optional[Tuple[List[Pose], List[float]]]:
        """Turn on the spot towards the goal, walk straight, turn to the goal's heading: free or None."""
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
        for prev, p in zip(path, path[1:]):
            if abs(p[0] - prev[0]) + abs(p[1] - prev[1]) < 1e-9 and abs(wrap(p[2] - prev[2])) < 1e-3:
                continue  # no turn needed
            out.append(p)
            vs.append(speeds[self._level(spaces, lambda sp, seg=(prev, p): sp.free_path(seg))])
        if not out:
            out, vs = [goal], [speeds[-1]]
        return out, vs


class CSpace:
    """Per heading bin, the cells where the robot's centre would hold an obstacle in the zone.

    Args:
        window: (x0, y0, width, height) of the grid [m, m, cells, cells].
        obstacles: H x W booleans.
        zone: the rectangle (FRONT, LEFT, BACK, RIGHT) [m].
        bin_width: heading bin [rad].
        headings: number of bins.
        arena: the centre stays inside (None: anywhere in the window).
        resolution: cell size [m].
        kernels: cache of the rotated rectangles' cell offsets, shared between plans.
        points: the obstacles as points (N x 2) for the exact check of poses the grid flags (None:
            the centres of the obstacle cells).
        turn_zone: the zone while turning on the spot (checked exactly; None: zone).
        walk_zone: curvature [1/m] -> the zone while walking on it (checked exactly where the grid,
            built for ``zone``, the largest, flags a pose); None: zone.
    """

    def __init__(self, window: Window, obstacles: np.ndarray, zone: Sequence[float], bin_width: float, headings: int,
                 arena: Optional[Arena] = None, resolution: float = 0.05, kernels: Optional[dict] = None,
                 points: Optional[np.ndarray] = None, turn_zone: Optional[Sequence[float]] = None,
                 walk_zone: Optional[Callable[[float], Sequence[float]]] = None) -> None:
        self.x0, self.y0, self.w, self.h = window[:4]
        h, w = obstacles.shape
        res = self.res = float(resolution)
        self.bin = bin_width
        self.headings = headings
        self.blocked = np.zeros((headings, h, w), dtype=bool)
        self.obstacles = obstacles
        self.zone = tuple(round(z, 6) for z in zone)
        self.kernels = kernels if kernels is not None else {}
        self.turn_zone = tuple(turn_zone) if turn_zone is not None else self.zone
        self.walk_zone = walk_zone
        self.outside = np.zeros((h, w), dtype=bool)
        if arena is not None:
            xs = self.x0 + (np.arange(w) + 0.5) * res
            ys = self.y0 + (np.arange(h) + 0.5) * res
            gx, gy = np.meshgrid(xs, ys)
            self.outside = ~arena.contains_many(np.stack([gx.ravel(), gy.ravel()], axis=1)).reshape(h, w)
        occ = np.argwhere(obstacles)
        if points is None:
            points = np.stack([self.x0 + (occ[:, 1] + 0.5) * res, self.y0 + (occ[:, 0] + 0.5) * res], axis=1)
        self.points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        self._occ = occ
        self._built = np.zeros(headings, dtype=bool)  # bins are built when first looked up

    def _build(self, k: int) -> None:
        layer = self.blocked[k]
        h, w = layer.shape
        if len(self._occ):
            kernel = self._kernel(k)
            if len(self._occ) * len(kernel) <= 300000:  # few obstacle cells: stamp the rectangle on each
                cells = (self._occ[:, None, :] - kernel[None, :, :]).reshape(-1, 2)
                ok = (cells[:, 0] >= 0) & (cells[:, 0] < h) & (cells[:, 1] >= 0) & (cells[:, 1] < w)
                layer[cells[ok, 0], cells[ok, 1]] = True
            else:  # walls: dilate by the rectangle's two sides in turn (Minkowski sum), then by a cell
                self._build_by_sides(k, layer)
        layer |= self.outside
        self._built[k] = True

    def _build_by_sides(self, k: int, layer: np.ndarray) -> None:
        res = self.res
        grow = 1.5 * res
        f, left, b, right = (z + grow for z in self.zone)
        for frac in np.linspace(-0.5, 0.5, 5):
            th = (k + frac) * self.bin
            c, s = math.cos(th), math.sin(th)
            u = np.linspace(-b, f, max(2, int(math.ceil((f + b) / (0.5 * res))) + 1))
            v = np.linspace(-right, left, max(2, int(math.ceil((left + right) / (0.5 * res))) + 1))
            # The robot at p holds an obstacle at o when o - p lies in the rectangle: p in o - R.
            side_u = set(zip(np.rint(-u * s / res).astype(int).tolist(), np.rint(-u * c / res).astype(int).tolist()))
            side_v = set(zip(np.rint(-v * c / res).astype(int).tolist(), np.rint(v * s / res).astype(int).tolist()))
            # Padded: an obstacle's first shift may leave the window and the second bring it back.
            pad = int(math.ceil(max(f, b, left, right) / res)) + 2
            src = np.pad(self.obstacles, pad)
            tmp = np.zeros_like(src)
            for dr, dc in side_u:
                _shift_or(tmp, src, dr, dc)
            full = np.zeros_like(src)
            for dr, dc in side_v:
                _shift_or(full, tmp, dr, dc)
            layer |= full[pad:-pad, pad:-pad]
        # Rounding each side's offsets on its own: the sum may be a cell off.
        grown = layer.copy()
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                _shift_or(grown, layer, dr, dc)
        layer[...] = grown

    def _kernel(self, k: int) -> np.ndarray:
        key = (self.zone, self.res, self.headings, k)
        if key not in self.kernels:
            if len(self.kernels) > 4 * self.headings * 8:
                self.kernels.clear()
            self.kernels[key] = self._make_kernel(k)
        return self.kernels[key]

    def _make_kernel(self, k: int) -> np.ndarray:
        """(drow, dcol) offsets from the robot's cell to every cell its zone may touch in bin k.

        The rectangle is grown by 1.5 cells (robot and obstacle anywhere in their cells) and rotated
        over the bin's whole span.
        """
        res = self.res
        grow = 1.5 * res
        f, left, b, right = (z + grow for z in self.zone)
        u = np.linspace(-b, f, max(2, int(math.ceil((f + b) / (0.5 * res))) + 1))
        v = np.linspace(-right, left, max(2, int(math.ceil((left + right) / (0.5 * res))) + 1))
        bu, bv = np.meshgrid(u, v)
        bu, bv = bu.ravel(), bv.ravel()
        reach = int(math.ceil(math.hypot(max(f, b), max(left, right)) / res)) + 1
        stamp = np.zeros((2 * reach + 1, 2 * reach + 1), dtype=bool)
        for frac in np.linspace(-0.5, 0.5, 5):
            th = (k + frac) * self.bin
            c, s = math.cos(th), math.sin(th)
            dx, dy = c * bu - s * bv, s * bu + c * bv
            stamp[np.rint(dy / res).astype(np.int64) + reach, np.rint(dx / res).astype(np.int64) + reach] = True
        return np.argwhere(stamp) - reach

    def _lookup(self, xs: np.ndarray, ys: np.ndarray, hs: np.ndarray, zone: Optional[Sequence[float]] = None) -> bool:
        c = np.floor((xs - self.x0) / self.res).astype(np.int64)
        r = np.floor((ys - self.y0) / self.res).astype(np.int64)
        if ((c < 0) | (r < 0) | (c >= self.w) | (r >= self.h)).any() or self.outside[r, c].any():
            return False
        k = np.rint(np.asarray(hs) / self.bin).astype(np.int64) % self.headings
        missing = ~self._built[k]
        if missing.any():
            for kk in set(k[missing].tolist()):
                self._build(kk)
        hit = self.blocked[k, r, c]
        if not hit.any():
            return True
        # The grid is conservative by 1.5 cells and a bin: judge the flagged samples exactly.
        return self._exact_free_in(xs[hit], ys[hit], np.asarray(hs)[hit], self.zone if zone is None else zone)

    def _exact_free_in(self, xs: np.ndarray, ys: np.ndarray, hs: np.ndarray, zone: Sequence[float]) -> bool:
        pts = self.points
        if not len(pts):
            return True
        reach = math.hypot(max(zone[0], zone[2]), max(zone[1], zone[3])) + EXACT_MARGIN
        near = ((pts[:, 0] > xs.min() - reach) & (pts[:, 0] < xs.max() + reach) & (pts[:, 1] > ys.min() - reach)
                & (pts[:, 1] < ys.max() + reach))
        pts = pts[near]
        if not len(pts):
            return True
        f, left, b, right = (z + EXACT_MARGIN for z in zone)
        c, s = np.cos(hs)[:, None], np.sin(hs)[:, None]
        dx, dy = pts[None, :, 0] - xs[:, None], pts[None, :, 1] - ys[:, None]
        bx, by = c * dx + s * dy, -s * dx + c * dy
        return not bool(((bx < f) & (bx > -b) & (by < left) & (by > -right)).any())

    def free_pose(self, pose: Sequence[float]) -> bool:
        """True if the zone of a robot at pose holds no obstacle cell."""
        return self._lookup(np.array([pose[0]]), np.array([pose[1]]), np.array([pose[2]]))

    def free_samples(self, x: float, y: float, samples: np.ndarray, curvature: float = 0.0) -> bool:
        """True if every relative sample (dx, dy, heading) from (x, y) is free (walking zone of the curvature)."""
        zone = self.walk_zone(curvature) if self.walk_zone is not None else None
        return self._lookup(x + samples[:, 0], y + samples[:, 1], samples[:, 2], zone)

    def free_turn(self, x: float, y: float, headings: np.ndarray) -> bool:
        """True if turning on the spot at (x, y) through the headings keeps the turning zone free."""
        if not self._lookup(np.array([x]), np.array([y]), np.array([headings[0]]) * 0.0 + headings[0]):
            # (outside the window or the arena, or the pose itself is blocked for walking: judge exactly)
            c = int(math.floor((x - self.x0) / self.res))
            r = int(math.floor((y - self.y0) / self.res))
            if not (0 <= c < self.w and 0 <= r < self.h) or self.outside[r, c]:
                return False
        n = len(headings)
        return self._exact_free_in(np.full(n, x), np.full(n, y), np.asarray(headings, dtype=np.float64), self.turn_zone)

    def free_path(self, poses: Sequence[Sequence[float]]) -> bool:
        """True if the path (linear between poses, turns on the spot) is free along its sweep."""
        for a, b in zip(poses, poses[1:]):
            if math.hypot(b[0] - a[0], b[1] - a[1]) < 1e-9:
                turn = sample_path([a, b], angle_step=0.01)
                if not self.free_turn(a[0], a[1], turn[:, 2]):
                    return False
                continue
            s = sample_path([a, b], step=0.02, angle_step=0.01)
            curvature = wrap(b[2] - a[2]) / math.hypot(b[0] - a[0], b[1] - a[1])
            if not self._lookup(s[:, 0], s[:, 1], s[:, 2],
                                self.walk_zone(curvature) if self.walk_zone is not None else None):
                return False
        return True

    def heuristic(self, goal: Sequence[float], speed: float) -> Callable[[float, float], float]:
        """A function (x, y) -> lower bound of the time to the goal [s] (inf where unreachable).

        Distances on a 2x coarser grid (8-connected Dijkstra from the goal) through the cells whose centre
        is farther from every obstacle cell than the zone's narrowest half (less 2 cells): a pose with
        any heading closer than that holds the obstacle. Never above the truth.
        """
        inner = int(math.floor(min(self.zone) / self.res)) - 2
        free = ~(dilate(self.obstacles, inner) if inner > 0 else self.obstacles) & ~self.outside
        h, w = free.shape
        ch, cw = (h + 1) // 2, (w + 1) // 2
        pad = np.zeros((ch * 2, cw * 2), dtype=bool)
        pad[:h, :w] = free
        coarse = pad.reshape(ch, 2, cw, 2).any(axis=(1, 3))
        cres = 2.0 * self.res
        gr = int((goal[1] - self.y0) / cres)
        gc = int((goal[0] - self.x0) / cres)
        dist = np.full((ch, cw), math.inf)
        if 0 <= gr < ch and 0 <= gc < cw:
            coarse[gr, gc] = True
            dist_l = dist.tolist()
            free_l = coarse.tolist()
            dist_l[gr][gc] = 0.0
            heap = [(0.0, gr, gc)]
            moves = [(-1, 0, 1.0), (1, 0, 1.0), (0, -1, 1.0), (0, 1, 1.0), (-1, -1, 1.4142), (-1, 1, 1.4142),
                     (1, -1, 1.4142), (1, 1, 1.4142)]
            while heap:
                d, r, c = heapq.heappop(heap)
                if d > dist_l[r][c]:
                    continue
                for dr, dc, step in moves:
                    nr, nc = r + dr, c + dc
                    if 0 <= nr < ch and 0 <= nc < cw and free_l[nr][nc]:
                        nd = d + step
                        if nd < dist_l[nr][nc]:
                            dist_l[nr][nc] = nd
                            heapq.heappush(heap, (nd, nr, nc))
            dist = np.array(dist_l)
        x0, y0 = self.x0, self.y0

        def heur(x: float, y: float) -> float:
            r, c = int((y - y0) / cres), int((x - x0) / cres)
            if not (0 <= r < ch and 0 <= c < cw):
                return math.inf
            # One coarse cell diagonal of slack keeps it a lower bound.
            cells = max(0.0, dist[r, c] - 1.5)
            return max(cells * cres, math.hypot(goal[0] - x, goal[1] - y)) / speed

        return heur


def speed_ahead(plan: LatticePlan, index: int, lookahead: int = 3) -> float:
    """The speed limit for following plan.poses from pose index on: the slowest of the next poses [m/s]."""
    vs = plan.speeds[max(0, index): max(0, index) + max(1, lookahead)]
    return min(vs) if vs else 0.0


def progress_index(plan: LatticePlan, pose: Sequence[float], current: int = 0, reached: float = 0.15) -> int:
    """Index of the plan's next pose for a robot at pose, never behind current.

    A pose is passed when the robot is within ``reached`` of it, or closer to the segment after it
    than to the segment before it (and past its start).
    """
    poses = plan.poses
    i = max(0, current)
    while i < len(poses) - 1:
        a = poses[i - 1] if i > 0 else poses[0]
        b, c = poses[i], poses[i + 1]
        if math.hypot(pose[0] - b[0], pose[1] - b[1]) <= reached and math.hypot(c[0] - b[0], c[1] - b[1]) > 1e-9:
            i += 1
            continue
        u2, d2 = _segment(pose, b, c)
        _, d1 = _segment(pose, a, b)
        if u2 > 0.0 and d2 < d1:
            i += 1
            continue
        break
    return i


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


def _shift_or(out: np.ndarray, src: np.ndarray, dr: int, dc: int) -> None:
    """out[r, c] |= src[r - dr, c - dc] where both are inside."""
    h, w = src.shape
    if abs(dr) >= h or abs(dc) >= w:
        return
    out[max(0, dr):h + min(0, dr), max(0, dc):w + min(0, dc)] |= src[max(0, -dr):h - max(0, dr),
                                                                     max(0, -dc):w - max(0, dc)]
