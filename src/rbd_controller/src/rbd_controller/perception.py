"""What the avoidance knows about the world, and its parameters. ROS-free.

The node feeds the robot pose, every LiDAR zone reading, the blocking (critical) points and
the scan points in the map frame, and the LiDAR map; the main controller's avoidance states
read the classification, the obstacles for the planner and the arena from here.
"""

import math
import threading
from typing import List, Sequence, Tuple

import numpy as np

from rbd_controller.arena import Arena, default_arena
from rbd_controller.blocking import MAX_COORD, STATIC, BlockClassifier
from rbd_controller.detour import GridMap
from rbd_controller.dodge import ApproachDetector
from rbd_controller.escape import ZoneReading

Point = Tuple[float, float]
GIVE_UP_POLICIES = ("skip", "home")
MEMORY_CELL = 0.05  # obstacle memory resolution [m]


class AvoidParams:
    """Parameters of the active collision avoidance (``~`` parameters of rbd_controller).

    Args:
        enabled: avoid static obstacles (False: wait forever, the thesis behaviour).
        dodge: step away from visitors while idle.
        blocked_timeout: stopped this long by a static obstacle before avoiding [s].
        static_after: blocking points unmoved this long count as static [s].
        low_static_after: ... and a low obstacle's (its top seen, see rbd_controller.blocking) [s]; 0 = no such rule.
        avoid_timeout: one avoidance (escape + detour) may take this long [s].
        max_detour_factor: a detour longer than this times the direct distance is refused [-].
        give_up: ``skip`` (drop the blocked pose) or ``home`` (go back to the trick's start).
        escape_margin: the escape stops when the zone is clear by this [m].
        escape_speed: speed of the escape [m/s].
        escape_max: longest single escape motion [m].
        dodge_max: the dodge stays within this of home [m].
        dodge_speed: speed of a dodge step [m/s] (<= 0.2).
        dodge_step: length of one dodge step [m].
        dodge_return_after: nothing in any slowdown band for this long => return home [s].
        inflation: detour clearance from obstacles [m] (zone side half-width + margin).
        clearance: the detour keeps this far from obstacles where it can [m].
        arena: polygon [[x, y], ...] (map frame); empty: a square of arena_half_size around home.
        arena_half_size: half side of the default arena [m].
        zone: rbd_lidar's stop zone per side (FRONT, LEFT, BACK, RIGHT) [m].
        slowdown: rbd_lidar's slowdown band per side [m].
        point_threshold: rbd_lidar's point_threshold.
        home_tolerance: a trick that ends farther than this from home (after avoiding) is followed
            by a walk back home [m].

    Raises:
        ValueError: a value out of range.
    """

    def __init__(
        self,
        enabled: bool = True,
        dodge: bool = False,
        blocked_timeout: float = 3.0,
        static_after: float = 5.0,
        low_static_after: float = 1.5,
        avoid_timeout: float = 60.0,
        max_detour_factor: float = 4.0,
        give_up: str = "skip",
        escape_margin: float = 0.15,
        escape_speed: float = 0.12,
        escape_max: float = 0.6,
        dodge_max: float = 0.5,
        dodge_speed: float = 0.2,
        dodge_step: float = 0.3,
        dodge_return_after: float = 2.0,
        inflation: float = 0.45,
        clearance: float = 0.8,
        arena: Sequence[Sequence[float]] = (),
        arena_half_size: float = 3.0,
        zone: Sequence[float] = (0.70, 0.35, 0.55, 0.35),
        slowdown: Sequence[float] = (0.50, 0.20, 0.30, 0.20),
        point_threshold: int = 5,
        home_tolerance: float = 0.2,
    ) -> None:
        positive = {
            "blocked_timeout": blocked_timeout,
            "static_after": static_after,
            "avoid_timeout": avoid_timeout,
            "max_detour_factor": max_detour_factor,
            "escape_speed": escape_speed,
            "escape_max": escape_max,
            "dodge_max": dodge_max,
            "dodge_speed": dodge_speed,
            "dodge_step": dodge_step,
            "dodge_return_after": dodge_return_after,
            "arena_half_size": arena_half_size,
            "home_tolerance": home_tolerance,
        }
        for name, v in positive.items():
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                raise ValueError("%s must be a finite number > 0, got %r" % (name, v))
        if give_up not in GIVE_UP_POLICIES:
            raise ValueError("give_up must be one of %s, got %r" % (GIVE_UP_POLICIES, give_up))
        if dodge_speed > 0.2 or escape_speed > 0.3:
            raise ValueError("dodge_speed must be <= 0.2 m/s and escape_speed <= 0.3 m/s")
        if len(zone) != 4 or len(slowdown) != 4:
            raise ValueError("zone and slowdown need 4 values (front, left, back, right)")
        self.enabled = bool(enabled)
        self.dodge = bool(dodge)
        self.blocked_timeout = float(blocked_timeout)
        self.static_after = float(static_after)
        if isinstance(low_static_after, bool) or not isinstance(low_static_after, (int, float)) or not (
                math.isfinite(low_static_after) and low_static_after >= 0):
            raise ValueError("low_static_after must be a finite number >= 0, got %r" % (low_static_after,))
        self.low_static_after = float(low_static_after)
        self.avoid_timeout = float(avoid_timeout)
        self.max_detour_factor = float(max_detour_factor)
        self.give_up = give_up
        self.escape_margin = float(escape_margin)
        self.escape_speed = float(escape_speed)
        self.escape_max = float(escape_max)
        self.dodge_max = float(dodge_max)
        self.dodge_speed = float(dodge_speed)
        self.dodge_step = float(dodge_step)
        self.dodge_return_after = float(dodge_return_after)
        self.inflation = float(inflation)
        self.clearance = float(clearance)
        self.arena = Arena(arena) if len(arena) else None
        self.arena_half_size = float(arena_half_size)
        self.zone = [float(z) for z in zone]
        self.slowdown = [float(z) for z in slowdown]
        self.point_threshold = int(point_threshold)
        self.home_tolerance = float(home_tolerance)


