"""Dodge: an idle robot steps back from an approaching visitor, then returns home. ROS-free.

The approach is read from the LiDAR zone's smallest distance per side (stop and slowdown
band, rbd_msgs/CollisionState.min_distance): a side is *approached* when something is inside
its slowdown band and came closer at ``approach_speed`` or faster over the last ``window``
seconds (or appeared in the band from nowhere). Standing objects (walls, furniture) never
trigger a dodge. The step goes straight away from the approached side (no turning), at most
``max_offset`` from home and inside the arena; the robot returns home once nothing has been in
any band for ``return_after`` seconds. The motions are GUARDED goals: the position controller
stops them if the side they head to is occupied, so the robot never moves towards anyone.
"""

import math
from typing import List, Optional, Sequence, Tuple

from rbd_controller.arena import Arena
from rbd_controller.escape import OPPOSITE, SIDE_NAMES, TOWARDS

Point = Tuple[float, float]


class ApproachDetector:
    """Per-side history of the nearest distance; reports sides something approaches.

    Args:
        band: outer edge of the slowdown band per side (zone + slowdown) [m].
        approach_speed: closing speed that counts as an approach [m/s].
        window: time over which the closing speed is measured [s].
    """

    def __init__(self, band: Sequence[float], approach_speed: float = 0.15, window: float = 0.4) -> None:
        if len(band) != 4 or approach_speed <= 0.0 or window <= 0.0:
            raise ValueError("need 4 band limits, approach_speed > 0 and window > 0")
        self.band = [float(b) for b in band]
        self.approach_speed = float(approach_speed)
        self.window = float(window)
        self.history = [[] for _ in range(4)]  # type: List[List[Tuple[float, float]]]
        self.last_occupied = -math.inf

    def reset(self) -> None:
        """Forget the history (the robot moved)."""
        self.history = [[] for _ in range(4)]

    def update(self, t: float, min_distance: Sequence[float], own: Tuple[float, float] = (0.0, 0.0)) -> List[int]:
        """Add one reading at t [s]; return the approached sides, fastest first.

        Args:
            t: time of the reading [s].
            min_distance: nearest distance per side (FRONT, LEFT, BACK, RIGHT) [m], inf: none.
            own: the robot's own body velocity (vx, vy) [m/s]; closing caused by it is not an
                approach (a robot walking home towards a standing visitor is not approached).
        """
        toward = (own[0], own[1], -own[0], -own[1])
        approached = []
        for s in range(4):
            d = float(min_distance[s])
            d = d if math.isfinite(d) else math.inf
            h = self.history[s]
            h.append((t, d))
            while len(h) > 1 and h[0][0] < t - self.window - 0.5:
                h.pop(0)
            if d < self.band[s]:
                self.last_occupied = t
                old = [(tt, dd) for tt, dd in h if tt <= t - self.window]
                ref = old[-1] if old else h[0]
                closing = math.inf if ref[1] == math.inf else (ref[1] - d) / max(t - ref[0], 1e-6)
                if ref[0] < t and closing - max(0.0, toward[s]) >= self.approach_speed:
                    approached.append((-closing, s))
        return [s for _, s in sorted(approached)]

    def quiet_for(self, t: float) -> float:
        """Seconds since anything was inside a slowdown band."""
        return t - self.last_occupied


def dodge_target(
    home: Point,
    pose: Tuple[float, float, float],
    approached_side: int,
    step: float = 0.3,
    max_offset: float = 0.5,
    arena: Optional[Arena] = None,
    arena_margin: float = 0.1,
) -> Tuple[Optional[Point], str]:
    """Where to step to get away from the approached side.

    Args:
        home: home position [m] (where the robot waits for gestures).
        pose: robot (x, y, yaw) [m, rad].
        approached_side: FRONT, LEFT, BACK or RIGHT (escape's indices).
        step: nominal step [m].
        max_offset: the target stays within this of home [m] (``~dodge_max``).
        arena: the target stays inside.
        arena_margin: distance kept from the arena's edge [m].

    Returns:
        (target, summary) or (None, reason) when no step of at least 5 cm is possible.
    """
    if not all(math.isfinite(v) for v in tuple(pose) + tuple(home) + (step, max_offset)):
        return None, "pose, home or limits not finite"
    x, y, yaw = pose
    bx, by = TOWARDS[OPPOSITE[approached_side]]
    c, s = math.cos(yaw), math.sin(yaw)
    ux, uy = c * bx - s * by, s * bx + c * by
    # Largest d <= step with |pose + d u - home| <= max_offset.
    px, py = x - home[0], y - home[1]
    b = px * ux + py * uy
    disc = b * b - (px * px + py * py - max_offset * max_offset)
    limit = -b + math.sqrt(disc) if disc >= 0.0 else 0.0
    d = max(0.0, min(step, limit))
    if arena is not None:
        d = min(d, arena.reach((x, y), (ux, uy), d, arena_margin))
    if d < 0.05:
        return None, "no room to step away from the %s (%.2f m from home, limit %.2f m)" % (
            SIDE_NAMES[approached_side],
            math.hypot(px, py),
            max_offset,
        )
    return (x + d * ux, y + d * uy), "%.2f m away from the %s" % (d, SIDE_NAMES[approached_side])
