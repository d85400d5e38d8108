"""The position controller: its FSM (:mod:`rbd_pos_controller.fsm`) driving the control law. ROS-free.

The node feeds poses, stop/release events and the clock in; step() returns the velocity to
command (Eq. 1 in PRE_ROTATION, LINEAR and POST_ROTATION, the zone-gated translation in GUARDED,
the path follower in FOLLOWING, zero otherwise). The stop states zero the velocity on entry; the
LiDAR slowdown scale applies to every motion but GUARDED.
"""

import math
from typing import Callable, Optional, Sequence

from rbd_geometry.goal import Goal
from rbd_pos_controller.control_law import Errors, Twist2D, hold_command, linear_command, rotation_command, wrap_angle
from rbd_pos_controller.fsm import MOTION_STATES, STATUS, STOP_STATES, TRANSITIONS, Event, State
from rbd_pos_controller.goal import GoalRejectedError
from rbd_pos_controller.params import Params
from rbd_pos_controller.path_follower import PathFollower, check_path
from rbd_pos_controller.zone_guard import ZoneGuard, cap_speed

ZERO = (0.0, 0.0, 0.0)  # type: Twist2D


class PositionController:
    """The position controller: FSM + Eq. 1.

    Args:
        params: tolerances, gains and options.
        on_enter: optional callback(state) called after every state change (after the
            controller's own entry actions).
        guard: the per-side zone gate of GUARDED goals (default: ZoneGuard()).
    """

    def __init__(
        self,
        params: Optional[Params] = None,
        on_enter: Optional[Callable[[State], None]] = None,
        guard: Optional[ZoneGuard] = None,
    ) -> None:
        self.params = params if params is not None else Params()
        self.guard = guard if guard is not None else ZoneGuard()
        self.guarded_speed = 0.0
        self.follower = None  # type: Optional[PathFollower]
        self._next_follower = None  # type: Optional[PathFollower]
        self.state = State.WAITING_FOR_POSE
        self.goal = None  # type: Optional[Goal]
        self.hold = None  # type: Optional[Tuple[float, float]]
        self.estop = False
        self.collision = False
        self.speed_scale = 1.0
        self.body_pose_request = None  # type: Optional[Goal]
        self.history = []  # type: List[Tuple[State, Event, State]]
        self._pose = None  # type: Optional[Tuple[float, float, float]]
        self._pose_time = None  # type: Optional[float]
        self._body_pose_since = None  # type: Optional[float]
        self._last_cmd = ZERO
        self._on_enter = on_enter

    # ----------------------------------------------------------------- FSM core
    @property
    def status(self) -> str:
        """Status for the GUI / main controller: idle, running, emergency or collision."""
        return STATUS[self.state]

    def fire(self, event: Event) -> bool:
        """Apply event; return True if the transition table has an entry for it."""
        target = TRANSITIONS.get((self.state, event))
        if target is None:
            return False
        source = self.state
        self.state = target
        self.history.append((source, event, target))
        self._enter(target)
        if self._on_enter is not None:
            self._on_enter(target)
        return True

    def _enter(self, state: State) -> None:
        if state in STOP_STATES or state in (State.WAITING_FOR_POSE, State.BODY_POSE):
            self._last_cmd = ZERO  # zero velocity on entry
        if state in STOP_STATES or state == State.WAITING_FOR_POSE:
            self.goal = None
            self.hold = None
            self.body_pose_request = None
        self.follower = self._next_follower if state == State.FOLLOWING else None
        self._next_follower = None
        if state == State.PRE_ROTATION and self._pose is not None:
            self.hold = (self._pose[0], self._pose[1])
        if state == State.POST_ROTATION and self.goal is not None:
            self.hold = (self.goal.x, self.goal.y)
        if state == State.BODY_POSE:
            self.body_pose_request = self.goal
            self._body_pose_since = None

    # ----------------------------------------------------------------- inputs
    def update_pose(self, x: float, y: float, yaw: float, now: float) -> bool:
        """Feed a pose measurement received at now [s]; NaN poses are ignored (False)."""
        if not all(math.isfinite(v) for v in (x, y, yaw, now)):
            return False
        self._pose = (x, y, yaw)
        self._pose_time = now
        return True

    def pose_fresh(self, now: float) -> bool:
        """True if a pose arrived within pose_timeout before now."""
        return self._pose_time is not None and now - self._pose_time <= self.params.pose_timeout

    def set_speed_scale(self, scale: float) -> None:
        """Slowdown from the LiDAR zone: clamp to [0, 1]; NaN means stop (0)."""
        self.speed_scale = min(1.0, max(0.0, scale)) if math.isfinite(scale) else 0.0

    def set_emergency(self, engaged: bool) -> None:
        """Engage or release the emergency stop (release goes to WAITING_FOR_POSE / idle)."""
        self.estop = bool(engaged)
        if self.estop:
            self.fire(Event.ESTOP)
        elif self.fire(Event.ESTOP_RELEASE) and self.collision:
            self.fire(Event.COLLISION)

    def set_collision(self, detected: bool) -> None:
        """Report a collision or its clearance (clear goes to WAITING_FOR_POSE / idle)."""
        self.collision = bool(detected)
        self.fire(Event.COLLISION if self.collision else Event.COLLISION_CLEAR)

    def update_zone(self, now: float, points: Sequence[int], stale: bool = False, error: str = "") -> None:
        """Feed one /rbd_lidar/state reading (critical points per side) received at now [s]."""
        self.guard.update(now, points, stale, error)

    def _refuse_unless_ready(self, now: float) -> None:
        """Raise GoalRejectedError in a stop state or without a fresh pose (any new goal)."""
        if self.state == State.EMERGENCY_STOP:
            raise GoalRejectedError("emergency stop engaged")
        if self.state == State.COLLISION_DETECTED:
            raise GoalRejectedError("collision detected")
        if not self.pose_fresh(now):
            raise GoalRejectedError("no robot pose received within %.2f s" % self.params.pose_timeout)

    def set_guarded_goal(self, goal: Goal, max_speed: float, now: float) -> None:
        """Accept an avoidance goal: translate to (goal.x, goal.y) at <= max_speed, heading kept.

        Raises:
            GoalRejectedError: NaN/inf values, max_speed outside (0, max_vx], a stop state, no
                fresh pose or no fresh zone reading.
        """
        if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in (goal.x, goal.y, max_speed)):
            raise GoalRejectedError("guarded goal has non-finite values: %r, max_speed %r" % (goal, max_speed))
        if not 0.0 < max_speed <= self.params.gains.max_vx:
            raise GoalRejectedError(
                "max_speed must be in (0, %.2f] m/s, got %r" % (self.params.gains.max_vx, max_speed)
            )
        self._refuse_unless_ready(now)
        if not self.guard.fresh(now):
            raise GoalRejectedError("no valid LiDAR zone state within %.2f s" % self.guard.timeout)
        self.goal = Goal(goal.x, goal.y, self._pose[2])
        self.guarded_speed = float(max_speed)
        self.fire(Event.GOAL_GUARDED)

    def set_path(self, poses: Sequence[Sequence[float]], max_speed: float, now: float) -> None:
        """Accept a path of poses (x, y, yaw) to follow at <= max_speed (replaces a running goal or path).

        Raises:
            GoalRejectedError: an empty, too long or non-finite path, max_speed outside (0, max_vx],
                a stop state, or no fresh pose.
        """
        why = check_path(poses, max_speed, self.params.gains)
        if why:
            raise GoalRejectedError(why)
        self._refuse_unless_ready(now)
        last = poses[-1]
        self.goal = Goal(float(last[0]), float(last[1]), float(last[2]))
        self._next_follower = PathFollower(poses, max_speed, self.params.gains)
        self.fire(Event.GOAL_PATH)

    def set_goal(self, goal: Goal, now: float) -> None:
        """Accept a new goal (replaces a running one).

        Raises:
            GoalRejectedError: NaN/inf values, a stop state, or no fresh pose to start from.
        """
        values = (goal.x, goal.y, goal.yaw, goal.roll, goal.pitch, goal.body_height)
        if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in values):
            raise GoalRejectedError("goal has non-finite values: %r" % (goal,))
        self._refuse_unless_ready(now)
        x, y, _ = self._pose
        self.goal = goal
        far = math.hypot(goal.x - x, goal.y - y) >= self.params.skip_rotation_distance
        self.fire(Event.GOAL_FAR if far else Event.GOAL_NEAR)

    def body_pose_done(self, now: float) -> None:
        """The body pose request was answered (success or failure) at now [s]."""
        if self.state == State.BODY_POSE:
            self.body_pose_request = None
            self._body_pose_since = now

    # ----------------------------------------------------------------- control
    def step(self, now: float) -> Twist2D:
        """Advance the FSM with the latest pose and return (v_x, v_y, yaw_rate) to command.

        Zero whenever idle, stopped, setting the body pose, or the pose is stale.
        """
        if self.state not in MOTION_STATES:
            return ZERO
        if self.state == State.BODY_POSE:
            if self._body_pose_since is not None and now - self._body_pose_since >= self.params.body_pose_settle:
                self.fire(Event.BODY_POSE_DONE)
            return ZERO
        if not self.pose_fresh(now):
            self._last_cmd = ZERO
            return ZERO
        if self.state == State.GUARDED:
            # No slowdown scale here: it is 0 while anything is in the zone; the guard gates per side.
            self._last_cmd = self._guarded_command(now)
            return self._last_cmd
        if self.state == State.FOLLOWING:
            cmd = self.follower.command(self._pose)
            if self.follower.done:
                self.fire(Event.PATH_DONE)
                return ZERO
            self._last_cmd = tuple(v * self.speed_scale for v in cmd)
            return self._last_cmd
        cmd = self._motion_command()
        # Transitions may chain (e.g. a goal already reached skips straight to BODY_POSE).
        self._last_cmd = tuple(v * self.speed_scale for v in cmd)
        return self._last_cmd

    def _guarded_command(self, now: float) -> Twist2D:
        p = self.params
        x, y, yaw = self._pose
        goal = self.goal
        err = Errors(x, y, yaw, goal.x, goal.y, goal.yaw)
        if err.rho <= p.position_tolerance:
            self.fire(Event.GUARDED_REACHED)
            return ZERO
        vx, vy = linear_command(err, p.gains, p.keep_direction)
        vx, vy = cap_speed(vx, vy, self.guarded_speed)
        return self.guard.filter((vx, vy, 0.0), now)

    def _motion_command(self) -> Twist2D:
        p = self.params
        x, y, yaw = self._pose
        for _ in range(4):
            goal = self.goal
            if self.state == State.PRE_ROTATION:
                err = Errors(x, y, yaw, goal.x, goal.y, goal.yaw)
                if abs(err.gamma) <= p.align_tolerance:
                    self.fire(Event.ALIGNED)
                    continue
                return self._rotate(err.gamma, x, y, yaw)
            if self.state == State.LINEAR:
                err = Errors(x, y, yaw, goal.x, goal.y, goal.yaw)
                if err.rho <= p.position_tolerance:
                    self.fire(Event.REACHED)
                    continue
                vx, vy = linear_command(err, p.gains, p.keep_direction)
                return (vx, vy, 0.0)
            if self.state == State.POST_ROTATION:
                delta = wrap_angle(goal.yaw - yaw)
                if abs(delta) <= p.yaw_tolerance:
                    self.fire(Event.ORIENTED)
                    continue
                return self._rotate(delta, x, y, yaw)
            return ZERO
        return ZERO

    def _rotate(self, angle_error: float, x: float, y: float, yaw: float) -> Twist2D:
        p = self.params
        wz = rotation_command(angle_error, p.gains)
        vx = vy = 0.0
        if self.hold is not None and (p.rotation_x_control or p.rotation_y_control):
            err = Errors(x, y, yaw, self.hold[0], self.hold[1], yaw)
            vx, vy = hold_command(err, p.k_hold, p.max_v_hold, p.rotation_x_control, p.rotation_y_control)
        return (vx, vy, wz)

    @property
    def last_command(self) -> Twist2D:
        """The last velocity step() returned."""
        return self._last_cmd