def _measured(points: Sequence[Point]) -> np.ndarray:
    """The points (N x 2) that can be measurements: finite and within MAX_COORD (NaN/inf are dropped)."""
    arr = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    return arr[np.all(np.isfinite(arr) & (np.abs(arr) < MAX_COORD), axis=1)]


class Perception:
    """Latest pose, zone reading, blocking points, obstacles and map (thread-safe).

    Args:
        params: the avoidance parameters.
        obstacle_memory: blocking points are kept this long for the planner [s].
        scan_memory: scan points are kept this long [s].
        shadow_depth: an obstacle is assumed this deep behind the face the LiDAR sees [m].
    """

    def __init__(self, params: AvoidParams, obstacle_memory: float = 60.0, scan_memory: float = 1.0,
                 shadow_depth: float = 0.4) -> None:
        self.params = params
        self.shadow_depth = float(shadow_depth)
        self.lock = threading.Lock()
        self.pose = None  # type: Optional[Tuple[float, float, float]]
        self.pose_time = None  # type: Optional[float]
        self._poses = []  # type: List[Tuple[float, float, float]]
        self.reading = None  # type: Optional[ZoneReading]
        self.reading_time = None  # type: Optional[float]
        self.classifier = BlockClassifier(static_after=params.static_after, low_after=params.low_static_after)
        band = [z + s for z, s in zip(params.zone, params.slowdown)]
        self.approach = ApproachDetector(band)
        self.approached = []  # type: List[int]
        self.approached_time = -math.inf
        self.grid = None  # type: Optional[GridMap]
        self.obstacle_memory = float(obstacle_memory)
        self.scan_memory = float(scan_memory)
        self._blocking = {}  # type: Dict[Tuple[int, int], float]
        self._pruned = -math.inf
        self._scan = []  # type: List[Tuple[float, np.ndarray]]
        self._static = np.zeros((0, 2))  # the blocking points last classified static
        self.known_static = np.zeros((0, 2))  # static obstacles avoided in this trick (see remember_static)
        self.arena = params.arena
        self._arena_from_map = False

    # ------------------------------------------------------------------ inputs
    def on_pose(self, now: float, x: float, y: float, yaw: float) -> None:
        """Robot pose in the map frame."""
        if all(math.isfinite(v) for v in (x, y, yaw)):
            with self.lock:
                self.pose, self.pose_time = (x, y, yaw), now
                self._poses.append((now, x, y))
                while len(self._poses) > 2 and self._poses[0][0] < now - 0.3:
                    self._poses.pop(0)

    def own_velocity(self) -> Tuple[float, float]:
        """The robot's body-frame velocity (vx, vy) over the last 0.3 s of poses [m/s]."""
        with self.lock:
            return self._own_velocity_locked()

    def _own_velocity_locked(self) -> Tuple[float, float]:
        if len(self._poses) < 2 or self.pose is None or self._poses[-1][0] - self._poses[0][0] < 0.05:
            return 0.0, 0.0
        (t0, x0, y0), (t1, x1, y1) = self._poses[0], self._poses[-1]
        vx, vy = (x1 - x0) / (t1 - t0), (y1 - y0) / (t1 - t0)
        c, s = math.cos(self.pose[2]), math.sin(self.pose[2])
        return c * vx + s * vy, -s * vx + c * vy

    def on_zone(self, now: float, reading: ZoneReading) -> None:
        """One /rbd_lidar/state."""
        with self.lock:
            self.reading, self.reading_time = reading, now
            own = self._own_velocity_locked()
            sides = self.approach.update(now, reading.min_distance, own) if reading.valid else []
            if sides:
                self.approached, self.approached_time = sides, now

    def on_blocking_points(self, now: float, points: Sequence[Point], low: bool = False) -> None:
        """The critical points of one scan, map frame; low: they are a low obstacle (rbd_controller.blocking.is_low).

        For the planner each point also stands for what the LiDAR cannot see behind it: the
        obstacle is assumed to extend ``shadow_depth`` further along the ray from the robot (a
        box seen by its face is that deep; a wall, deeper than that anyway).
        """
        arr = _measured(points)
        with self.lock:
            self.classifier.update(now, arr, low)
            if len(arr):
                thin = arr[:: max(1, len(arr) // 400)]
                if self.pose is not None and self.shadow_depth > 0.0:
                    ray = thin - np.array(self.pose[:2])
                    ray /= np.maximum(np.hypot(ray[:, 0], ray[:, 1]), 1e-6)[:, None]
                    steps = np.arange(0.1, self.shadow_depth + 1e-9, 0.1)
                    thin = np.concatenate([thin] + [thin + d * ray for d in steps])
                # Remembered as 5 cm cells with the time last seen (bounded however long it stands).
                for key in set(map(tuple, np.floor(thin / MEMORY_CELL).astype(np.int64).tolist())):
                    self._blocking[key] = now
            if now - self._pruned > 1.0:
                self._pruned = now
                old = now - self.obstacle_memory
                self._blocking = {k: t for k, t in self._blocking.items() if t >= old}

    def on_scan_points(self, now: float, points: Sequence[Point]) -> None:
        """Obstacle points of one scan (the central ring), map frame."""
        arr = _measured(points)
        with self.lock:
            self._scan.append((now, arr))
            while self._scan and self._scan[0][0] < now - self.scan_memory:
                self._scan.pop(0)

    def on_map(self, grid: GridMap) -> None:
        """A new LiDAR map."""
        with self.lock:
            self.grid = grid

    # ------------------------------------------------------------------ queries
    def obstacles(self, since: float = -math.inf) -> np.ndarray:
        """Blocking points (cell centres) seen since ``since`` plus the recent scan points (N x 2)."""
        with self.lock:
            cells = [k for k, t in self._blocking.items() if t >= since]
            parts = [a for _, a in self._scan]
        if cells:
            parts.append((np.asarray(cells, dtype=np.float64) + 0.5) * MEMORY_CELL)
        return np.concatenate(parts) if parts else np.zeros((0, 2))

    def forget_blocking(self) -> None:
        """Drop the remembered blocking points and the classification history."""
        with self.lock:
            self._blocking = {}
            self.classifier.reset()

    def classify(self) -> Tuple[str, str]:
        """(classification, reason) of the blocking points (see rbd_controller.blocking).

        Points on a remembered static obstacle (:meth:`remember_static`) count like map points.
        """
        with self.lock:
            grid = self.grid
            occupied = (lambda x, y: grid.is_occupied(x, y)) if grid is not None else None
            result = self.classifier.classify(occupied, self.known_static)
            if result == STATIC:
                self._static = self.classifier.latest()
            return result, self.classifier.reason

    @property
    def low_match(self) -> bool:
        """The last :meth:`classify` found the blocker static by the low-obstacle rule."""
        with self.lock:
            return self.classifier.low_match

    @property
    def known_match(self) -> bool:
        """The last :meth:`classify` found the blocker on a remembered static obstacle."""
        with self.lock:
            return self.classifier.known_match

    def remember_static(self) -> None:
        """A detour is planned around the blocker last classified static: keep it static (issue 27).

        Remembered are the obstacle memory's cells within ``shadow_depth`` + 0.1 m of the points
        classified static (so the obstacle's depth behind the face seen, and later faces of it, are
        known too). Until :meth:`forget_static`, a stop at them is classified static after the map's
        short confirmation instead of ``static_after``; motion still wins at once.
        """
        with self.lock:
            if not len(self._static):
                return
            parts = [self.known_static, self._static]
            if self._blocking:
                cells = (np.asarray(list(self._blocking), dtype=np.float64) + 0.5) * MEMORY_CELL
                reach = self.shadow_depth + 0.1
                near = np.zeros(len(cells), dtype=bool)
                for x, y in self._static:
                    near |= np.hypot(cells[:, 0] - x, cells[:, 1] - y) <= reach
                parts.append(cells[near])
            keys = np.unique(np.floor(np.concatenate(parts) / MEMORY_CELL).astype(np.int64), axis=0)
            self.known_static = (keys + 0.5) * MEMORY_CELL

    def forget_static(self) -> None:
        """Drop the remembered static obstacles (the trick is over)."""
        with self.lock:
            self._static = np.zeros((0, 2))
            self.known_static = np.zeros((0, 2))

    def recently_approached(self, now: float, within: float = 0.5) -> List[int]:
        """Sides something approached within the last ``within`` seconds."""
        with self.lock:
            return list(self.approached) if now - self.approached_time <= within else []

    def quiet_for(self, now: float) -> float:
        """Seconds since anything was in a slowdown band."""
        with self.lock:
            return self.approach.quiet_for(now)

    def ensure_arena(self, home: Point) -> Arena:
        """The configured arena, or the default one around home (cut to the explored map)."""
        with self.lock:
            if self.arena is None or (self.params.arena is None and not self._arena_from_map and self.grid):
                explored = self.grid.explored_bounds() if self.grid is not None else None
                self.arena = default_arena(home, self.params.arena_half_size, explored)
                self._arena_from_map = explored is not None
            return self.arena
