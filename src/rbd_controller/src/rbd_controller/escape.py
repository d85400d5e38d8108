"""Escape: which way to step out of a blocked zone, and how far. ROS-free.

Works on the LiDAR zone reading (rbd_msgs/CollisionState: critical points and the smallest
perpendicular distance per side, FRONT, LEFT, BACK, RIGHT) and the zone's side limits. The
robot translates without turning (a turn sweeps every side of the zone): straight away from the
most occupied side when the opposite side is free, else sideways; far enough that the blocking
side's nearest point ends ``margin`` beyond the zone, never more than ``max_distance``, and only
as far as the arena allows. The motion itself is a GUARDED goal of the position controller, so
it still stops if the side it heads to closes.
"""

import math
from typing import List, Optional, Sequence, Tuple

from rbd_controller.arena import Arena

FRONT, LEFT, BACK, RIGHT = 0, 1, 2, 3
SIDE_NAMES = ("front", "left", "back", "right")
#: Body-frame unit direction that moves towards each side.
TOWARDS = {FRONT: (1.0, 0.0), LEFT: (0.0, 1.0), BACK: (-1.0, 0.0), RIGHT: (0.0, -1.0)}
#: The escape aims this far beyond zone + margin (noise), and never moves less than MIN_STEP [m].
OVERSHOOT = 0.05
MIN_STEP = 0.1
OPPOSITE = {FRONT: BACK, BACK: FRONT, LEFT: RIGHT, RIGHT: LEFT}
PERPENDICULAR = {FRONT: (LEFT, RIGHT), BACK: (LEFT, RIGHT), LEFT: (FRONT, BACK), RIGHT: (FRONT, BACK)}


class ZoneReading:
    """One /rbd_lidar/state in the escape's terms.

    Args:
        points: critical points per side (FRONT, LEFT, BACK, RIGHT).
        min_distance: smallest perpendicular distance per side among points in the stop or
            slowdown zone [m]; inf when none.
        stale: the monitor reports stale data.
        error: the monitor rejected the cloud.
    """

    def __init__(
        self, points: Sequence[int], min_distance: Sequence[float], stale: bool = False, error: str = ""
    ) -> None:
        self.points = [int(p) for p in points]
        self.min_distance = [float(d) if math.isfinite(d) else math.inf for d in min_distance]
        self.stale = bool(stale)
        self.error = str(error)

    @property
    def valid(self) -> bool:
        """Usable for decisions (not stale, no error)."""
        return not self.stale and not self.error


class Escape:
    """A planned escape motion.

    Attributes:
        side: the side moved towards.
        distance: planned distance [m].
        target: target position in the map frame [m].
        reason: human-readable summary.
    """

    def __init__(self, side: int, distance: float, target: Tuple[float, float], reason: str) -> None:
        self.side = side
        self.distance = distance
        self.target = target
        self.reason = reason

    def __repr__(self) -> str:
        """Readable form for logs."""
        return "Escape(%s %.2f m -> (%.2f, %.2f): %s)" % (
            SIDE_NAMES[self.side],
            self.distance,
            self.target[0],
            self.target[1],
            self.reason,
        )


def occupied_sides(reading: ZoneReading, zone: Sequence[float], threshold: int, margin: float = 0.0) -> List[int]:
    """Sides with >= threshold critical points or a point within zone + margin, most crowded first."""
    sides = [s for s in range(4) if reading.points[s] >= threshold or reading.min_distance[s] < zone[s] + margin]
    return sorted(sides, key=lambda s: (-reading.points[s], reading.min_distance[s]))


def clear_by_margin(reading: ZoneReading, zone: Sequence[float], threshold: int, margin: float) -> bool:
    """True when the reading is valid and no side has anything within zone + margin."""
    return reading.valid and not occupied_sides(reading, zone, threshold, margin)


