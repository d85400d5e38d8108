"""Kinematic model of the Unitree A1 under high-level control (ROS-free; the mock A1 node wraps it).

It receives raw ``HighCmd`` bytes exactly as the robot's LCM server would hand them on (decoded
with the robot side's own description, ``rbd_sim.unitree_wire``), and integrates them:

* Bad packets (wrong size, wrong levelFlag, unknown mode/gait/speed level, NaN/inf) are rejected
  and counted; the robot keeps doing what the last valid command said.
* Each valid command takes effect ``latency`` seconds after it arrived (thesis Fig. 18: < 0.1 s).
* Stale command (none effective for ``cmd_timeout``) => the robot's own watchdog targets zero
  velocity (the SDK's lcm_server_high gives up after 10 loops of 2 ms without a command).
* Mode 2 (velocity walking): velocity and yaw rate saturated to ``max_*`` and reached with the
  acceleration limits ``max_acc_*``. Modes 0/1: stand still; mode 1 tilts/lowers the body to
  euler + bodyHeight (rate limited). Modes 3..13 are not modeled: the mock holds still.
* Imperfection (thesis §4.3): an in-place 180 deg turn leaves the robot about 0.4 m off the spot,
  sideways to its path. Modeled as a creep velocity fixed in the body frame,
  ``k * |yaw rate| * (cos(drift_heading), sin(drift_heading))`` with ``k = drift_per_180 / 2``:
  integrated over a half turn it moves the robot by ``2 k``. With the default
  ``drift_heading = 0`` (the trot creeps forward while turning) the net displacement of a
  half turn is perpendicular to the heading the turn started from, towards the turn side (left
  for a counter-clockwise turn), so a turn out and a turn back (the thesis loop) add up to a
  sideways offset, as in thesis Fig. 16. ``k`` is scaled once per run by
  ``1 + drift_sigma * N(0, 1)`` from the seeded RNG. ``drift_per_180 = 0`` turns it off.

Ground truth (``pose()``) includes the slip; the robot's own odometry (``HighState.position``)
does not, as the real A1's leg odometry does not see it. The legs (``motorState``, ``footForce``
of SDK 3.3.4) come from a trot phase model (``rbd_sim.a1_legs``); the hand-held remote's buttons
are whatever :meth:`A1Model.press` holds.
"""

import collections
import math
import random

from rbd_geometry.rotation import rpy_to_quat, wrap_angle
from rbd_sim import unitree_wire as wire
from rbd_sim.a1_legs import FOOT_RAISE, Legs


class A1Config:
    """Model parameters (defaults documented in rbd_sim/README.md, "Mock A1")."""

    def __init__(
        self,
        latency: float = 0.05,
        cmd_timeout: float = 0.1,
        max_vx: float = 1.0,
        max_vy: float = 0.5,
        max_wz: float = 2.0,
        max_acc_x: float = 1.5,
        max_acc_y: float = 1.0,
        max_acc_wz: float = 4.0,
        drift_per_180: float = 0.4,
        drift_sigma: float = 0.05,
        drift_heading: float = 0.0,
        attitude_rate: float = 1.5,
        height_rate: float = 0.3,
        max_roll: float = 0.75,
        max_pitch: float = 0.75,
        max_yaw: float = 0.6,
        min_body_height: float = -0.16,
        max_body_height: float = 0.06,
        x0: float = 0.0,
        y0: float = 0.0,
        yaw0: float = 0.0,
        seed: int = 1,
    ) -> None:
        values = dict(locals())
        values.pop("self")
        for name, value in values.items():
            if not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError("%s must be a finite number, got %r" % (name, value))
        if not 0.0 <= latency < 1.0:
            raise ValueError("latency must be in [0, 1) s, got %r" % latency)
        for name in ("cmd_timeout", "max_vx", "max_vy", "max_wz", "max_acc_x", "max_acc_y", "max_acc_wz",
                     "attitude_rate", "height_rate"):
            if values[name] <= 0.0:
                raise ValueError("%s must be > 0, got %r" % (name, values[name]))
        if drift_per_180 < 0.0 or drift_sigma < 0.0:
            raise ValueError("drift_per_180 and drift_sigma must be >= 0")
        if abs(drift_heading) > math.pi:
            raise ValueError("drift_heading must be in [-pi, pi] rad")
        for name, value in values.items():
            setattr(self, name, float(value) if name != "seed" else int(value))


def _toward(value: float, target: float, max_step: float) -> float:
    if target > value + max_step:
        return value + max_step
    if target < value - max_step:
        return value - max_step
    return target


def _clamp(value: float, limit: float) -> float:
    return max(-limit, min(limit, value))


