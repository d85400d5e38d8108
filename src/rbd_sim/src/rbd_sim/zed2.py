"""Simulated ZED2 positional tracking: the base_link pose in ``map`` with drift, noise and jumps.

ROS-free. The estimate is the true pose plus an error state (x, y, z, yaw) that

- drifts as a random walk whose variance grows with distance travelled, rotation and time
  (visual odometry drifts most when moving and turning);
- jumps now and then (a Poisson process): either a relocalisation that removes the drift at
  once (a loop closure), or a spurious shift of jump_min..jump_max metres in a random
  direction, as the ZED does when the scene changes (crowds);

plus white noise on every sample. ``map`` is the ZED2's own tracking frame: the robot's start
pose in the simulator's ``world`` (the world origin unless the robot is placed elsewhere;
:func:`in_tracking_frame`), as a real ZED2 starts tracking at zero where it is switched on.
Everything is drawn from one seeded generator: the same seed and the same true trajectory give
the same output.
"""

import math

import numpy as np

from rbd_geometry.rotation import wrap_angle


def in_tracking_frame(position: tuple, rpy: tuple, origin: tuple) -> tuple:
    """The true pose (world) in the ZED2's tracking frame, which starts at ``origin``.

    Args:
        position: (x, y, z) in world [m].
        rpy: (roll, pitch, yaw) in world [rad].
        origin: (x, y, yaw) of the tracking frame in world: the robot's start pose [m, m, rad].

    Returns:
        (position, rpy) in the tracking frame; z, roll and pitch unchanged (the origin is level).
    """
    ox, oy, oyaw = origin
    c, s = math.cos(oyaw), math.sin(oyaw)
    dx, dy = position[0] - ox, position[1] - oy
    return (c * dx + s * dy, -s * dx + c * dy, position[2]), (rpy[0], rpy[1], wrap_angle(rpy[2] - oyaw))


class ZedPose:
    """One estimated pose.

    Attributes:
        position: (x, y, z) [m].
        rpy: (roll, pitch, yaw) [rad].
        covariance: 36 floats, row-major 6x6 (x, y, z, roll, pitch, yaw).
        jumped: True if a jump happened at this sample.
    """

    __slots__ = ("position", "rpy", "covariance", "jumped")


