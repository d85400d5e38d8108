"""The arena: the floor polygon that no avoidance motion leaves. ROS-free.

Configured as ``~arena`` (a list of [x, y] vertices in the map frame); by default a square of
``~arena_half_size`` around the robot's start pose, cut to the bounding box of the LiDAR map's
explored cells (shrunk by a margin) once the map is there. Tricks are not limited by it; every
escape target, dodge target and detour pose is.
"""

import math
from typing import Optional, Sequence, Tuple

import numpy as np

Point = Tuple[float, float]


class Arena:
    """A simple polygon (at least 3 vertices, any orientation, not self-intersecting).

    Args:
        vertices: [(x, y), ...] in the map frame [m].

    Raises:
        ValueError: fewer than 3 finite vertices or zero area.
    """

    def __init__(self, vertices: Sequence[Sequence[float]]) -> None:
        pts = []
        for v in vertices:
            if len(v) != 2 or not all(isinstance(c, (int, float)) and math.isfinite(c) for c in v):
                raise ValueError("arena vertices must be [x, y] pairs of finite numbers, got %r" % (v,))
            pts.append((float(v[0]), float(v[1])))
        if len(pts) < 3:
            raise ValueError("arena needs at least 3 vertices, got %d" % len(pts))
        area = 0.5 * sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(pts, pts[1:] + pts[:1]))
        if abs(area) < 1e-6:
            raise ValueError("arena polygon has no area")
        self.vertices = pts

    @classmethod
    def rectangle(cls, x0: float, y0: float, x1: float, y1: float) -> "Arena":
        """Axis-aligned rectangle between two corners."""
        return cls([(x0, y0), (x1, y0), (x1, y1), (x0, y1)])

    def bounds(self) -> Tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax)."""
        xs = [p[0] for p in self.vertices]
        ys = [p[1] for p in self.vertices]
        return min(xs), min(ys), max(xs), max(ys)

    def contains(self, x: float, y: float) -> bool:
        """True if (x, y) is inside (even-odd rule; points on an edge may go either way)."""
        return bool(self.contains_many(np.array([[x, y]]))[0])

    def contains_many(self, xy: np.ndarray) -> np.ndarray:
        """Boolean mask of the points (N x 2) inside the polygon."""
        xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        x, y = xy[:, 0], xy[:, 1]
        inside = np.zeros(len(xy), dtype=bool)
        pts = self.vertices
        for (x1, y1), (x2, y2) in zip(pts, pts[1:] + pts[:1]):
            crosses = (y1 > y) != (y2 > y)
            with np.errstate(divide="ignore", invalid="ignore"):
                xc = x1 + (y - y1) * (x2 - x1) / (y2 - y1)
            inside ^= crosses & (x < xc)
        return inside

    def edge_distance(self, x: float, y: float) -> float:
        """Distance from (x, y) to the nearest edge [m] (positive inside and outside)."""
        best = math.inf
        pts = self.vertices
        for (x1, y1), (x2, y2) in zip(pts, pts[1:] + pts[:1]):
            dx, dy = x2 - x1, y2 - y1
            len2 = dx * dx + dy * dy
            u = 0.0 if len2 == 0 else max(0.0, min(1.0, ((x - x1) * dx + (y - y1) * dy) / len2))
            best = min(best, math.hypot(x - x1 - u * dx, y - y1 - u * dy))
        return best

    def segment_inside(self, a: Point, b: Point, step: float = 0.02) -> bool:
        """True if the straight motion from a to b stays inside (sampled every ``step`` m); False if not finite."""
        if not all(math.isfinite(v) for v in tuple(a) + tuple(b)):
            return False
        x0, y0, x1, y1 = self.bounds()
        if math.hypot(b[0] - a[0], b[1] - a[1]) > math.hypot(x1 - x0, y1 - y0):
            return False  # longer than the arena is wide
        n = max(2, int(math.ceil(math.hypot(b[0] - a[0], b[1] - a[1]) / step)) + 1)
        u = np.linspace(0.0, 1.0, n)
        xy = np.stack([a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])], axis=1)
        return bool(np.all(self.contains_many(xy)))

    def reach(self, start: Point, direction: Point, distance: float, margin: float = 0.0, step: float = 0.02) -> float:
        """How far [m] (<= distance) one can move from start along a unit direction and stay inside.

        ``margin`` is kept to the edges; 0 if start itself is outside.
        """
        if not self.contains(*start) or not all(math.isfinite(v) for v in direction) or not distance > 0.0:
            return 0.0
        norm = math.hypot(direction[0], direction[1])
        if norm < 1e-9:
            return 0.0
        x0, y0, x1, y1 = self.bounds()
        distance = min(distance, math.hypot(x1 - x0, y1 - y0) / norm)  # beyond that it is outside anyway
        d = 0.0
        while d + step <= distance + 1e-9:
            x, y = start[0] + (d + step) * direction[0], start[1] + (d + step) * direction[1]
            if not self.contains(x, y) or (margin > 0.0 and self.edge_distance(x, y) < margin):
                break
            d += step
        return d


def default_arena(
    home: Point, half_size: float, explored: Optional[Tuple[float, float, float, float]] = None, margin: float = 0.3
) -> Arena:
    """Square of half_size around home, cut to the explored map's bounding box shrunk by margin.

    Args:
        home: the start pose's position [m].
        half_size: half the square's side [m].
        explored: (xmin, ymin, xmax, ymax) of the map's known cells, or None.
        margin: the explored box is shrunk by this [m].

    Returns:
        The arena (the square alone if the cut would leave less than 1 m x 1 m around home).
    """
    x0, y0, x1, y1 = home[0] - half_size, home[1] - half_size, home[0] + half_size, home[1] + half_size
    if explored is not None:
        cx0, cy0 = max(x0, explored[0] + margin), max(y0, explored[1] + margin)
        cx1, cy1 = min(x1, explored[2] - margin), min(y1, explored[3] - margin)
        if cx0 <= home[0] - 0.5 and cy0 <= home[1] - 0.5 and cx1 >= home[0] + 0.5 and cy1 >= home[1] + 0.5:
            x0, y0, x1, y1 = cx0, cy0, cx1, cy1
    return Arena.rectangle(x0, y0, x1, y1)
