"""Configuration space of the SE(2) lattice: per heading bin, where the robot's zone would hold an obstacle. ROS-free.

The obstacle cells dilated by the stop zone's rectangle rotated over a whole heading bin, so any
heading inside the bin is covered (built lazily, bin by bin); poses the grid flags are judged exactly
against the obstacle points. Also the goal-distance heuristic of the search. Used by
:class:`rbd_controller.lattice.LatticePlanner`.
"""

import heapq
import math
from typing import Callable, Optional, Sequence, Tuple

import numpy as np
from scipy.signal import fftconvolve

from rbd_controller.arena import Arena
from rbd_controller.detour import GridMap, dilate
from rbd_controller.footprint import sample_path
from rbd_geometry.rotation import wrap_angle

Window = Tuple[float, float, int, int]  # x0, y0 [m], width, height [cells]
#: The exact check of a pose the grid flags keeps this much more around the zone: the sweep between two
#: samples (<= 0.02 m, on the spot <= 0.01 rad apart) [m]. Map cells are checked by corners and centre.
EXACT_MARGIN = 0.015


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
        points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        self.points = points[np.argsort(points[:, 0], kind="stable")]  # by x: a range is two binary searches
        self._occ = occ
        self._built = np.zeros(headings, dtype=bool)  # bins are built when first looked up

    def _build(self, k: int) -> None:
        layer = self.blocked[k]
        if len(self._occ):
            layer |= self._dilated(k)
        layer |= self.outside
        self._built[k] = True

    def _dilated(self, k: int) -> np.ndarray:
        """The obstacle cells dilated by bin k's rotated rectangle: p is blocked when p + offset is an obstacle.

        One FFT convolution of the obstacle grid with the kernel's stamp (the cost does not grow with
        the number of obstacle cells: a wall of the LiDAR map costs what a box costs).
        """
        kernel = self._kernel(k)
        reach = int(np.abs(kernel).max())
        stamp = np.zeros((2 * reach + 1, 2 * reach + 1))
        stamp[reach - kernel[:, 0], reach - kernel[:, 1]] = 1.0
        counts = fftconvolve(self.obstacles.astype(np.float64), stamp, mode="same")
        return counts > 0.5

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
        lo, hi = np.searchsorted(pts[:, 0], (xs.min() - reach, xs.max() + reach))
        pts = pts[lo:hi]
        pts = pts[(pts[:, 1] > ys.min() - reach) & (pts[:, 1] < ys.max() + reach)]
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
            curvature = wrap_angle(b[2] - a[2]) / math.hypot(b[0] - a[0], b[1] - a[1])
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


def obstacle_grid(window: Window, resolution: float, grid: Optional[GridMap], pts: np.ndarray) -> np.ndarray:
    """The window's cells (H x W booleans) holding an occupied map cell (any overlap) or an obstacle point."""
    x0, y0, w, h = window
    res = resolution
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

def exact_points(window: Window, resolution: float, grid: Optional[GridMap], pts: np.ndarray) -> np.ndarray:
    """The obstacles as points: the scan points, and each occupied map cell's centre and corners.

    Only those in the window, rounded to 5 mm and deduplicated (a scan holds thousands of points
    on the walls around; the exact check's cost grows with them).
    """
    x0, y0, w, h = window
    pts = pts.reshape(-1, 2)
    inside = (pts[:, 0] >= x0) & (pts[:, 0] <= x0 + w * resolution) & (pts[:, 1] >= y0) & (
        pts[:, 1] <= y0 + h * resolution)
    out = [np.unique(np.round(pts[inside] / 0.005), axis=0) * 0.005]
    if grid is not None and grid.occupied.ndim == 2 and grid.occupied.size:
        x0, y0, w, h = window
        r, c = np.nonzero(grid.occupied)
        gx, gy = grid.origin[0] + c * grid.resolution, grid.origin[1] + r * grid.resolution
        near = (gx > x0 - 1.0) & (gx < x0 + w * resolution + 1.0) & (gy > y0 - 1.0) & (
            gy < y0 + h * resolution + 1.0)
        gx, gy = gx[near], gy[near]
        for fx, fy in ((0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.5)):
            out.append(np.stack([gx + fx * grid.resolution, gy + fy * grid.resolution], axis=1))
    return np.concatenate(out).reshape(-1, 2)
