"""The mock A1's legs: joint angles, rates, torques and foot forces from a trot phase model (ROS-free).

What SDK 3.3.4's ``HighState.motorState`` and ``footForce`` would show, plausibly, not a dynamics
model. Conventions of unitree_ros' ``a1_description``: zero angles = leg straight down; hip about
+x, thigh and calf about +y; the motor order is leg * 3 + joint with legs FR, FL, RR, RL and joints
hip, thigh, calf. A standing A1 (body 0.28 m) has thigh ≈ +0.80 rad and calf ≈ −1.59 rad.

* Standing (modes 0/1, or no command): feet under the hips, the leg length set by the body
  height, so the minimum body height (lie down, 0.12 m) gives the lying angles (thigh ≈ 1.27,
  calf ≈ −2.53 rad). Each foot carries a quarter of the weight.
* Walking (mode 2): a trot. The diagonal pairs FR+RL and FL+RR alternate every half period; a
  stance foot slides backwards under its hip at the hip's velocity, a swing foot returns forward
  and lifts by ``FOOT_RAISE`` on a sine. The two stance feet carry half the weight each, swing
  feet none. Sideways velocity and turning swing the feet sideways through the hip joints.

Geometry (a1_description): thigh and calf 0.2 m, hips at (±0.1805, ±0.047) m from the body centre,
the leg plane 0.0838 m outside the hip. Mass 12 kg.
"""

import math
from typing import List, Sequence, Tuple

THIGH = 0.2  # [m]
CALF = 0.2  # [m]
HIPS = ((0.1805, -0.047), (0.1805, 0.047), (-0.1805, -0.047), (-0.1805, 0.047))  # FR, FL, RR, RL (x, y) [m]
LEG_OFFSET = (-0.0838, 0.0838, -0.0838, 0.0838)  # leg plane outside the hip, y [m]
MASS = 12.0  # [kg]
GRAVITY = 9.81
TROT_PERIOD = 0.4  # one full trot cycle [s]
FOOT_RAISE = 0.08  # swing foot height (SDK default footRaiseHeight) [m]
PAIR = (0, 1, 1, 0)  # trot pair of each leg: FR+RL, FL+RR


def leg_ik(x: float, z: float) -> Tuple[float, float]:
    """Thigh and calf angles [rad] that put the foot at (x, z) from the hip in the leg plane.

    x forward, z up (the foot below the hip has z < 0); the reach is clipped to the leg's range.
    """
    d = min(max(math.hypot(x, z), 0.04), THIGH + CALF - 1e-6)
    knee = math.acos(max(-1.0, min(1.0, (d * d - THIGH * THIGH - CALF * CALF) / (2.0 * THIGH * CALF))))
    calf = -knee
    alpha = math.atan2(-x, -z)  # direction of the foot from the hip, from straight down
    beta = math.acos(max(-1.0, min(1.0, (THIGH * THIGH + d * d - CALF * CALF) / (2.0 * THIGH * d))))
    return alpha + beta, calf


def leg_fk(thigh: float, calf: float) -> Tuple[float, float]:
    """Foot (x, z) from the hip in the leg plane for thigh/calf angles [rad] (inverse of leg_ik)."""
    x = -THIGH * math.sin(thigh) - CALF * math.sin(thigh + calf)
    z = -THIGH * math.cos(thigh) - CALF * math.cos(thigh + calf)
    return x, z


class Legs:
    """Joint state of the 12 motors, advanced with the body's motion."""

    def __init__(self) -> None:
        self.phase = 0.0  # trot phase of pair 0 [0, 1)
        self.q = [0.0] * 12
        self.dq = [0.0] * 12
        self.tau = [0.0] * 12
        self.force = [0.0] * 4  # vertical foot force [N]
        self.feet = [(0.0, 0.0, 0.0)] * 4  # foot positions relative to the body (x, y, z) [m]
        self._time = None

    def update(self, now: float, walking: bool, body_height: float, velocity: Sequence[float]) -> None:
        """Advance to ``now``.

        Args:
            now: time [s].
            walking: trotting (mode 2, command fresh).
            body_height: height of the hips above the ground [m].
            velocity: body (vx, vy, wz) [m/s, m/s, rad/s].
        """
        dt = 0.0 if self._time is None else max(0.0, now - self._time)
        self._time = now
        if walking:
            self.phase = (self.phase + dt / TROT_PERIOD) % 1.0
        vx, vy, wz = velocity
        weight = MASS * GRAVITY
        q = [0.0] * 12
        for leg in range(4):
            hx, hy = HIPS[leg]
            x = y = lift = 0.0
            stance = True
            if walking:
                phase = (self.phase + 0.5 * PAIR[leg]) % 1.0
                hip_vx, hip_vy = vx - wz * hy, vy + wz * hx  # the hip's velocity over the ground
                half = 0.5 * TROT_PERIOD  # stance lasts half a cycle
                if phase < 0.5:  # stance: the foot slides back under the hip
                    s = 0.5 - phase / 0.5
                else:  # swing: the foot returns forward, lifted
                    stance = False
                    s = (phase - 0.5) / 0.5 - 0.5
                    lift = FOOT_RAISE * math.sin(math.pi * (phase - 0.5) / 0.5)
                x, y = hip_vx * half * s, hip_vy * half * s
            h = max(body_height - lift, 0.04)
            hip = math.atan2(y, h)  # hip about +x: a positive angle swings the foot to +y
            thigh, calf = leg_ik(x, -math.hypot(h, y))
            q[3 * leg: 3 * leg + 3] = [hip, thigh, calf]
            pair_load = 0.5 if walking else 0.25
            self.force[leg] = weight * pair_load if stance else 0.0
            self.feet[leg] = (hx + x, hy + LEG_OFFSET[leg] + y, -h)
        if dt > 0.0:
            self.dq = [(a - b) / dt for a, b in zip(q, self.q)]
        self.q = q
        self.tau = self._torques()

    def _torques(self) -> List[float]:
        """Static joint torques holding each foot's vertical load: tau = J^T (0, -F) in the leg plane."""
        tau = [0.0] * 12
        for leg in range(4):
            thigh, calf = self.q[3 * leg + 1], self.q[3 * leg + 2]
            f = self.force[leg]
            dz_thigh = THIGH * math.sin(thigh) + CALF * math.sin(thigh + calf)
            dz_calf = CALF * math.sin(thigh + calf)
            tau[3 * leg + 1] = -f * dz_thigh
            tau[3 * leg + 2] = -f * dz_calf
        return tau
