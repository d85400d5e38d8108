"""Detour planning: A* on an inflated occupancy grid, simplified to a few poses. ROS-free.

The grid is the LiDAR map (rbd_localization's ``/map``, occupied cells) plus the obstacle
points of the current scans, in a window around the start and the goal. Every obstacle is
inflated by ``inflation`` (the LiDAR zone's side half-width plus a margin: a robot whose centre
keeps that distance has the obstacle outside its side zones), cells outside the arena are
blocked, and a soft cost keeps the path away from obstacles up to ``clearance``. The cell path
is cut to the waypoints where it turns (line of sight through free cells), which the position
controller then drives one by one (turn towards the next, walk straight). Why a grid search and
not OMPL: see the rbd_controller README ("Detour planner").
"""

import heapq
import math
from typing import List, Optional, Sequence, Tuple

import numpy as np

from rbd_controller.arena import Arena

Point = Tuple[float, float]
SQRT2 = math.sqrt(2.0)
#: Start and goal farther apart than this are refused (the window would be needlessly large) [m].
MAX_DETOUR_SPAN = 30.0


class GridMap:
    """An occupancy grid: boolean ``occupied[row, col]``, row = y, origin = the (0, 0) cell's corner.

    Args:
        occupied: H x W booleans.
        origin: (x, y) of the grid's lower-left corner in the map frame [m].
        resolution: cell size [m].
        known: optional H x W booleans, True where the map has seen the cell.
    """

    def __init__(
        self, occupied: np.ndarray, origin: Point, resolution: float, known: Optional[np.ndarray] = None
    ) -> None:
        self.occupied = np.asarray(occupied, dtype=bool)
        self.origin = (float(origin[0]), float(origin[1]))
        self.resolution = float(resolution)
        self.known = None if known is None else np.asarray(known, dtype=bool)

    @classmethod
    def from_occupancy(
        cls, data: Sequence[int], width: int, height: int, origin: Point, resolution: float, threshold: int = 50
    ) -> "GridMap":
        """From nav_msgs/OccupancyGrid values (0..100, -1 unknown), row-major from the origin."""
        arr = np.asarray(data, dtype=np.int16).reshape(int(height), int(width))
        return cls(arr >= threshold, origin, resolution, known=arr >= 0)

    def cell(self, x: float, y: float) -> Tuple[int, int]:
        """(row, col) of a point (may be outside the grid)."""
        return (
            int(math.floor((y - self.origin[1]) / self.resolution)),
            int(math.floor((x - self.origin[0]) / self.resolution)),
        )

    def is_occupied(self, x: float, y: float, radius_cells: int = 1) -> bool:
        """True if an occupied cell lies within radius_cells of the point's cell."""
        r, c = self.cell(x, y)
        h, w = self.occupied.shape
        r0, r1, c0, c1 = (
            max(0, r - radius_cells),
            min(h, r + radius_cells + 1),
            max(0, c - radius_cells),
            min(w, c + radius_cells + 1),
        )
        if r0 >= r1 or c0 >= c1:
            return False
        return bool(self.occupied[r0:r1, c0:c1].any())

    def explored_bounds(self) -> Optional[Tuple[float, float, float, float]]:
        """(xmin, ymin, xmax, ymax) of the known cells, None if none are known."""
        if self.known is None or not self.known.any():
            return None
        rows = np.nonzero(self.known.any(axis=1))[0]
        cols = np.nonzero(self.known.any(axis=0))[0]
        res = self.resolution
        return (
            self.origin[0] + cols[0] * res,
            self.origin[1] + rows[0] * res,
            self.origin[0] + (cols[-1] + 1) * res,
            self.origin[1] + (rows[-1] + 1) * res,
        )


class Plan:
    """A planner answer.

    Attributes:
        ok: a path was found.
        waypoints: poses to drive (without the start), the goal last.
        length: path length [m] (through the waypoints).
        direct: straight start-goal distance [m].
        reason: why it failed (or a summary).
        cells: the raw A* cell path as (x, y) points (for plots and RViz).
        expanded: A* expansions (cost figure).
    """

    def __init__(
        self,
        ok: bool,
        waypoints: List[Point],
        length: float,
        direct: float,
        reason: str,
        cells: Optional[List[Point]] = None,
        expanded: int = 0,
    ) -> None:
        self.ok = ok
        self.waypoints = waypoints
        self.length = length
        self.direct = direct
        self.reason = reason
        self.cells = cells or []
        self.expanded = expanded

    def __repr__(self) -> str:
        """Readable form for logs."""
        return "Plan(ok=%s, %d waypoints, %.2f m vs %.2f m direct, %s)" % (
            self.ok,
            len(self.waypoints),
            self.length,
            self.direct,
            self.reason,
        )


