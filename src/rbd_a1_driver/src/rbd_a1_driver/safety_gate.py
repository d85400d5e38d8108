"""The driver's safety gate (ROS-free): what HighCmd goes to the A1, given the inputs and their ages.

Rules (DESIGN.md §5.2/§5.3, CONTRACT.md):

* No velocity command for ``cmd_timeout`` (0.25 s) => zero velocity.
* A velocity command with a NaN/inf component is rejected and replaced by zero velocity.
* Finite velocities are clamped per axis to ``max_vx`` / ``max_vy`` / ``max_wz``.
* E-stop engaged (``/rbd_controller/estop`` true) => zero velocity; velocity commands are ignored
  until it is released; the last command is forgotten, so motion only resumes on a new command.
  Never received => no gate.
* E-stop signal lost: the e-stop source (rbd_controller) republishes its flag periodically (10 Hz).
  The watchdog arms when two e-stop messages arrive less than ``estop_timeout`` (0.5 s) apart (a
  periodic source; a one-shot latched publisher never arms it). Once armed, no e-stop message for
  ``estop_timeout`` => treated as engaged (zero velocity, last command forgotten) until a fresh
  ``false`` arrives. ``estop_timeout`` 0 = off.
* ``estop_required`` (on the robot and in the simulated system): before the first e-stop message
  the gate counts as engaged (zero velocity, commands and body poses ignored), so nothing moves
  until the e-stop source is up. Off, "never received" means no gate (isolated tests).
* The A1's own remote as a physical e-stop (``remote_estop``): a HighState whose remote buttons
  hold the e-stop combination (default L2 + B) latches the gate at once (zero velocity from the
  next send cycle; the last command is forgotten). Only the operator's release clears it: the
  e-stop flag of rbd_controller must go true (it engaged, told by the driver) and then false
  while the combination is no longer held. A release while it is held is void.
* No HighState for ``state_timeout`` (0.5 s), or none yet => zero velocity (the link is suspect).
* Modes: a fresh non-zero velocity => mode 2 (velocity walking, trot). After the velocity has been
  zero for ``stand_delay`` the A1 is put in mode 1 (force stand) with the requested body pose
  (euler + bodyHeight); until then mode 2 with zero velocity lets the trot settle in place.
  A body pose requested while walking is stored and applied when standing.

All times are seconds on one monotonic clock chosen by the caller.
"""

import math

from rbd_a1_driver import unitree_layout as ul


class GateConfig:
    """Limits and timeouts of the gate (defaults match README.md)."""

    def __init__(
        self,
        max_vx: float = 0.5,
        max_vy: float = 0.3,
        max_wz: float = 1.0,
        cmd_timeout: float = 0.25,
        state_timeout: float = 0.5,
        stand_delay: float = 0.5,
        max_roll: float = 0.75,
        max_pitch: float = 0.75,
        max_yaw: float = 0.6,
        min_body_height: float = -0.16,
        max_body_height: float = 0.06,
        estop_timeout: float = 0.5,
        estop_required: bool = False,
        remote_estop: bool = True,
    ) -> None:
        values = dict(locals())
        values.pop("self")
        for name in ("estop_required", "remote_estop"):
            flag = values.pop(name)
            if not isinstance(flag, bool):
                raise ValueError("%s must be true or false, got %r" % (name, flag))
        for name, value in values.items():
            if not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError("%s must be a finite number, got %r" % (name, value))
        for name in ("max_vx", "max_vy", "max_wz", "cmd_timeout", "state_timeout", "max_roll", "max_pitch"):
            if values[name] <= 0.0:
                raise ValueError("%s must be > 0, got %r" % (name, values[name]))
        if stand_delay < 0.0 or max_yaw < 0.0 or estop_timeout < 0.0:
            raise ValueError("stand_delay, max_yaw and estop_timeout must be >= 0")
        if not min_body_height <= 0.0 <= max_body_height:
            raise ValueError("body height range must contain 0")
        self.max_vx = float(max_vx)
        self.max_vy = float(max_vy)
        self.max_wz = float(max_wz)
        self.cmd_timeout = float(cmd_timeout)
        self.state_timeout = float(state_timeout)
        self.stand_delay = float(stand_delay)
        self.max_roll = float(max_roll)
        self.max_pitch = float(max_pitch)
        self.max_yaw = float(max_yaw)
        self.min_body_height = float(min_body_height)
        self.max_body_height = float(max_body_height)
        self.estop_timeout = float(estop_timeout)
        self.estop_required = estop_required
        self.remote_estop = remote_estop


