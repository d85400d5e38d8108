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

A *low* blocker (a bag, a box: :func:`is_low`) is static once unmoved for ``low_after`` (1.5 s)
instead of ``static_after``. Why that is sound: ``static_after`` is the time a visitor who stopped
in front of the robot gets to walk on, and what stands in front of the robot is low only when the
LiDAR sees its top with free beams above it: every point lies below ``LOW_HEIGHT`` above the sensor
(about 0.5 m above the floor on the A1) and at least ``LOW_MARGIN`` below the highest beam at the
point's range. A standing or sitting person, a child, a table's leg reach the highest beam at any
range in the zone (the OS1's top beam, 20.5 deg up, climbs 0.37 m per metre), so their points fail
the second test; only something whose top is seen, lower than that, passes. Motion still means
MOVING at once (a crawling child, a dog), and a person lying still is walked around at the zone's
distance, as any static blocker.
"""

import math
from typing import Any, Callable, Optional, Sequence, Tuple

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
#: A low blocker's points all lie at most this high above the LiDAR [m] ...
LOW_HEIGHT = 0.15
#: ... and at least this far below the highest beam at their range [m] (beam spacing, body pitch).
LOW_MARGIN = 0.10


def top_beam_from(angles: Any) -> Optional[float]:
    """The highest beam [rad] of rbd_lidar's ``beam_altitude_angles`` [deg]; None when there are none (no low rule)."""
    try:
        values = [float(a) for a in angles]
    except (TypeError, ValueError):
        return None
    values = [a for a in values if math.isfinite(a) and -90.0 < a < 90.0]
    return math.radians(max(values)) if values else None


def is_low(points: np.ndarray, top_beam: Optional[float], low_height: float = LOW_HEIGHT,
           margin: float = LOW_MARGIN) -> bool:
    """True when blocking points (N x 3, x y z in the LiDAR's frame) are a low obstacle whose top the LiDAR sees.

    Every point lies at most ``low_height`` above the sensor and ``margin`` below the highest beam
    (``top_beam`` [rad] up) at its horizontal range: the beams above it pass over. False for no
    points, non-finite values or an unknown top beam (None).
    """
    if top_beam is None or not math.isfinite(top_beam):
        return False
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] < 3 or not len(pts) or not np.all(np.isfinite(pts[:, :3])):
        return False
    rng = np.hypot(pts[:, 0], pts[:, 1])
    z = pts[:, 2]
    return bool(np.all((z <= low_height) & (z <= rng * math.tan(top_beam) - margin)))


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
        low_after: seconds a low blocker (every scan of them low, see :func:`is_low`) must stay put
            to count as static (capped at static_after; 0: no such rule).

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
        low_after: float = 0.0,
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
        if not math.isfinite(low_after) or low_after < 0.0:
            raise ValueError("low_after must be a finite number >= 0, got %r" % (low_after,))
        self.low_after = min(float(low_after), self.static_after)
        self.scans = []  # type: List[Tuple[float, np.ndarray]]
        self.lows = []  # type: List[bool]  # per scan: its points were a low obstacle
        self.reason = ""
        self.known_match = False  # the last STATIC came from the known obstacle
        self.low_match = False  # the last STATIC came from the low-obstacle rule

    def reset(self) -> None:
        """Forget the history (the robot moved, or a new stop began)."""
        self.scans = []
        self.lows = []
        self.reason = ""

    def update(self, t: float, points: Sequence[Point], low: bool = False) -> None:
        """Add one scan's blocking points (map frame) received at time t [s]; low: they are a low obstacle."""
        arr = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        arr = arr[np.all(np.isfinite(arr) & (np.abs(arr) < MAX_COORD), axis=1)]  # NaN/inf/absurd: no point
        if len(arr):  # thin to one point per 5 cm cell: thousands of critical points become tens
            arr = (np.unique(np.floor(arr / CELL).astype(np.int64), axis=0) + 0.5) * CELL
        if self.scans and t < self.scans[-1][0]:
            self.reset()  # clock jumped back
        self.scans.append((float(t), arr))
        self.lows.append(bool(low) and len(arr) > 0)
        while self.scans and self.scans[0][0] < t - self.horizon:
            self.scans.pop(0)
            self.lows.pop(0)

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

    def _all_low(self, since: float) -> bool:
        """Every scan with points since the time was a low obstacle (and there were at least 3)."""
        flags = [low for (t, pts), low in zip(self.scans, self.lows) if t >= since and len(pts)]
        return len(flags) >= 3 and all(flags)

    def classify(self, occupied: Optional[Callable[[float, float], bool]] = None,
                 known: Optional[np.ndarray] = None) -> str:
        """CLEAR, UNKNOWN, STATIC or MOVING for the history so far; ``reason`` says why.

        Args:
            occupied: (x, y) -> True if the map has an obstacle there (None: no map).
            known: points (N x 2) of obstacles already classified static and avoided (None: none);
                ``known_match`` tells whether a STATIC came from them.
        """
        self.known_match = False
        self.low_match = False
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
        if 0.0 < self.low_after <= unmoved and self._all_low(t_last - self.low_after):
            self.low_match = True
            self.reason = "a low obstacle (its top seen below the beams above it), unmoved for %.1f s" % unmoved
            return STATIC
        self.reason = "observed for %.1f s of %.1f s" % (unmoved, self.static_after)
        return UNKNOWN