def plan_escape(
    reading: ZoneReading,
    zone: Sequence[float],
    pose: Tuple[float, float, float],
    threshold: int = 5,
    margin: float = 0.15,
    max_distance: float = 0.6,
    side_step: float = 0.3,
    arena: Optional[Arena] = None,
    arena_margin: float = 0.1,
    room: Optional[Sequence[float]] = None,
) -> Tuple[Optional[Escape], str]:
    """Choose the escape motion for a blocked zone.

    Args:
        reading: the latest zone reading.
        zone: stop-zone limits per side (FRONT, LEFT, BACK, RIGHT) [m], rbd_lidar's zone_*.
        pose: robot (x, y, yaw) in the map frame.
        threshold: rbd_lidar's point_threshold.
        margin: clearance beyond the zone the escape aims for [m].
        max_distance: longest escape [m].
        side_step: distance of a sideways step when backing off is not possible [m].
        arena: the escape target must stay inside (None: no limit).
        arena_margin: distance kept from the arena's edge [m].
        room: per side, the clearance beyond the zone a step straight away from that side aims for when
            it is more than margin (None: margin) [m]: room for the detour's first turn on the spot at
            full rate (:meth:`rbd_controller.lattice.LatticePlanner.turn_room`). Still at most
            max_distance, the free space on the side moved towards and the arena; the escape ends, as
            before, once every side is clear by margin.

    Returns:
        (Escape, "") or (None, reason) when the zone is unusable, already clear or every
        direction is closed.
    """
    if not reading.valid:
        return None, "zone reading stale or invalid"
    if not all(math.isfinite(v) for v in pose):
        return None, "robot pose not finite: %r" % (pose,)
    blocking = occupied_sides(reading, zone, threshold, margin)
    if not blocking:
        return None, "zone already clear by %.2f m" % margin
    occupied = set(occupied_sides(reading, zone, threshold, 0.0))
    candidates = []  # (sides moved towards, body-frame unit direction, distance, why)
    step_length = min(max_distance, side_step)  # no escape is longer than max_distance
    for s in blocking:
        away = OPPOSITE[s]
        want = margin if room is None or not math.isfinite(room[s]) else max(margin, room[s])
        need = zone[s] + want + OVERSHOOT - reading.min_distance[s]
        candidates.append(((away,), TOWARDS[away], min(max_distance, max(MIN_STEP, need)),
                           "away from the %s" % SIDE_NAMES[s]))
    for s in blocking:
        for step in sorted(PERPENDICULAR[s], key=lambda p: -reading.min_distance[p]):
            candidates.append(((step,), TOWARDS[step], step_length, "side-step from the %s" % SIDE_NAMES[s]))
    for s in blocking:  # diagonally away: out of a corner (e.g. a wall behind and a box ahead-left)
        away = OPPOSITE[s]
        for step in sorted(PERPENDICULAR[s], key=lambda p: -reading.min_distance[p]):
            u = (TOWARDS[away][0] + TOWARDS[step][0], TOWARDS[away][1] + TOWARDS[step][1])
            n = math.hypot(*u)
            candidates.append(((away, step), (u[0] / n, u[1] / n), step_length,
                               "diagonally away from the %s" % SIDE_NAMES[s]))
    x, y, yaw = pose
    c, sn = math.cos(yaw), math.sin(yaw)
    tried = []
    for sides, (bx, by), dist, why in candidates:
        name = "-".join(SIDE_NAMES[t] for t in sides)
        if any(t in occupied for t in sides):
            tried.append("%s occupied" % name)
            continue
        for t in sides:  # free space beyond the zone on that side, along the motion
            room = reading.min_distance[t] - zone[t] - margin
            share = abs(TOWARDS[t][0] * bx + TOWARDS[t][1] * by)
            if math.isfinite(room) and share > 0.0:
                dist = min(dist, room / share)
        wx, wy = c * bx - sn * by, sn * bx + c * by
        if arena is not None:
            dist = min(dist, arena.reach((x, y), (wx, wy), dist, arena_margin))
        if dist < 0.05:
            tried.append("%s: no room" % name)
            continue
        target = (x + dist * wx, y + dist * wy)
        return Escape(sides[0], dist, target, "%s: %.2f m towards the %s" % (why, dist, name)), ""
    return None, "wedged: %s (points %s, nearest %s m)" % (
        ", ".join(sorted(set(tried))), reading.points, ["%.2f" % d for d in reading.min_distance])
