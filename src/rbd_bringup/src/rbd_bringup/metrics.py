"""Ground-truth safety metrics shared by the demo, the system tests and the soak.

ROS-free: the robot is a rectangle (its footprint) at a pose in the world frame, people are
vertical cylinders. Distances are the clearance between the footprint's edge and the
cylinder's surface; a clearance <= 0 is a contact.
"""

import math
from typing import Iterable, List, Optional, Tuple

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