def finite_points(points: Sequence[Point]) -> np.ndarray:
    """Points as an N x 2 float array without the rows holding NaN or inf (bad returns are dropped)."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    return pts[np.isfinite(pts).all(axis=1)]


def _disk(radius_cells: int) -> List[Tuple[int, int]]:
    r = int(radius_cells)
    return [(dr, dc) for dr in range(-r, r + 1) for dc in range(-r, r + 1) if dr * dr + dc * dc <= r * r]


def dilate(mask: np.ndarray, radius_cells: int) -> np.ndarray:
    """Binary dilation of a mask with a disk (numpy shifts; no SciPy on the robot)."""
    out = mask.copy()
    h, w = mask.shape
    for dr, dc in _disk(radius_cells):
        if dr == 0 and dc == 0:
            continue
        src = mask[max(0, -dr) : h - max(0, dr), max(0, -dc) : w - max(0, dc)]
        out[max(0, dr) : h - max(0, -dr), max(0, dc) : w - max(0, -dc)] |= src
    return out


def distance_field(obstacles: np.ndarray, max_cells: int) -> np.ndarray:
    """Approximate Euclidean distance (in cells) to the nearest obstacle, capped at max_cells.

    Computed from dilations with growing disks (exact at integer radii).
    """
    dist = np.full(obstacles.shape, float(max_cells))
    dist[obstacles] = 0.0
    covered = obstacles.copy()
    for r in range(1, max_cells + 1):
        grown = dilate(obstacles, r)
        dist[grown & ~covered] = r
        covered |= grown
    return dist


def zone_occupied_at(goal: Tuple[float, float, float], zone: Sequence[float], points: Sequence[Point],
                     margin: float = 0.05) -> int:
    """Obstacle points inside the stop zone of a robot standing at goal (x, y, yaw).

    Args:
        goal: the pose [m, m, rad].
        zone: stop-zone limits (FRONT, LEFT, BACK, RIGHT) [m], rbd_lidar's zone_*.
        points: obstacle points in the map frame [m].
        margin: added to every side [m].

    Returns:
        The number of points inside (a goal with points inside cannot be held: the zone would stop
        the robot there).
    """
    pts = finite_points(points)
    if not len(pts):
        return 0
    c, s = math.cos(goal[2]), math.sin(goal[2])
    dx, dy = pts[:, 0] - goal[0], pts[:, 1] - goal[1]
    bx, by = c * dx + s * dy, -s * dx + c * dy
    inside = (bx < zone[0] + margin) & (by < zone[1] + margin) & (bx > -zone[2] - margin) & (by > -zone[3] - margin)
    return int(inside.sum())


class DetourPlanner:
    """Grid A* around blocking obstacles.

    Args:
        inflation: obstacles are grown by this [m] (zone side half-width + margin).
        clearance: a soft cost keeps the path this far from obstacles where it can [m].
        resolution: planning cell size [m].
        window_margin: the planning window extends this far beyond start and goal [m].
        clearance_weight: weight of the soft cost (0 = shortest path).
        max_expansions: A* gives up after this many expansions.
    """

    def __init__(
        self,
        inflation: float = 0.45,
        clearance: float = 0.8,
        resolution: float = 0.05,
        window_margin: float = 1.5,
        clearance_weight: float = 2.0,
        max_expansions: int = 60000,
    ) -> None:
        if not 0.0 < resolution <= 0.5 or inflation < 0.0 or clearance < inflation:
            raise ValueError("need 0 < resolution <= 0.5, inflation >= 0 and clearance >= inflation")
        self.inflation = float(inflation)
        self.clearance = float(clearance)
        self.resolution = float(resolution)
        self.window_margin = float(window_margin)
        self.clearance_weight = float(clearance_weight)
        self.max_expansions = int(max_expansions)

    def plan(
        self,
        start: Point,
        goal: Point,
        grid: Optional[GridMap] = None,
        points: Sequence[Point] = (),
        arena: Optional[Arena] = None,
    ) -> Plan:
        """Plan from start to goal (map frame).

        Args:
            start: robot position [m].
            goal: the blocked trick pose's position [m].
            grid: the LiDAR map (may be None).
            points: obstacle points of the current scans [m].
            arena: cells outside are blocked (None: no limit).

        Returns:
            A Plan; ``ok`` False with the reason when the goal is blocked, outside the arena, or
            unreachable.
        """
        try:
            return self._plan(start, goal, grid, points, arena)
        except (ArithmeticError, IndexError, MemoryError, TypeError, ValueError) as err:
            # Last line of defence: the checks in _plan() should make this unreachable (the property
            # tests assert that no scene ends here), but a planner error must never kill the node.
            return Plan(False, [], 0.0, math.nan, "planner error: %s: %s" % (type(err).__name__, err))

    def _plan(
        self,
        start: Point,
        goal: Point,
        grid: Optional[GridMap],
        points: Sequence[Point],
        arena: Optional[Arena],
    ) -> Plan:
        if not all(math.isfinite(float(v)) for v in (start[0], start[1], goal[0], goal[1])):
            return Plan(False, [], 0.0, math.nan, "start or goal not finite: %r -> %r" % (start, goal))
        direct = math.hypot(goal[0] - start[0], goal[1] - start[1])
        if direct > MAX_DETOUR_SPAN:
            return Plan(False, [], 0.0, direct, "goal %.1f m away: beyond the planner's %.0f m" % (
                direct, MAX_DETOUR_SPAN))
        res = self.resolution
        m = self.window_margin
        x0, y0 = min(start[0], goal[0]) - m, min(start[1], goal[1]) - m
        x1, y1 = max(start[0], goal[0]) + m, max(start[1], goal[1]) + m
        w, h = int(math.ceil((x1 - x0) / res)), int(math.ceil((y1 - y0) / res))
        obstacles = np.zeros((h, w), dtype=bool)
        xs = x0 + (np.arange(w) + 0.5) * res
        ys = y0 + (np.arange(h) + 0.5) * res
        if grid is not None:
            # Sample the map at the window's cell centres.
            gc = np.floor((xs - grid.origin[0]) / grid.resolution).astype(np.int64)
            gr = np.floor((ys - grid.origin[1]) / grid.resolution).astype(np.int64)
            gh, gw = grid.occupied.shape
            vc, vr = (gc >= 0) & (gc < gw), (gr >= 0) & (gr < gh)
            sub = np.zeros((h, w), dtype=bool)
            sub[np.ix_(vr, vc)] = grid.occupied[np.ix_(gr[vr], gc[vc])]
            obstacles |= sub
        pts = finite_points(points)
        if len(pts):
            c = np.floor((pts[:, 0] - x0) / res).astype(np.int64)
            r = np.floor((pts[:, 1] - y0) / res).astype(np.int64)
            ok = (c >= 0) & (c < w) & (r >= 0) & (r < h)
            obstacles[r[ok], c[ok]] = True
        infl_cells = int(math.ceil(self.inflation / res))
        soft_cells = max(infl_cells, int(math.ceil(self.clearance / res)))
        dist = distance_field(obstacles, soft_cells) * res
        blocked = dist < self.inflation
        outside = np.zeros((h, w), dtype=bool)
        if arena is not None:
            gx, gy = np.meshgrid(xs, ys)
            outside = ~arena.contains_many(np.stack([gx.ravel(), gy.ravel()], axis=1)).reshape(h, w)
        # Start and goal are at least window_margin inside the window; clip for a zero margin.
        sr, sc = min(h - 1, int((start[1] - y0) / res)), min(w - 1, int((start[0] - x0) / res))
        gr_, gc_ = min(h - 1, int((goal[1] - y0) / res)), min(w - 1, int((goal[0] - x0) / res))
        if arena is not None and not arena.contains(*goal):
            return Plan(False, [], 0.0, direct, "goal outside the arena")
        if blocked[gr_, gc_]:
            return Plan(False, [], 0.0, direct, "goal blocked: an obstacle within %.2f m of the goal" % self.inflation)
        # The robot may start inside the inflation (it escaped only as far as the zone needs):
        # cells around the start that are no closer to an obstacle than the start are allowed.
        d_start = dist[sr, sc]
        if blocked[sr, sc]:
            gx, gy = np.meshgrid((np.arange(w) - sc) * res, (np.arange(h) - sr) * res)
            near = np.hypot(gx, gy) <= self.inflation
            blocked = blocked & ~(near & (dist >= d_start - 1e-9) & (dist > 0.0))
        blocked = blocked | outside
        cost_extra = np.where(
            dist < self.clearance,
            self.clearance_weight * (self.clearance - dist) / max(self.clearance - self.inflation, 1e-6),
            0.0,
        )
        path, expanded = self._astar(blocked, cost_extra, (sr, sc), (gr_, gc_))
        if path is None:
            return Plan(
                False, [], 0.0, direct, "no path around the obstacle (%d cells searched)" % expanded, expanded=expanded
            )
        cells_xy = [(x0 + (c + 0.5) * res, y0 + (r + 0.5) * res) for r, c in path]
        keep = self._simplify(path, blocked)
        # The cells between start and goal, then the goal itself (its cell's centre is replaced).
        # Start and goal in one cell: the cell path is that one cell and the goal is all there is.
        waypoints = [(x0 + (c + 0.5) * res, y0 + (r + 0.5) * res) for r, c in keep[1:-1]]
        waypoints.append((float(goal[0]), float(goal[1])))
        length = 0.0
        prev = start
        for p in waypoints:
            length += math.hypot(p[0] - prev[0], p[1] - prev[1])
            prev = p
        return Plan(
            True, waypoints, length, direct, "%d waypoints, %.2f m" % (len(waypoints), length), cells_xy, expanded
        )

    def _astar(
        self, blocked: np.ndarray, extra: np.ndarray, start: Tuple[int, int], goal: Tuple[int, int]
    ) -> Tuple[Optional[List[Tuple[int, int]]], int]:
        h, w = blocked.shape
        moves = [
            (-1, 0, 1.0),
            (1, 0, 1.0),
            (0, -1, 1.0),
            (0, 1, 1.0),
            (-1, -1, SQRT2),
            (-1, 1, SQRT2),
            (1, -1, SQRT2),
            (1, 1, SQRT2),
        ]
        gr, gc = goal

        def heur(r: int, c: int) -> float:
            dr, dc = abs(r - gr), abs(c - gc)
            return (dr + dc) + (SQRT2 - 2.0) * min(dr, dc)

        g = {start: 0.0}
        parent = {start: None}
        heap = [(heur(*start), 0.0, start)]
        closed = set()
        expanded = 0
        blocked_l = blocked.tolist()
        extra_l = extra.tolist()
        while heap:
            _, cost, node = heapq.heappop(heap)
            if node in closed:
                continue
            closed.add(node)
            expanded += 1
            if node == goal:
                path = []
                while node is not None:
                    path.append(node)
                    node = parent[node]
                return path[::-1], expanded
            if expanded > self.max_expansions:
                break
            r, c = node
            for dr, dc, step in moves:
                nr, nc = r + dr, c + dc
                if nr < 0 or nc < 0 or nr >= h or nc >= w or blocked_l[nr][nc]:
                    continue
                if dr and dc and (blocked_l[r][nc] or blocked_l[nr][c]):
                    continue  # no corner cutting
                ng = cost + step * (1.0 + extra_l[nr][nc])
                if ng < g.get((nr, nc), math.inf):
                    g[(nr, nc)] = ng
                    parent[(nr, nc)] = node
                    heapq.heappush(heap, (ng + heur(nr, nc), ng, (nr, nc)))
        return None, expanded

    @staticmethod
    def _line_free(blocked: np.ndarray, a: Tuple[int, int], b: Tuple[int, int]) -> bool:
        n = max(abs(b[0] - a[0]), abs(b[1] - a[1])) * 2 + 1
        rs = np.rint(np.linspace(a[0], b[0], n)).astype(np.int64)
        cs = np.rint(np.linspace(a[1], b[1], n)).astype(np.int64)
        return not bool(blocked[rs, cs].any())

    def _simplify(self, path: List[Tuple[int, int]], blocked: np.ndarray) -> List[Tuple[int, int]]:
        """Keep the cells where the path must turn: from each kept cell, the farthest one in sight."""
        keep = [path[0]]
        i = 0
        while i < len(path) - 1:
            j = len(path) - 1
            while j > i + 1 and not self._line_free(blocked, path[i], path[j]):
                j -= 1
            keep.append(path[j])
            i = j
        return keep
