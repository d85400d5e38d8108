"""What blocks the robot: static (a wall, a bag put down) or moving (a person). ROS-free.

Fed with the critical points of every scan (rbd_lidar's ``collision_points``) in the map
frame while the robot stands stopped. The blocker is *moving* as soon as the set moved (its
points are no longer near the earlier ones, or its centroid shifted), whatever the map says;
*static* when the point set stayed where it was for ``static_after`` seconds, or already after
``map_confirm`` seconds when its points lie on the LiDAR map (occupied cells). The map alone is no
proof: it is built live from the scans (rbd_localization's log-odds map), so a visitor who walks
the same loop, or stood somewhere while the map grew, is on it too; being unmoved for
``map_confirm`` (a person walking at 0.3 m/s or faster has moved by more than ``max_shift``)
is what makes the map's verdict count. People are waited for, as the thesis robot does; only static blockers start
the avoidance. Points on an obstacle already classified static and avoided during this trick
(``known``) are static when every scan of the last ``map_confirm`` lies on it (>= 90 % of the
points) and did not move (tighter than the normal test): what the robot saw of it before the stop
(its own motion changes the part in the zone) is not taken for motion, so a robot going around it
does not start from "unknown" at each stop (issue 27). Anything else in the zone (a person) keeps
the normal classification, so a moving person is still waited for at once.
A person who stands still for ``static_after`` counts as static: the avoidance
then steps away from them and walks around, never towards (the position controller's zone
guard), and a person who starts to move again is classified moving at the next scan.
"""

import math
from typing import Callable, Optional, Sequence, Tuple

import numpy as np

Point = Tuple[float, float]

CELL = 0.05  # thinning cell [m]
CLEAR = "clear"  # no blocking points in the last scan
UNKNOWN = "unknown"  # not observed for static_after yet, no motion seen
STATIC = "static"
MOVING = "moving"
#: A stop counts as the known static obstacle when at least this fraction of the points of every scan of
#: the last map_confirm lies on it.
KNOWN_FRACTION = 0.9
#: Coordinates beyond this are no measurement (they would overflow the cell hashing) [m].
MAX_COORD = 1e6


def near_fraction(points: np.ndarray, reference: np.ndarray, radius: float) -> float:
    """Fraction of ``points`` (N x 2) with a point of ``reference`` (M x 2) within about ``radius`` [m].

    Cell hashing at the radius (vectorised): a neighbour is any reference point in the 3 x 3
    cells around a point's cell (so "within radius" up to a factor of 2 sqrt(2)).
    """
    if len(points) == 0:
        return 1.0
    if len(reference) == 0:
        return 0.0
    ref = np.floor(reference / radius).astype(np.int64)
    keys = np.floor(points / radius).astype(np.int64)
    big = np.int64(1 << 31)
    ref_keys = np.unique(ref[:, 0] * big + ref[:, 1])
    near = np.zeros(len(keys), dtype=bool)
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            near |= np.isin((keys[:, 0] + dx) * big + (keys[:, 1] + dy), ref_keys)
    return float(near.mean())


