"""Ground-truth safety metrics shared by the demo, the system tests and the soak.

ROS-free: the robot is a rectangle (its footprint) at a pose in the world frame, people are
vertical cylinders. Distances are the clearance between the footprint's edge and the
cylinder's surface; a clearance <= 0 is a contact.
"""

import math
from typing import Dict, Iterable, List, Optional, Tuple

#: Unitree A1 footprint [m]: the feet span about 0.50 m x 0.30 m (body 0.267 x 0.194).
A1_FOOTPRINT_LENGTH = 0.50
A1_FOOTPRINT_WIDTH = 0.30


def footprint_clearance(
    robot_xy: Tuple[float, float],
    robot_yaw: float,
    person_xy: Tuple[float, float],
    person_radius: float,
    length: float = A1_FOOTPRINT_LENGTH,
    width: float = A1_FOOTPRINT_WIDTH,
) -> float:
    """Clearance between the robot's footprint rectangle and a person's cylinder.

    Args:
        robot_xy: Footprint centre in the world [m].
        robot_yaw: Heading [rad].
        person_xy: Cylinder axis in the world [m].
        person_radius: Cylinder radius [m].
        length: Footprint length along the robot's x axis [m].
        width: Footprint width along the robot's y axis [m].

    Returns:
        Distance [m] from the rectangle to the cylinder surface; <= 0 means contact.
    """
    if person_radius < 0 or length <= 0 or width <= 0:
        raise ValueError("radius must be >= 0 and footprint sizes > 0")
    dx = person_xy[0] - robot_xy[0]
    dy = person_xy[1] - robot_xy[1]
    c, s = math.cos(robot_yaw), math.sin(robot_yaw)
    # Person centre in the robot frame.
    px = c * dx + s * dy
    py = -s * dx + c * dy
    ex = max(abs(px) - length / 2.0, 0.0)
    ey = max(abs(py) - width / 2.0, 0.0)
    if ex == 0.0 and ey == 0.0:
        # Centre inside the rectangle: negative clearance (depth of the inner point).
        inside = min(length / 2.0 - abs(px), width / 2.0 - abs(py))
        return -inside - person_radius
    return math.hypot(ex, ey) - person_radius


def _rect(cx: float, cy: float, yaw: float, length: float, width: float) -> List[Tuple[float, float]]:
    c, s = math.cos(yaw), math.sin(yaw)
    hx, hy = length / 2.0, width / 2.0
    return [(cx + c * x - s * y, cy + s * x + c * y) for x, y in ((hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy))]


def _segment_distance(p: Tuple[float, float], a: Tuple[float, float], b: Tuple[float, float]) -> float:
    dx, dy = b[0] - a[0], b[1] - a[1]
    len2 = dx * dx + dy * dy
    u = 0.0 if len2 == 0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2))
    return math.hypot(p[0] - a[0] - u * dx, p[1] - a[1] - u * dy)


def _inside(p: Tuple[float, float], poly: List[Tuple[float, float]]) -> bool:
    inside = False
    for (x1, y1), (x2, y2) in zip(poly, poly[1:] + poly[:1]):
        if (y1 > p[1]) != (y2 > p[1]) and p[0] < x1 + (p[1] - y1) * (x2 - x1) / (y2 - y1):
            inside = not inside
    return inside


def footprint_box_clearance(
    robot_xy: Tuple[float, float],
    robot_yaw: float,
    box_xy: Tuple[float, float],
    box_yaw: float,
    box_size: Tuple[float, float],
    length: float = A1_FOOTPRINT_LENGTH,
    width: float = A1_FOOTPRINT_WIDTH,
) -> float:
    """Clearance between the robot's footprint rectangle and a box's footprint (a bag, a wall panel).

    Args:
        robot_xy: Footprint centre in the world [m].
        robot_yaw: Heading [rad].
        box_xy: Box centre [m].
        box_yaw: Box rotation [rad].
        box_size: (length along its x, width along its y) [m].
        length: Footprint length [m].
        width: Footprint width [m].

    Returns:
        Distance [m] between the two rectangles; 0 when they touch or overlap (a contact).
    """
    a = _rect(robot_xy[0], robot_xy[1], robot_yaw, length, width)
    b = _rect(box_xy[0], box_xy[1], box_yaw, box_size[0], box_size[1])
    if any(_inside(p, b) for p in a) or any(_inside(p, a) for p in b):
        return 0.0
    best = math.inf
    for poly, other in ((a, b), (b, a)):
        for p in poly:
            for q, r in zip(other, other[1:] + other[:1]):
                best = min(best, _segment_distance(p, q, r))
    return best