def _clamp(value: float, limit: float) -> float:
    return max(-limit, min(limit, value))


class GateOutput:
    """What the gate decided for one send cycle."""

    __slots__ = ("mode", "gait_type", "velocity", "yaw_speed", "euler", "body_height", "reason")

    def __init__(self, mode: int, gait_type: int, velocity: tuple, yaw_speed: float, euler: tuple,
                 body_height: float, reason: str) -> None:
        self.mode = mode
        self.gait_type = gait_type
        self.velocity = velocity
        self.yaw_speed = yaw_speed
        self.euler = euler
        self.body_height = body_height
        self.reason = reason  # why the velocity is zero ("" when moving as commanded)

    def to_high_cmd(self) -> ul.HighCmd:
        """Fill a HighCmd with this decision."""
        cmd = ul.HighCmd()
        cmd.mode = self.mode
        cmd.gait_type = self.gait_type
        cmd.velocity = self.velocity
        cmd.yaw_speed = self.yaw_speed
        cmd.euler = self.euler
        cmd.body_height = self.body_height
        return cmd


class SafetyGate:
    """Turns cmd_vel, body-pose requests, e-stop and state freshness into the HighCmd to send."""

    def __init__(self, config: GateConfig = None) -> None:
        self.config = config if config is not None else GateConfig()
        self._vel = (0.0, 0.0, 0.0)
        self._vel_time = None
        self._last_motion_time = None  # last time a non-zero velocity was being sent
        self._estop = None  # None = never received
        self._estop_time = None  # arrival of the last e-stop message
        self._estop_armed = False  # the e-stop source has shown it is periodic
        self._estop_lost = False  # engaged because the e-stop messages stopped
        self._remote_held = False  # the remote's e-stop combination held in the last HighState
        self._remote_latched = False  # engaged by the remote, waiting for the operator's release
        self._remote_ack = False  # rbd_controller's e-stop flag was true since the latch engaged
        self._state_time = None
        self._euler = (0.0, 0.0, 0.0)
        self._body_height = 0.0
        self.rejected = 0  # count of rejected velocity commands

    # ---- inputs ---------------------------------------------------------------------------------
    def set_velocity(self, vx: float, vy: float, wz: float, now: float, others: tuple = ()) -> str:
        """Take a velocity command (body frame, SI). Returns "" if used, else why it was not.

        ``others`` are the Twist components the A1 cannot use (linear.z, angular.x/y): they must
        be finite too, or the whole command is rejected.
        """
        values = (vx, vy, wz) + tuple(others)
        if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in values):
            self._vel = (0.0, 0.0, 0.0)
            self._vel_time = now
            self.rejected += 1
            return "non-finite velocity %r rejected: zero velocity sent" % (values,)
        self._check_estop_signal(now)
        if self._remote_latched:
            return "remote e-stop engaged: velocity command ignored"
        if self._estop:
            return "e-stop engaged: velocity command ignored"
        if self.estop_missing:
            return "no e-stop signal yet (estop_required): velocity command ignored"
        c = self.config
        self._vel = (_clamp(float(vx), c.max_vx), _clamp(float(vy), c.max_vy), _clamp(float(wz), c.max_wz))
        self._vel_time = now
        if self._vel != (vx, vy, wz):
            return "clamped to %r" % (self._vel,)
        return ""

    def set_estop(self, engaged: bool, now: float) -> None:
        """Latch the e-stop state; engaging it forgets the last velocity command.

        Every call is one received e-stop message: it feeds the e-stop signal watchdog, and a
        fresh ``false`` releases an engagement caused by a lost signal.
        """
        timeout = self.config.estop_timeout
        if self._estop_time is not None and timeout > 0.0 and now - self._estop_time < timeout:
            self._estop_armed = True
        self._estop_time = now
        self._estop_lost = False
        self._engage(bool(engaged))
        if self._remote_latched:
            if engaged:
                self._remote_ack = True
            elif self._remote_ack and not self._remote_held:
                self._remote_latched = False  # the operator released it after it engaged
            else:
                self._remote_ack = False  # released while held (or before it engaged): void

    def set_remote(self, held: bool) -> bool:
        """The remote's e-stop combination is (not) held in the latest HighState.

        Returns:
            True if this engaged the remote e-stop (it was not latched before).
        """
        if not self.config.remote_estop:
            return False
        self._remote_held = bool(held)
        if not held or self._remote_latched:
            return False
        self._remote_latched = True
        self._remote_ack = False
        self._vel = (0.0, 0.0, 0.0)
        self._vel_time = None
        return True

    def _engage(self, engaged: bool) -> None:
        self._estop = engaged
        if engaged:
            self._vel = (0.0, 0.0, 0.0)
            self._vel_time = None

    def _check_estop_signal(self, now: float) -> None:
        """Engage the gate when an armed e-stop signal has been silent for estop_timeout."""
        if self._estop_lost or not self._estop_armed or self.config.estop_timeout <= 0.0:
            return
        if now - self._estop_time > self.config.estop_timeout:
            self._estop_lost = True
            self._engage(True)

    def set_body_pose(self, roll: float, pitch: float, yaw: float, body_height: float) -> str:
        """Request a standing body pose. Returns "" if accepted, else the reason it was rejected."""
        values = (roll, pitch, yaw, body_height)
        if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in values):
            return "non-finite body pose %r rejected" % (values,)
        c = self.config
        if abs(roll) > c.max_roll or abs(pitch) > c.max_pitch or abs(yaw) > c.max_yaw:
            return "attitude (%.3f, %.3f, %.3f) rad outside limits (+-%.2f, +-%.2f, +-%.2f)" % (
                roll, pitch, yaw, c.max_roll, c.max_pitch, c.max_yaw)
        if not c.min_body_height <= body_height <= c.max_body_height:
            return "body_height %.3f m outside [%.3f, %.3f]" % (body_height, c.min_body_height, c.max_body_height)
        if self._estop or self._remote_latched:
            return "e-stop engaged: body pose ignored"
        if self.estop_missing:
            return "no e-stop signal yet (estop_required): body pose ignored"
        self._euler = (float(roll), float(pitch), float(yaw))
        self._body_height = float(body_height)
        return ""

    def note_state(self, now: float) -> None:
        """Record that a valid HighState arrived."""
        self._state_time = now

    # ---- queries --------------------------------------------------------------------------------
    @property
    def estop(self) -> bool:
        """True while the e-stop is engaged (by a message or by a lost e-stop signal)."""
        return bool(self._estop)

    @property
    def remote_state(self) -> str:
        """The remote e-stop: ``off`` (switched off), ``ready`` or ``engaged`` (latched)."""
        if not self.config.remote_estop:
            return "off"
        return "engaged" if self._remote_latched else "ready"

    @property
    def remote_held(self) -> bool:
        """True while the last HighState had the remote's e-stop combination held."""
        return self._remote_held

    @property
    def estop_missing(self) -> bool:
        """True while estop_required holds the gate because no e-stop message has arrived yet."""
        return self.config.estop_required and self._estop is None

    @property
    def estop_armed(self) -> bool:
        """True once the e-stop source has shown it is periodic (the signal watchdog runs)."""
        return self._estop_armed

    @property
    def estop_lost(self) -> bool:
        """True while the gate is engaged because the e-stop messages stopped."""
        return self._estop_lost

    def state_fresh(self, now: float) -> bool:
        """True if a HighState arrived within state_timeout."""
        return self._state_time is not None and now - self._state_time <= self.config.state_timeout

    def command(self, now: float) -> GateOutput:
        """Decide the command for this send cycle."""
        reason = ""
        self._check_estop_signal(now)
        vel = self._vel
        if self._remote_latched:
            reason = "remote e-stop (A1 remote)"
        elif self._estop_lost:
            reason = "e-stop signal lost (no /rbd_controller/estop for > %.2f s)" % self.config.estop_timeout
        elif self._estop:
            reason = "e-stop"
        elif self.estop_missing:
            reason = "no e-stop signal yet (estop_required)"
        elif self._vel_time is None:
            reason = "no velocity command yet"
        elif now - self._vel_time > self.config.cmd_timeout:
            reason = "velocity command stale (> %.2f s)" % self.config.cmd_timeout
        elif not self.state_fresh(now):
            reason = "HighState stale (> %.2f s)" % self.config.state_timeout
        if reason:
            vel = (0.0, 0.0, 0.0)
        moving = vel != (0.0, 0.0, 0.0)
        if moving:
            self._last_motion_time = now
        walking = moving or (
            self._last_motion_time is not None and now - self._last_motion_time < self.config.stand_delay
        )
        if walking:
            return GateOutput(ul.MODE_VELOCITY_WALK, ul.GAIT_TROT, (vel[0], vel[1]), vel[2], (0.0, 0.0, 0.0),
                              self._body_height, reason)
        return GateOutput(ul.MODE_FORCE_STAND, ul.GAIT_IDLE, (0.0, 0.0), 0.0, self._euler, self._body_height,
                          reason)