class BlockClassifier:
    """Static/moving classification of the blocking points over the last scans.

    Args:
        static_after: seconds the points must stay put to count as static (``~static_after``).
        match_radius: a point "stayed" if an earlier scan had a point this close [m] (LiDAR
            noise ±30 mm plus the robot's own pose noise).
        min_match: fraction of points (both ways) that must match for "unchanged".
        max_shift: centroid shift that counts as motion [m].
        map_fraction: fraction of points on occupied map cells that makes them static after
            ``map_confirm``.
        map_confirm: seconds points on the map must stay unmoved to count as static [s] (capped
            at static_after).
        horizon: scans older than this are forgotten [s].
        max_gap: scans without blocking points for longer than this end the observation [s].

    Raises:
        ValueError: non-positive static_after, match_radius or horizon.
    """

    def __init__(
        self,
        static_after: float = 2.0,
        match_radius: float = 0.1,
        min_match: float = 0.6,
        max_shift: float = 0.12,
        map_fraction: float = 0.7,
        map_confirm: float = 0.5,
        horizon: float = 10.0,
        max_gap: float = 1.5,
    ) -> None:
        for name, v in (("static_after", static_after), ("match_radius", match_radius), ("horizon", horizon),
                        ("map_confirm", map_confirm)):
            if not math.isfinite(v) or v <= 0.0:
                raise ValueError("%s must be a finite number > 0, got %r" % (name, v))
        self.static_after = float(static_after)
        self.match_radius = float(match_radius)
        self.min_match = float(min_match)
        self.max_shift = float(max_shift)
        self.map_fraction = float(map_fraction)
        self.map_confirm = min(float(map_confirm), self.static_after)
        self.horizon = max(float(horizon), self.static_after + 1.0)
        self.max_gap = float(max_gap)
        self.scans = []  # type: List[Tuple[float, np.ndarray]]
        self.reason = ""
        self.known_match = False  # the last STATIC came from the known obstacle

    def reset(self) -> None:
        """Forget the history (the robot moved, or a new stop began)."""
        self.scans = []
        self.reason = ""

    def update(self, t: float, points: Sequence[Point]) -> None:
        """Add one scan's blocking points (map frame) received at time t [s]."""
        arr = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        arr = arr[np.all(np.isfinite(arr) & (np.abs(arr) < MAX_COORD), axis=1)]  # NaN/inf/absurd: no point
        if len(arr):  # thin to one point per 5 cm cell: thousands of critical points become tens
            arr = (np.unique(np.floor(arr / CELL).astype(np.int64), axis=0) + 0.5) * CELL
        if self.scans and t < self.scans[-1][0]:
            self.reset()  # clock jumped back
        self.scans.append((float(t), arr))
        while self.scans and self.scans[0][0] < t - self.horizon:
            self.scans.pop(0)

    def latest(self) -> np.ndarray:
        """The last scan's points (N x 2), empty before the first."""
        return self.scans[-1][1] if self.scans else np.zeros((0, 2))

    def _on_known(self, known: Optional[np.ndarray]) -> Optional[float]:
        """The smallest fraction of points on known over the last map_confirm; None unless all scans are on it, unmoved.

        Only the known obstacle's points count (within half the match radius): whatever else shows up
        (a person) keeps the normal classification. The scans of the last map_confirm must not have
        moved against the latest one either (the robot stands; a person beside the box moves).
        """
        if known is None or not len(known) or self.scans[0][0] > self.scans[-1][0] - self.map_confirm:
            return None
        known = np.asarray(known, dtype=np.float64).reshape(-1, 2)
        t_last, last = self.scans[-1]
        window = [pts for t, pts in self.scans if t >= t_last - self.map_confirm and len(pts)]
        if len(window) < 3:
            return None
        fractions = [near_fraction(pts, known, self.match_radius / 2.0) for pts in window]
        if min(fractions) < KNOWN_FRACTION:
            return None
        centre = last.mean(axis=0)
        for pts in window[:-1]:
            if (float(np.hypot(*(pts.mean(axis=0) - centre))) > self.max_shift / 2.0
                    or near_fraction(last, pts, self.match_radius / 2.0) < self.min_match
                    or near_fraction(pts, last, self.match_radius / 2.0) < self.min_match):
                return None
        return min(fractions)

    def classify(self, occupied: Optional[Callable[[float, float], bool]] = None,
                 known: Optional[np.ndarray] = None) -> str:
        """CLEAR, UNKNOWN, STATIC or MOVING for the history so far; ``reason`` says why.

        Args:
            occupied: (x, y) -> True if the map has an obstacle there (None: no map).
            known: points (N x 2) of obstacles already classified static and avoided (None: none);
                ``known_match`` tells whether a STATIC came from them.
        """
        self.known_match = False
        if not self.scans or len(self.scans[-1][1]) == 0:
            self.reason = "no blocking points"
            return CLEAR
        t_last, last = self.scans[-1]
        on_known = self._on_known(known)
        if on_known is not None:
            self.known_match = True
            self.reason = "%.0f %% of the blocking points are on the static obstacle being avoided for %.1f s" % (
                100.0 * on_known, self.map_confirm)
            return STATIC
        centre = last.mean(axis=0)
        oldest = t_last
        next_check = 0.0  # compare with about ten scans per static_after, not every one
        seen = t_last  # time of the latest non-empty scan passed so far
        for t, pts in reversed(self.scans[:-1]):
            if len(pts) == 0:
                # Brief gaps are the zone shrinking when the robot stops (velocity-aware zone): the
                # robot creeps stop-and-go at the same obstacle. A longer gap: it appeared after it.
                if seen - t > self.max_gap:
                    break
                continue
            seen = t
            if t_last - t < next_check:
                oldest = t
                continue
            next_check = t_last - t + min(self.static_after / 10.0, self.map_confirm / 2.0)
            shift = float(np.hypot(*(pts.mean(axis=0) - centre)))
            fwd = near_fraction(last, pts, self.match_radius)
            bwd = near_fraction(pts, last, self.match_radius)
            if shift > self.max_shift or fwd < self.min_match or bwd < self.min_match:
                if t >= t_last - self.static_after:
                    self.reason = "blocking points moved %.2f m in %.1f s (match %.0f/%.0f %%)" % (
                        shift,
                        t_last - t,
                        100 * fwd,
                        100 * bwd,
                    )
                    return MOVING
                break  # something else stood there before
            oldest = t
        unmoved = t_last - oldest
        if occupied is not None and unmoved >= self.map_confirm:
            on_map = sum(1 for x, y in last.tolist() if occupied(x, y)) / float(len(last))
            if on_map >= self.map_fraction:
                self.reason = "%.0f %% of the blocking points are on the LiDAR map, unmoved for %.1f s" % (
                    100.0 * on_map, unmoved)
                return STATIC
        if unmoved >= self.static_after:
            self.reason = "blocking points unmoved for %.1f s" % unmoved
            return STATIC
        self.reason = "observed for %.1f s of %.1f s" % (unmoved, self.static_after)
        return UNKNOWN