def box_ahead(
    robot_pose: Tuple[float, float, float],
    gap: float,
    box_size: Tuple[float, float],
    lateral: float = 0.0,
    box_yaw: float = 0.0,
    length: float = A1_FOOTPRINT_LENGTH,
    width: float = A1_FOOTPRINT_WIDTH,
) -> Tuple[float, float, float]:
    """Where to put a box on the robot's way so that it lands ``gap`` ahead of the footprint.

    The way a visitor drops a bag in front of a walking robot: the box centre lies on the line
    ``lateral`` to the side of the robot's heading, as far ahead as makes the clearance between
    the footprint and the box (:func:`footprint_box_clearance`) exactly ``gap``, whatever its
    rotation. With ``gap`` beyond the stop zone's front margin the box lands outside the zone.

    Args:
        robot_pose: (x, y, yaw) of the footprint centre in the world [m, rad].
        gap: clearance between the footprint and the box [m], > 0.
        box_size: (length along its x, width along its y) [m].
        lateral: offset of the box centre to the left of the heading [m].
        box_yaw: rotation of the box relative to the robot's heading [rad].
        length: footprint length [m].
        width: footprint width [m].

    Returns:
        (x, y, yaw) of the box centre in the world [m, rad].

    Raises:
        ValueError: gap <= 0, non-finite values, box sizes <= 0, or a lateral offset that puts the
            box beside the robot (not on its way: already ``gap`` away at the footprint's centre).
    """
    values = tuple(robot_pose) + (gap, lateral, box_yaw) + tuple(box_size)
    if not all(math.isfinite(v) for v in values) or gap <= 0.0 or min(box_size) <= 0.0:
        raise ValueError("box_ahead needs finite values, gap > 0 and box sizes > 0, got %r" % (values,))
    x, y, yaw = robot_pose
    c, s = math.cos(yaw), math.sin(yaw)
    world_yaw = yaw + box_yaw

    def clearance(d: float) -> float:
        bx, by = x + c * d - s * lateral, y + s * d + c * lateral
        return footprint_box_clearance((x, y), yaw, (bx, by), world_yaw, box_size, length, width)

    if clearance(0.0) >= gap:
        raise ValueError("a box %.2f m to the side is not on the robot's way" % lateral)
    lo, hi = 0.0, length / 2.0 + gap + math.hypot(*box_size)  # clearance(lo) < gap < clearance(hi)
    for _ in range(60):  # the clearance grows with the distance ahead: bisection to well below 1 um
        mid = 0.5 * (lo + hi)
        if clearance(mid) < gap:
            lo = mid
        else:
            hi = mid
    d = 0.5 * (lo + hi)
    return x + c * d - s * lateral, y + s * d + c * lateral, world_yaw


def outside_polygon(xy: Tuple[float, float], polygon: Iterable[Tuple[float, float]]) -> bool:
    """True if the point lies outside the polygon (even-odd rule)."""
    return not _inside(xy, list(polygon))


