"""What a simulated world is made of: boxes, cylinders and people on scripted paths (ROS-free).

People move along their polyline at constant speed; ``mode`` is ``loop`` (closed polygon),
``pingpong`` (there and back) or ``stand`` (stays at the first point). ``phase`` [s] shifts a
person along the path. Positions are a pure function of time, so every node that loads the
same file computes the same people at the same time.
"""

import math

DEFAULT_REFLECTIVITY = {"wall": 60, "box": 40, "table": 50, "cylinder": 30, "person": 25, "placed": 25}
PERSON_MODES = ("loop", "pingpong", "stand")


class WorldError(ValueError):
    """A world file or a world request is invalid; the message says where and why."""


class Box:
    """A box standing on z0 with a yaw about the vertical axis.

    Attributes:
        name: Entry name.
        cx, cy: Centre in the world frame [m].
        hx, hy: Half sizes along the box's own x and y axes [m].
        z0, z1: Bottom and top height [m].
        yaw: Rotation about z [rad].
        reflectivity: OS1 reflectivity 0..255.
    """

    __slots__ = ("name", "cx", "cy", "hx", "hy", "z0", "z1", "yaw", "reflectivity")

    def __init__(
        self,
        name: str,
        cx: float,
        cy: float,
        hx: float,
        hy: float,
        z0: float,
        z1: float,
        yaw: float = 0.0,
        reflectivity: int = 40,
    ) -> None:
        self.name = name
        self.cx, self.cy, self.hx, self.hy = float(cx), float(cy), float(hx), float(hy)
        self.z0, self.z1, self.yaw = float(z0), float(z1), float(yaw)
        self.reflectivity = int(reflectivity)

    def bounding_radius(self) -> float:
        """Radius of the vertical cylinder around the box's footprint [m]."""
        return math.hypot(self.hx, self.hy)


class Cylinder:
    """A vertical cylinder (person, pillar, placed obstacle).

    Attributes:
        name: Entry name.
        cx, cy: Axis position in the world frame [m].
        radius: Radius [m].
        z0, z1: Bottom and top height [m].
        reflectivity: OS1 reflectivity 0..255.
        kind: "cylinder", "person" or "placed".
    """

    __slots__ = ("name", "cx", "cy", "radius", "z0", "z1", "reflectivity", "kind")

    def __init__(
        self,
        name: str,
        cx: float,
        cy: float,
        radius: float,
        z0: float,
        z1: float,
        reflectivity: int = 30,
        kind: str = "cylinder",
    ) -> None:
        self.name = name
        self.cx, self.cy, self.radius = float(cx), float(cy), float(radius)
        self.z0, self.z1 = float(z0), float(z1)
        self.reflectivity = int(reflectivity)
        self.kind = kind

    def bounding_radius(self) -> float:
        """Radius of the footprint [m]."""
        return self.radius


class Person:
    """A person walking a scripted polyline at constant speed.

    Args:
        name: Unique name.
        path: List of (x, y) way points [m].
        speed: Walking speed [m/s].
        mode: "loop", "pingpong" or "stand".
        radius: Body radius [m].
        height: Body height [m].
        phase: Time offset along the path [s].
        reflectivity: OS1 reflectivity 0..255.
    """

    def __init__(
        self,
        name: str,
        path: list,
        speed: float = 0.8,
        mode: str = "loop",
        radius: float = 0.25,
        height: float = 1.75,
        phase: float = 0.0,
        reflectivity: int = 25,
    ) -> None:
        self.name = name
        pts = [(float(p[0]), float(p[1])) for p in path]
        if mode == "loop" and len(pts) > 1:
            pts = pts + [pts[0]]
        elif mode == "pingpong" and len(pts) > 1:
            pts = pts + pts[-2::-1]
        self.points = pts
        self.speed, self.mode = float(speed), mode
        self.radius, self.height, self.phase = float(radius), float(height), float(phase)
        self.reflectivity = int(reflectivity)
        self.seg_len = [math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(pts[:-1], pts[1:])]
        self.length = sum(self.seg_len)

    def position(self, t: float) -> tuple:
        """Return the (x, y) position at time t [s] since the world epoch."""
        if self.mode == "stand" or self.length <= 0.0 or self.speed <= 0.0:
            return self.points[0]
        s = math.fmod((t + self.phase) * self.speed, self.length)
        if s < 0.0:
            s += self.length
        for (a, b), seg in zip(zip(self.points[:-1], self.points[1:]), self.seg_len):
            if s <= seg and seg > 0.0:
                f = s / seg
                return (a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]))
            s -= seg
        return self.points[-1]

    def cylinder(self, t: float) -> Cylinder:
        """Return the person's body as a cylinder at time t [s]."""
        x, y = self.position(t)
        return Cylinder(self.name, x, y, self.radius, 0.0, self.height, self.reflectivity, "person")
