"""A small kinematic quadruped stand-in for tests and tuning. ROS-free.

Integrates body-frame velocity commands with a command latency and an optional sideways
drift proportional to the yaw rate (the A1's imperfection: about 0.4 m per 180 deg turn on
the real robot). Not the project's simulator (rbd_sim is); this only checks wiring and the
control law quickly and deterministically.
"""

import collections
import math
from typing import Tuple


class KinematicRobot:
    """Unicycle-with-sideways-velocity robot.

    Args:
        x: start x [m].
        y: start y [m].
        yaw: start heading [rad].
        latency: command latency [s] (commands take effect this much later).
        drift_per_rad: creep while turning [m per rad turned].
        drift_heading: direction of the creep in the body frame [rad]: pi/2 = sideways (+y),
            0 = forward (rbd_sim's mock A1 default; the net displacement of a half turn is then
            sideways).
        max_v: speed limits (vx, vy, wz) [m/s, m/s, rad/s] the robot itself enforces.
    """

    def __init__(
        self,
        x: float = 0.0,
        y: float = 0.0,
        yaw: float = 0.0,
        latency: float = 0.0,
        drift_per_rad: float = 0.0,
        drift_heading: float = math.pi / 2,
        max_v: Tuple[float, float, float] = (1.0, 0.5, 2.0),
    ) -> None:
        self.x = x
        self.y = y
        self.yaw = yaw
        self.t = 0.0
        self.latency = latency
        self.drift_per_rad = drift_per_rad
        self.drift_heading = drift_heading
        self.max_v = max_v
        self._queue = collections.deque()  # type: Deque[Tuple[float, Tuple[float, float, float]]]
        self._active = (0.0, 0.0, 0.0)

    def command(self, vx: float, vy: float, wz: float) -> None:
        """Send a body-frame velocity command at the current time."""
        limited = tuple(max(-m, min(m, v)) for v, m in zip((vx, vy, wz), self.max_v))
        self._queue.append((self.t + self.latency, limited))

    @property
    def velocity(self) -> Tuple[float, float, float]:
        """The velocity currently acting on the body (after latency)."""
        return self._active

    def advance(self, dt: float) -> None:
        """Integrate dt seconds."""
        self.t += dt
        while self._queue and self._queue[0][0] <= self.t + 1e-9:
            self._active = self._queue.popleft()[1]
        vx, vy, wz = self._active
        creep = self.drift_per_rad * abs(wz)
        vx = vx + creep * math.cos(self.drift_heading)
        vy = vy + creep * math.sin(self.drift_heading)
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        self.x += (c * vx - s * vy) * dt
        self.y += (s * vx + c * vy) * dt
        self.yaw = (self.yaw + wz * dt + math.pi) % (2.0 * math.pi) - math.pi