class Zed2Model:
    """Drift, noise and jump model of the ZED2 pose.

    Args:
        noise_pos_std: White position noise [m].
        noise_rot_std: White roll/pitch/yaw noise [rad].
        drift_per_m: Position random walk per sqrt(metre travelled) [m].
        drift_per_s: Position random walk per sqrt(second) [m].
        yaw_drift_per_rad: Yaw random walk per sqrt(radian turned) [rad].
        yaw_drift_per_s: Yaw random walk per sqrt(second) [rad].
        jump_rate: Mean jumps per second (0: none).
        jump_reset_prob: Probability that a jump is a relocalisation removing the drift.
        jump_min: Smallest spurious jump [m].
        jump_max: Largest spurious jump [m].
        jump_yaw_std: Yaw part of a spurious jump [rad].
        seed: Random seed.

    Raises:
        ValueError: negative or inconsistent parameters.
    """

    def __init__(
        self,
        noise_pos_std: float = 0.005,
        noise_rot_std: float = 0.002,
        drift_per_m: float = 0.03,
        drift_per_s: float = 0.002,
        yaw_drift_per_rad: float = 0.01,
        yaw_drift_per_s: float = 0.0005,
        jump_rate: float = 0.02,
        jump_reset_prob: float = 0.5,
        jump_min: float = 0.05,
        jump_max: float = 0.3,
        jump_yaw_std: float = 0.02,
        seed: int = 0,
    ) -> None:
        values = (
            noise_pos_std,
            noise_rot_std,
            drift_per_m,
            drift_per_s,
            yaw_drift_per_rad,
            yaw_drift_per_s,
            jump_rate,
            jump_min,
            jump_max,
            jump_yaw_std,
        )
        if any(not math.isfinite(v) or v < 0 for v in values):
            raise ValueError("ZED2 model parameters must be finite and >= 0")
        if not 0.0 <= jump_reset_prob <= 1.0 or jump_min > jump_max:
            raise ValueError("jump_reset_prob must be in [0, 1] and jump_min <= jump_max")
        self.noise_pos_std, self.noise_rot_std = float(noise_pos_std), float(noise_rot_std)
        self.drift_per_m, self.drift_per_s = float(drift_per_m), float(drift_per_s)
        self.yaw_drift_per_rad, self.yaw_drift_per_s = float(yaw_drift_per_rad), float(yaw_drift_per_s)
        self.jump_rate, self.jump_reset_prob = float(jump_rate), float(jump_reset_prob)
        self.jump_min, self.jump_max, self.jump_yaw_std = float(jump_min), float(jump_max), float(jump_yaw_std)
        self.rng = np.random.default_rng(seed)
        self.drift = np.zeros(4)  # x, y, z, yaw
        self._var = np.zeros(2)  # accumulated drift variance (position, yaw) since the last reset
        self.jumps = 0
        self._last = None

    def step(self, dt: float, position: tuple, rpy: tuple) -> ZedPose:
        """Advance by dt [s] to the true pose (position [m], roll/pitch/yaw [rad]); return the estimate."""
        dt = max(0.0, float(dt))
        # A fixed number of draws per step keeps the stream aligned whatever happens.
        n = self.rng.standard_normal(10)
        u = self.rng.random(3)
        p = np.asarray(position, dtype=float)
        if self._last is not None:
            dist = float(np.hypot(*(p[:2] - self._last[0][:2])))
            turn = abs(wrap_angle(rpy[2] - self._last[1]))
            sp = math.sqrt(self.drift_per_m**2 * dist + self.drift_per_s**2 * dt)
            sy = math.sqrt(self.yaw_drift_per_rad**2 * turn + self.yaw_drift_per_s**2 * dt)
            self.drift[0:2] += sp * n[0:2]
            self.drift[2] += 0.2 * sp * n[2]
            self.drift[3] += sy * n[3]
            self._var += (sp * sp, sy * sy)
        self._last = (p, float(rpy[2]))
        jumped = False
        if self.jump_rate > 0 and dt > 0 and u[0] < 1.0 - math.exp(-self.jump_rate * dt):
            jumped = True
            self.jumps += 1
            if u[1] < self.jump_reset_prob:
                self.drift[:] = 0.0
                self._var[:] = 0.0
            else:
                mag = self.jump_min + (self.jump_max - self.jump_min) * u[2]
                ang = math.atan2(n[8], n[9])
                self.drift[0] += mag * math.cos(ang)
                self.drift[1] += mag * math.sin(ang)
                self.drift[3] += self.jump_yaw_std * n[7]
        out = ZedPose()
        out.position = (
            p[0] + self.drift[0] + self.noise_pos_std * n[4],
            p[1] + self.drift[1] + self.noise_pos_std * n[5],
            p[2] + self.drift[2] + self.noise_pos_std * n[6],
        )
        rn = self.noise_rot_std * self.rng.standard_normal(3)
        out.rpy = (rpy[0] + rn[0], rpy[1] + rn[1], wrap_angle(rpy[2] + self.drift[3] + rn[2]))
        out.jumped = jumped
        # The reported covariance is what the tracker could know: noise plus the drift variance
        # accumulated since the last relocalisation (not the actual, hidden error).
        pv = self.noise_pos_std**2 + float(self._var[0]) + 1e-6
        rv = self.noise_rot_std**2 + 1e-6
        cov = [0.0] * 36
        for i, v in enumerate((pv, pv, pv, rv, rv, rv + float(self._var[1]))):
            cov[7 * i] = v
        out.covariance = cov
        return out