class ContactMonitor:
    """Accumulates minimum clearance and contact events over a run."""

    def __init__(self, length: float = A1_FOOTPRINT_LENGTH, width: float = A1_FOOTPRINT_WIDTH) -> None:
        self.length = length
        self.width = width
        self.min_clearance = math.inf
        self.min_clearance_at: Optional[float] = None
        self.contacts: List[Tuple[float, str]] = []
        self._in_contact = set()

    def update(self, stamp: float, robot_xy: Tuple[float, float], robot_yaw: float,
               people: Iterable[Tuple[str, float, float, float]]) -> float:
        """Add one ground-truth sample.

        Args:
            stamp: Time of the sample [s].
            robot_xy: Robot footprint centre [m].
            robot_yaw: Robot heading [rad].
            people: (name, x, y, radius) of every person.

        Returns:
            The smallest clearance in this sample [m] (+inf when nobody is there).
        """
        sample_min = math.inf
        touching = set()
        for name, x, y, radius in people:
            d = footprint_clearance(robot_xy, robot_yaw, (x, y), radius, self.length, self.width)
            sample_min = min(sample_min, d)
            if d <= 0.0:
                touching.add(name)
                if name not in self._in_contact:
                    self.contacts.append((stamp, name))
        self._in_contact = touching
        if sample_min < self.min_clearance:
            self.min_clearance = sample_min
            self.min_clearance_at = stamp
        return sample_min


class TowardsMonitor:
    """The rule "never move towards a moving person" (issue 17), measured on ground truth.

    For every sample, each person who moves (faster than ``person_speed``) and is within ``band``
    of the footprint is checked: the robot's velocity component towards the person's axis must
    not exceed ``tolerance``. A person who has just come that close is given ``reaction`` seconds:
    the zone can only stop a motion that is already under way after it saw the person (the
    thesis measured 0.44 ± 0.09 s from intrusion to standing still).

    Args:
        band: footprint-person clearance within which the rule applies [m].
        reaction: grace time after a moving person came within the band [s].
        person_speed: a person faster than this is moving [m/s].
        tolerance: largest allowed velocity towards such a person [m/s] (ground-truth noise).
        length: footprint length [m].
        width: footprint width [m].
    """

    def __init__(self, band: float = 0.5, reaction: float = 0.55, person_speed: float = 0.1,
                 tolerance: float = 0.03, length: float = A1_FOOTPRINT_LENGTH,
                 width: float = A1_FOOTPRINT_WIDTH) -> None:
        self.band = band
        self.reaction = reaction
        self.person_speed = person_speed
        self.tolerance = tolerance
        self.length = length
        self.width = width
        self.max_towards = -math.inf  # largest velocity towards a moving person after the grace time [m/s]
        self.checked = 0  # samples with a moving person within the band after the grace time
        self.violations: List[Tuple[float, str, float]] = []  # (time, person, velocity towards)
        self._since: Dict[str, float] = {}

    def update(self, stamp: float, robot_xy: Tuple[float, float], robot_yaw: float,
               robot_velocity: Tuple[float, float],
               people: Iterable[Tuple[str, float, float, float, float, float]]) -> None:
        """Add one ground-truth sample.

        Args:
            stamp: time of the sample [s].
            robot_xy: footprint centre [m].
            robot_yaw: heading [rad].
            robot_velocity: the robot's velocity in the world frame (vx, vy) [m/s].
            people: (name, x, y, radius, vx, vy) of every person, velocities in the world frame.
        """
        near = set()
        for name, x, y, radius, pvx, pvy in people:
            if math.hypot(pvx, pvy) <= self.person_speed:
                continue
            if footprint_clearance(robot_xy, robot_yaw, (x, y), radius, self.length, self.width) >= self.band:
                continue
            near.add(name)
            since = self._since.setdefault(name, stamp)
            if stamp - since < self.reaction:
                continue
            dx, dy = x - robot_xy[0], y - robot_xy[1]
            dist = math.hypot(dx, dy)
            towards = (robot_velocity[0] * dx + robot_velocity[1] * dy) / dist if dist > 1e-9 else 0.0
            self.checked += 1
            self.max_towards = max(self.max_towards, towards)
            if towards > self.tolerance:
                self.violations.append((stamp, name, towards))
        for name in list(self._since):
            if name not in near:
                del self._since[name]