class A1Model:
    """The mock A1's state and its integration. Times are seconds on the caller's clock."""

    GRAVITY = 9.81

    def __init__(self, config: A1Config = None, now: float = 0.0) -> None:
        self.config = c = config if config is not None else A1Config()
        rng = random.Random(c.seed)
        self.drift_gain = c.drift_per_180 / 2.0 * max(0.0, 1.0 + c.drift_sigma * rng.gauss(0, 1))
        # Ground truth of the locomotion frame (feet) and the body pose on top of it.
        self.x, self.y, self.heading = c.x0, c.y0, c.yaw0
        self.vx = self.vy = self.wz = 0.0  # commanded part, body frame [m/s, rad/s]
        self.slip = (0.0, 0.0)  # the drift's creep velocity in the body frame [m/s]
        self.roll = self.pitch = self.body_yaw = 0.0  # body attitude relative to the feet [rad]
        self.dheight = 0.0  # body height change from nominal [m]
        self.rates = (0.0, 0.0, 0.0)  # roll, pitch, body-yaw rates [rad/s]
        self.dheight_rate = 0.0
        self.acc = (0.0, 0.0)  # body-frame horizontal acceleration [m/s^2]
        # The robot's own odometry (no slip), in its power-up frame.
        self.odom_x = self.odom_y = 0.0
        # Command pipeline.
        self._pending = collections.deque(maxlen=4096)  # bounded even if step() is starved
        self._active = None  # (arrival time, HighCmd)
        self.time = now
        self.rejected = 0
        self.accepted = 0
        self.last_error = ""
        self.unmodeled_mode = None
        self.mode = wire.MODE_IDLE
        self.gait_type = wire.GAIT_IDLE
        self.legs = Legs()
        self.led = ((0, 0, 0),) * 4  # LED[4] (r, g, b) of the effective command
        self._buttons = ()  # remote buttons held
        self._buttons_until = 0.0  # ... until this time

    # ---- input ----------------------------------------------------------------------------------
    def receive(self, data: bytes, now: float) -> str:
        """Take one LCM_High_Cmd payload. Returns "" if accepted, else why it was rejected."""
        try:
            cmd = wire.decode_high_cmd(bytes(data))
        except wire.WireError as e:
            self.rejected += 1
            self.last_error = str(e)
            return self.last_error
        self.accepted += 1
        self._pending.append((now, cmd))
        return ""

    def command_stale(self, now: float) -> bool:
        """True if no command has been effective within cmd_timeout (the robot's watchdog)."""
        if self._active is None:
            return True
        return now - self.config.latency - self._active[0] > self.config.cmd_timeout

    # ---- integration ----------------------------------------------------------------------------
    def step(self, now: float) -> None:
        """Advance the model to time ``now`` (sub-stepped at <= 10 ms)."""
        dt_total = now - self.time
        if dt_total <= 0.0:
            return
        n = max(1, int(math.ceil(dt_total / 0.01)))
        dt = dt_total / n
        for i in range(n):
            self._step(self.time + dt * (i + 1), dt)
        self.time = now

    def _targets(self, now: float) -> tuple:
        c = self.config
        while self._pending and self._pending[0][0] + c.latency <= now:
            self._active = self._pending.popleft()
        targets = (0.0, 0.0, 0.0, self.roll, self.pitch, self.body_yaw, self.dheight)
        if self.command_stale(now):
            self.mode = wire.MODE_IDLE if self._active is None else self.mode
            return targets
        cmd = self._active[1]
        self.mode, self.gait_type = cmd.mode, cmd.gaitType
        self.led = tuple((led["r"], led["g"], led["b"]) for led in cmd.led)
        dh = max(c.min_body_height, min(c.max_body_height, cmd.bodyHeight))
        if cmd.mode == wire.MODE_VELOCITY_WALK:
            self.unmodeled_mode = None
            return (_clamp(cmd.velocity[0], c.max_vx), _clamp(cmd.velocity[1], c.max_vy),
                    _clamp(cmd.yawSpeed, c.max_wz), 0.0, 0.0, 0.0, dh)
        if cmd.mode == wire.MODE_FORCE_STAND:
            self.unmodeled_mode = None
            e = cmd.euler
            return (0.0, 0.0, 0.0, _clamp(e[0], c.max_roll), _clamp(e[1], c.max_pitch), _clamp(e[2], c.max_yaw), dh)
        if cmd.mode == wire.MODE_IDLE:
            self.unmodeled_mode = None
            return (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        self.unmodeled_mode = cmd.mode
        return targets

    def _step(self, now: float, dt: float) -> None:
        c = self.config
        tvx, tvy, twz, troll, tpitch, tyaw, tdh = self._targets(now)
        vx0, vy0 = self.vx, self.vy
        self.vx = _toward(self.vx, tvx, c.max_acc_x * dt)
        self.vy = _toward(self.vy, tvy, c.max_acc_y * dt)
        self.wz = _toward(self.wz, twz, c.max_acc_wz * dt)
        self.acc = ((self.vx - vx0) / dt, (self.vy - vy0) / dt)
        creep = self.drift_gain * abs(self.wz)
        self.slip = (creep * math.cos(c.drift_heading), creep * math.sin(c.drift_heading))
        old = (self.roll, self.pitch, self.body_yaw, self.dheight)
        self.roll = _toward(self.roll, troll, c.attitude_rate * dt)
        self.pitch = _toward(self.pitch, tpitch, c.attitude_rate * dt)
        self.body_yaw = _toward(self.body_yaw, tyaw, c.attitude_rate * dt)
        self.dheight = _toward(self.dheight, tdh, c.height_rate * dt)
        self.rates = ((self.roll - old[0]) / dt, (self.pitch - old[1]) / dt, (self.body_yaw - old[2]) / dt)
        self.dheight_rate = (self.dheight - old[3]) / dt
        mid = self.heading + 0.5 * self.wz * dt
        cm, sm = math.cos(mid), math.sin(mid)
        vx_true, vy_true = self.vx + self.slip[0], self.vy + self.slip[1]
        self.x += (vx_true * cm - vy_true * sm) * dt
        self.y += (vx_true * sm + vy_true * cm) * dt
        # Own odometry: leg odometry without the slip, heading from the IMU (true).
        mo = mid - self.config.yaw0
        self.odom_x += (self.vx * math.cos(mo) - self.vy * math.sin(mo)) * dt
        self.odom_y += (self.vx * math.sin(mo) + self.vy * math.cos(mo)) * dt
        self.heading = wrap_angle(self.heading + self.wz * dt)

    # ---- outputs --------------------------------------------------------------------------------
    def body_height(self) -> float:
        """Absolute height of base_link above the floor [m]."""
        return wire.NOMINAL_BODY_HEIGHT + self.dheight

    def yaw(self) -> float:
        """Body yaw in the world frame (heading of the feet + body yaw offset) [rad]."""
        return wrap_angle(self.heading + self.body_yaw)

    def pose(self) -> tuple:
        """Ground truth (x, y, z, roll, pitch, yaw) of base_link in the world frame."""
        return (self.x, self.y, self.body_height(), self.roll, self.pitch, self.yaw())

    def twist(self) -> tuple:
        """Ground truth (vx, vy, vz, wx, wy, wz) in the body frame (roll/pitch ignored for velocity)."""
        return (self.vx + self.slip[0], self.vy + self.slip[1], self.dheight_rate, self.rates[0], self.rates[1],
                self.wz + self.rates[2])

    def walking(self) -> bool:
        """True while the robot trots (mode 2 with a fresh command)."""
        return self.mode == wire.MODE_VELOCITY_WALK and not self.command_stale(self.time)

    def press(self, buttons: tuple, now: float, duration: float) -> None:
        """Hold remote buttons (names of ``unitree_wire.BUTTONS``) from ``now`` for ``duration`` s.

        Raises:
            ValueError: an unknown button name or a negative/non-finite duration.
        """
        unknown = [b for b in buttons if b not in wire.BUTTONS]
        if unknown:
            raise ValueError("unknown remote buttons %s (known: %s)" % (unknown, ", ".join(wire.BUTTONS)))
        if not (math.isfinite(duration) and duration >= 0.0):
            raise ValueError("duration must be >= 0 s, got %r" % duration)
        self._buttons = tuple(buttons)
        self._buttons_until = now + duration

    def buttons(self, now: float) -> tuple:
        """Remote buttons held at ``now``."""
        return self._buttons if now < self._buttons_until else ()

    def high_state(self) -> dict:
        """What the A1 would report now: HighState members by their SDK names (both layouts' superset)."""
        yaw_imu = wrap_angle(self.yaw() - self.config.yaw0)
        qx, qy, qz, qw = rpy_to_quat(self.roll, self.pitch, yaw_imu)
        tw = self.twist()
        # Specific force in the body frame: gravity seen through roll/pitch plus horizontal acceleration.
        g = self.GRAVITY
        cr, sr = math.cos(self.roll), math.sin(self.roll)
        cp, sp = math.cos(self.pitch), math.sin(self.pitch)
        legs = self.legs
        legs.update(self.time, self.walking(), self.body_height(), (self.vx, self.vy, self.wz))
        forces = tuple(int(round(f)) for f in legs.force)
        return {
            "levelFlag": wire.HIGHLEVEL,
            "mode": self.mode,
            "gaitType": self.gait_type,
            "footRaiseHeight": FOOT_RAISE,
            "imu": {
                "quaternion": (qw, qx, qy, qz),
                "gyroscope": (tw[3], tw[4], tw[5]),
                "accelerometer": (self.acc[0] - g * sp, self.acc[1] + g * sr * cp, g * cr * cp),
                "rpy": (self.roll, self.pitch, yaw_imu),
                "temperature": 30,
            },
            "position": (self.odom_x, self.odom_y, 0.0),
            "bodyHeight": self.body_height(),
            "velocity": (self.vx, self.vy, 0.0),
            "yawSpeed": self.wz,
            "motorState": [{"mode": 0x0A, "q": legs.q[i], "dq": legs.dq[i], "tauEst": legs.tau[i],
                            "temperature": 35} for i in range(12)],
            "footForce": forces,
            "footForceEst": forces,
            "footPosition2Body": [{"x": x, "y": y, "z": z} for x, y, z in legs.feet],
            "wirelessRemote": wire.remote_bytes(self.buttons(self.time)),
        }
