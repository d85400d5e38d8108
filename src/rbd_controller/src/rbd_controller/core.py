"""Main controller behaviour around the FSM, with the ROS side injected as ports. ROS-free.

The node calls the stop handlers from its service callbacks and tick() from one loop
thread. Slow calls (gesture poll, path generation, set_position, body pose) run in tick()
without the lock; their results are dropped if the FSM changed meanwhile (epoch check).

Active collision avoidance (issue 17) runs in the same loop: the zone stop is classified while
COLLISION_DETECTED (static -> BLOCKED), BLOCKED starts ESCAPING after ~blocked_timeout,
ESCAPING sends guarded goals (the position controller gates them per zone side) until the zone
is clear by a margin, AVOIDING plans a detour to the blocked pose and sends it pose by pose,
DODGING steps an idle robot away from an approaching visitor and back home. Every decision
is in a ROS-free module (blocking, escape, detour, dodge, arena); this file only sequences them.
"""

import math
import threading
from typing import Any, Callable, List, Sequence, Tuple

from rbd_controller.blocking import MOVING, STATIC
from rbd_controller.detour import DetourPlanner, zone_occupied_at
from rbd_controller.dodge import dodge_target
from rbd_controller.escape import SIDE_NAMES, TOWARDS, clear_by_margin, plan_escape
from rbd_controller.fsm import Event, Fsm, State
from rbd_controller.perception import AvoidParams, Perception
from rbd_controller.watchdog import POLICIES, OperatorWatchdog

#: Stops after which AVOIDING goes on with its detour instead of planning a new one.
RESUMED_FROM = (State.COLLISION_DETECTED, State.EMERGENCY_STOP, State.OPERATOR_LOST)
#: Stopped again within this many seconds of a resume: the same blockage (stop-and-go creeping) [s].
REBLOCK_WINDOW = 3.0

PathResult = Tuple[bool, str, Sequence[Any], Sequence[str]]


class Ports:
    """What the controller needs from the outside world (ROS in the node, fakes in tests).

    Every callable must not raise; failures are reported through return values.

    Args:
        get_gesture: () -> command or "" (GetLastGesture).
        generate_path: command -> (success, message, poses, names) (GeneratePath).
        set_position: pose -> (accepted, message) (SetPosition).
        set_body_pose: (roll, pitch, body_height) -> bool (SetBodyPose).
        pos_emergency: bool -> None: tell the position controller about the e-stop.
        pos_collision: bool -> None: tell the position controller about a collision.
        publish_estop: bool -> None: the latched e-stop flag the driver gates on.
        publish: controller -> None: publish state, queue, path (called after changes).
        log: (level, message) -> None, level in "info", "warn", "error".
        set_guarded_position: (x, y, max_speed) -> (accepted, message) (SetGuardedPosition).
        make_pose: (x, y, yaw) -> a pose for set_position (geometry_msgs/Pose in the node).
        pose_xy: pose -> (x, y, yaw) of a trick pose.
        publish_avoidance: dict -> None: avoidance events, plans and the arena (RViz, reports).
    """

    def __init__(
        self,
        get_gesture: Callable[[], str],
        generate_path: Callable[[str], PathResult],
        set_position: Callable[[Any], Tuple[bool, str]],
        set_body_pose: Callable[[float, float, float], bool],
        pos_emergency: Callable[[bool], None],
        pos_collision: Callable[[bool], None],
        publish_estop: Callable[[bool], None],
        publish: Callable[[Any], None],
        log: Callable[[str, str], None],
        set_guarded_position: Callable[[float, float, float], Tuple[bool, str]] = None,
        make_pose: Callable[[float, float, float], Any] = None,
        pose_xy: Callable[[Any], Tuple[float, float, float]] = None,
        publish_avoidance: Callable[[dict], None] = None,
    ) -> None:
        self.get_gesture = get_gesture
        self.generate_path = generate_path
        self.set_position = set_position
        self.set_body_pose = set_body_pose
        self.pos_emergency = pos_emergency
        self.pos_collision = pos_collision
        self.publish_estop = publish_estop
        self.publish = publish
        self.log = log
        self.set_guarded_position = set_guarded_position or (lambda x, y, v: (False, "no guarded motion"))
        self.make_pose = make_pose or (lambda x, y, yaw: (x, y, yaw))
        self.pose_xy = pose_xy or (lambda pose: (pose[0], pose[1], pose[2]))
        self.publish_avoidance = publish_avoidance or (lambda info: None)


class MainController:
    """Gesture -> path -> poses, preempted by e-stop and collision, resuming afterwards.

    Args:
        ports: the outside world.
        attentive_pitch: body pitch while waiting for a gesture [rad] (< 0: nose up, camera
            towards the person).
        gesture_period: minimum time between two gesture polls [s].
        pose_timeout: longest time one pose may take before the trick is aborted [s].
        start_timeout: time for the position controller to report "running" after accepting [s].
        operator_timeout: operator heartbeat silence that stops the robot [s]; <= 0 disables
            the watchdog. It arms with the first heartbeat.
        operator_policy: ``stop`` (stop the current trick at once, resume it when heartbeats
            return or on an e-stop release) or ``finish`` (finish the current trick, then
            wait in OPERATOR_LOST).
        lidar_timeout: no /rbd_lidar/state for this long counts as a collision (the collision
            monitor died or hangs) [s]; <= 0 disables. It arms with the first state message.
        avoid: active collision avoidance parameters (None: avoidance and dodge off).

    Raises:
        ValueError: unknown operator_policy or non-finite operator_timeout.
    """

    def __init__(
        self,
        ports: Ports,
        attentive_pitch: float = -0.25,
        gesture_period: float = 0.2,
        pose_timeout: float = 60.0,
        start_timeout: float = 3.0,
        operator_timeout: float = 0.0,
        operator_policy: str = "stop",
        lidar_timeout: float = 0.0,
        avoid: AvoidParams = None,
    ) -> None:
        if operator_policy not in POLICIES:
            raise ValueError("operator_policy must be one of %s, got %r" % (POLICIES, operator_policy))
        self.operator = OperatorWatchdog(operator_timeout)
        self.operator_policy = operator_policy
        self.lidar = OperatorWatchdog(lidar_timeout)
        self.lidar_lost = False
        self.ports = ports
        self.attentive_pitch = attentive_pitch
        self.gesture_period = gesture_period
        self.pose_timeout = pose_timeout
        self.start_timeout = start_timeout
        self.lock = threading.RLock()
        self.command = ""
        self.queue = []  # type: List[Tuple[Any, str]]
        self.current = None  # type: Optional[Tuple[Any, str]]
        self.sent_at = None  # type: Optional[float]
        self.seen_running = False
        self.status_seq = 0
        self.status = ""
        self._sent_seq = 0
        self._last_poll = -1e9
        self._body_pose_wanted = None  # type: Optional[Tuple[float, float, float]]
        self._flush_gesture = False
        self._synced = (None, None)  # (emergency, collision) told to the position controller
        self._now = 0.0  # latest time seen by tick()/on_heartbeat()
        self.avoid = avoid if avoid is not None else AvoidParams(enabled=False, dodge=False)
        self.perception = Perception(self.avoid)
        self.planner = DetourPlanner(inflation=self.avoid.inflation, clearance=self.avoid.clearance)
        self.home = None  # type: Optional[Tuple[float, float]]  # where the show is (dodge, arena, back home)
        self.home_yaw = None  # type: Optional[float]
        self._returning = False  # the "back home" pose of this trick is queued (tried once per trick)
        self.trick_home = None  # type: Optional[Tuple[float, float, float]]
        self.detour = None  # type: Optional[List[Any]]
        self.stats = {"avoided": 0, "gave_up": 0, "escapes": 0, "dodges": 0, "blocked": 0}
        self._stop_since = None  # type: Optional[float]
        self._last_stop_end = -1e9
        self._active = 0.0  # seconds spent in BLOCKED / ESCAPING / AVOIDING (avoid_timeout clock)
        self._progress_active = 0.0
        self._last_tick = None  # type: Optional[float]
        self._episode_start = None  # type: Optional[float]
        self._trick_episodes_since = None  # type: Optional[float]  # first avoidance episode of this trick
        self._attempts = 0
        self._retry_at = 0.0
        self._reason = ""
        self.remote_held = False  # the A1 remote's e-stop combination is held (rbd_a1_driver reports it)
        self.fsm = Fsm(
            on_enter={
                State.EMERGENCY_STOP: self._enter_stop,
                State.COLLISION_DETECTED: self._enter_stop,
                State.OPERATOR_LOST: self._enter_stop,
                State.BLOCKED: self._enter_stop,
                State.ESCAPING: self._enter_avoidance,
                State.AVOIDING: self._enter_avoidance,
                State.DODGING: self._enter_avoidance,
                State.WAITING_FOR_GESTURE: self._enter_waiting,
                State.GENERATING_PATH: self._enter_generating,
                State.EXECUTING: self._enter_executing,
            }
        )

    # ------------------------------------------------------------------ properties
    @property
    def state(self) -> State:
        """Current FSM state."""
        return self.fsm.state

    def remaining(self) -> List[Tuple[Any, str]]:
        """The pose being executed (first) and the ones still queued."""
        with self.lock:
            return ([self.current] if self.current is not None else []) + list(self.queue)

    # ------------------------------------------------------------------ start
    def start(self) -> None:
        """Publish the power-up state (EMERGENCY_STOP) and stop the position controller."""
        with self.lock:
            self._sync_stops()
            self.ports.publish(self)

    # ------------------------------------------------------------------ stop inputs
    def set_emergency(self, engaged: bool) -> str:
        """Engage/release the e-stop (service, CLI, GUI); returns a message.

        A release while the A1 remote's e-stop combination is held is refused (see
        :meth:`release_refusal`); the state does not change.
        """
        with self.lock:
            if not engaged and self.remote_held:
                return self.release_refusal()
            before = self.fsm.state
            if not engaged and self.operator.lost(self._now):
                self.operator.disarm()  # the release acknowledges the lost link
            self.fsm.fire(Event.ESTOP if engaged else Event.ESTOP_RELEASE)
            self._sync_stops()
            self.ports.publish(self)
            return "%s -> %s" % (before.name, self.fsm.state.name)

    def release_refusal(self) -> str:
        """Why an e-stop release would be refused now ("" if it would not)."""
        if self.remote_held:
            return "release refused: the e-stop combination is held on the A1's remote"
        return ""

    def set_remote_estop(self, held: bool) -> str:
        """The A1's remote holds (True) or let go of (False) its e-stop combination.

        Held engages the e-stop through the same event as the service and blocks releases
        until it is let go; letting go releases nothing (the operator does). Returns a message.
        """
        with self.lock:
            self.remote_held = bool(held)
            if not held:
                return "remote e-stop combination let go"
            return self.set_emergency(True)

    def set_collision(self, detected: bool) -> str:
        """Collision reported (True) or cleared (False) by rbd_lidar; returns a message."""
        with self.lock:
            before = self.fsm.state
            self.fsm.fire(Event.COLLISION if detected else Event.COLLISION_CLEAR)
            self._sync_stops()
            self.ports.publish(self)
            return "%s -> %s" % (before.name, self.fsm.state.name)

    def on_heartbeat(self, now: float) -> None:
        """An operator heartbeat arrived at ``now`` [s]."""
        with self.lock:
            self._now = max(self._now, now)
            self.operator.beat(now)
            if self.fsm.operator_lost:
                before = self.fsm.state
                self.fsm.fire(Event.OPERATOR_BACK)
                self._sync_stops()
                self.ports.publish(self)
                self.ports.log("info", "operator link back (%s -> %s)" % (before.name, self.fsm.state.name))

    def on_lidar_state(self, now: float, collision: bool, reading: Any = None) -> None:
        """A CollisionState from rbd_lidar arrived at ``now`` [s].

        Args:
            now: arrival time [s].
            collision: its ``collision`` flag.
            reading: the same as an :class:`rbd_controller.escape.ZoneReading` (per-side points and
                distances) for the avoidance; None when not available.
        """
        if reading is not None:
            self.perception.on_zone(now, reading)
        with self.lock:
            self.lidar.beat(now)
            if not self.lidar_lost:
                return
            self.lidar_lost = False
            self.ports.log("info", "collision monitor back (collision %s)" % collision)
            self.fsm.fire(Event.COLLISION if collision else Event.COLLISION_CLEAR)
            self._sync_stops()
            self.ports.publish(self)

    def check_lidar(self, now: float) -> None:
        """No state from the collision monitor for lidar_timeout => collision; called from tick()."""
        with self.lock:
            if self.lidar_lost or not self.lidar.lost(now):
                return
            self.lidar_lost = True
            self.ports.log("error", "no /rbd_lidar/state for > %.2f s: collision (monitor lost)" % self.lidar.timeout)
            self.fsm.fire(Event.COLLISION)
            self._sync_stops()
            self.ports.publish(self)

    def check_operator(self, now: float) -> None:
        """Fire OPERATOR_LOST when the heartbeat is gone (per policy); called from tick()."""
        with self.lock:
            self._now = max(self._now, now)
            if self.fsm.operator_lost or not self.operator.lost(now):
                return
            if self.operator_policy == "finish" and self.fsm.state != State.WAITING_FOR_GESTURE:
                return  # let the current trick (or stop) run its course
            before = self.fsm.state
            self.fsm.fire(Event.OPERATOR_LOST)
            self._sync_stops()
            self.ports.publish(self)
            self.ports.log(
                "warn",
                "operator heartbeat lost for > %.1f s (policy %s): %s -> %s"
                % (self.operator.timeout, self.operator_policy, before.name, self.fsm.state.name),
            )

    def _sync_stops(self) -> None:
        """Tell the driver gate and the position controller; engage before release.

        OPERATOR_LOST holds the position controller like a collision does (it drops its
        goal and stops; the interrupted pose is re-sent on resume). It never touches the
        e-stop gate.
        """
        emergency = self.fsm.state == State.EMERGENCY_STOP
        collision = self.fsm.state in (State.COLLISION_DETECTED, State.OPERATOR_LOST, State.BLOCKED)
        old_emergency, old_collision = self._synced
        if emergency != old_emergency and emergency:
            self.ports.publish_estop(True)
            self.ports.pos_emergency(True)
        if collision != old_collision and collision:
            self.ports.pos_collision(True)
        if emergency != old_emergency and not emergency:
            self.ports.publish_estop(False)
            self.ports.pos_emergency(False)
        if collision != old_collision and not collision:
            self.ports.pos_collision(False)
        self._synced = (emergency, collision)

    def on_pos_status(self, status: str) -> None:
        """Status message from the position controller (idle/running/emergency/collision)."""
        with self.lock:
            self.status_seq += 1
            self.status = status
            if status == "running" and self.status_seq > self._sent_seq:
                self.seen_running = True

    # ------------------------------------------------------------------ on_enter hooks
    def _enter_stop(self, previous: State) -> None:
        self.sent_at = None  # the interrupted pose is re-sent on resume
        if self.fsm.state == State.COLLISION_DETECTED and previous not in (State.BLOCKED, State.EMERGENCY_STOP):
            # A robot that creeps stop-and-go at the same obstacle (the zone shrinks when it stops)
            # is still blocked since the first stop.
            if self._stop_since is None or self._now - self._last_stop_end > REBLOCK_WINDOW:
                self._stop_since = self._now
        if self.fsm.state == State.BLOCKED:
            self.stats["blocked"] += 1
            self.ports.publish_avoidance({"event": "blocked", "detail": self._reason})

    def _enter_motion(self, previous: State) -> None:
        if previous in (State.COLLISION_DETECTED, State.BLOCKED):
            self._last_stop_end = self._now

    def _enter_avoidance(self, previous: State) -> None:
        self._enter_motion(previous)
        self.sent_at = None
        if not (self.fsm.state == State.AVOIDING and previous in RESUMED_FROM):
            # A new obstacle (after BLOCKED / ESCAPING) means a new plan; after a stop that cleared
            # by itself (a person passed, a stale scan, an e-stop) the current detour pose is re-sent.
            self.detour = None
        self._attempts = 0
        self._retry_at = 0.0
        if self.fsm.state != State.DODGING and self._episode_start is None:
            self._episode_start = self._now
            self._progress_active = self._active
            if self._trick_episodes_since is None:
                self._trick_episodes_since = self._now
        if self.fsm.state == State.DODGING:
            self.stats["dodges"] += 1

    def _enter_waiting(self, previous: State) -> None:
        pose = self.perception.pose
        if pose is not None and (self.home is None or previous == State.EMERGENCY_STOP):
            # Home is where the operator released the robot (carrying it elsewhere under the e-stop
            # and releasing it there moves the show), not wherever a trick happened to end.
            self.home, self.home_yaw = (pose[0], pose[1]), pose[2]
        self._returning = False
        self._episode_start = None
        self._trick_episodes_since = None
        self.command = ""
        self.queue = []
        self.current = None
        self.sent_at = None
        self._body_pose_wanted = (0.0, self.attentive_pitch, 0.0)
        self._flush_gesture = True  # a gesture made while busy or stopped is not acted on

    def _enter_generating(self, _previous: State) -> None:
        self._body_pose_wanted = (0.0, 0.0, 0.0)
        self.trick_home = self.perception.pose
        self._trick_episodes_since = None

    def _enter_executing(self, previous: State) -> None:
        self._enter_motion(previous)
        self.sent_at = None

    # ------------------------------------------------------------------ loop
    def tick(self, now: float) -> None:
        """One step of the work states; call periodically from a single thread."""
        self.check_lidar(now)
        self.check_operator(now)
        with self.lock:
            if self._last_tick is not None and self.fsm.state in (State.BLOCKED, State.ESCAPING, State.AVOIDING):
                self._active += max(0.0, min(now - self._last_tick, 1.0))
            self._last_tick = now
            self._now = max(self._now, now)
            epoch = self.fsm.epoch
            state = self.fsm.state
            body_pose, self._body_pose_wanted = self._body_pose_wanted, None
        if body_pose is not None and state in (State.WAITING_FOR_GESTURE, State.GENERATING_PATH):
            self.ports.set_body_pose(*body_pose)
        if state == State.WAITING_FOR_GESTURE:
            self._tick_waiting(now, epoch)
        elif state == State.GENERATING_PATH:
            self._tick_generating(epoch)
        elif state == State.EXECUTING:
            self._tick_executing(now, epoch)
        elif state == State.COLLISION_DETECTED:
            self._tick_collision(now, epoch)
        elif state == State.BLOCKED:
            self._tick_blocked(now, epoch)
        elif state == State.ESCAPING:
            self._tick_escaping(now, epoch)
        elif state == State.AVOIDING:
            self._tick_avoiding(now, epoch)
        elif state == State.DODGING:
            self._tick_dodging(now, epoch)

    def _fire_if(self, epoch: int, event: Event) -> bool:
        """Fire event only if nothing changed the FSM since epoch (caller holds the lock)."""
        if self.fsm.epoch != epoch:
            return False
        self.fsm.fire(event)
        self._sync_stops()  # avoidance events move between stop and motion states
        self.ports.publish(self)
        return True

    def _tick_waiting(self, now: float, epoch: int) -> None:
        if self.home is None and self.perception.pose is not None:
            with self.lock:
                pose = self.perception.pose  # the first pose seen while waiting
                self.home, self.home_yaw = (pose[0], pose[1]), pose[2]
        if self.avoid.dodge and self.home is not None and self._may_avoid(now):
            sides = self.perception.recently_approached(now)
            if sides:
                with self.lock:
                    self._reason = "approached from the %s" % SIDE_NAMES[sides[0]]
                    self.ports.log("info", "visitor %s: dodging" % self._reason)
                    if self._fire_if(epoch, Event.DODGE):
                        return
        if now - self._last_poll < self.gesture_period:
            return
        self._last_poll = now
        command = self.ports.get_gesture()
        with self.lock:
            flush, self._flush_gesture = self._flush_gesture, False
        if flush and command:
            self.ports.log("info", "dropping gesture %r made before the robot was ready" % command)
            return
        if not command:
            return
        with self.lock:
            if self.fsm.epoch == epoch:
                self.command = command
                self.ports.log("info", "gesture command %r" % command)
                self._fire_if(epoch, Event.GESTURE)

    def _tick_generating(self, epoch: int) -> None:
        command = self.command
        ok, message, poses, names = self.ports.generate_path(command)
        with self.lock:
            if self.fsm.epoch != epoch:
                return
            if not ok or not poses:
                self.ports.log("warn", "no path for %r: %s" % (command, message or "empty path"))
                self._fire_if(epoch, Event.PATH_FAILED)
                return
            names = list(names) + [""] * (len(poses) - len(names))
            self.queue = list(zip(poses, names))
            self.current = None
            self.ports.log("info", "path for %r: %d poses" % (command, len(poses)))
            self._fire_if(epoch, Event.PATH_READY)

    def _tick_executing(self, now: float, epoch: int) -> None:
        with self.lock:
            if self.fsm.epoch != epoch:
                return
            if self.current is not None and self.sent_at is not None:
                self._check_progress(now, epoch)
                return
            if self.current is None:
                if not self.queue:
                    self._trick_done(epoch)
                    return
                self.current = self.queue.pop(0)
            pose, name = self.current
            self._sent_seq = self.status_seq
            self.seen_running = False
        accepted, message = self.ports.set_position(pose)
        with self.lock:
            if self.fsm.epoch != epoch:
                return  # preempted meanwhile: the pose is re-sent on resume
            if not accepted:
                self.ports.log("error", "position controller refused %r: %s; aborting trick" % (name, message))
                self._fire_if(epoch, Event.ABORT)
                return
            self.sent_at = now
            self.ports.publish(self)

    def _check_progress(self, now: float, epoch: int) -> None:
        """Caller holds the lock. Pose done when the position controller went running -> idle."""
        if self.seen_running and self.status == "idle":
            self.current = None
            self.sent_at = None
            if self._episode_start is not None:
                self.stats["avoided"] += 1
                self.ports.publish_avoidance({"event": "avoided", "detail": "blocked pose reached after %.1f s" % (
                    now - self._episode_start)})
                self._episode_start = None
                self.perception.forget_blocking()
            self.ports.publish(self)
            if not self.queue:
                self._trick_done(epoch)
            return
        if not self.seen_running and now - self.sent_at > self.start_timeout:
            self.ports.log("error", "position controller never reported running; aborting trick")
            self._fire_if(epoch, Event.ABORT)
        elif now - self.sent_at > self.pose_timeout:
            self.ports.log(
                "error", "pose %r not reached in %.0f s; aborting trick" % (self.current[1], self.pose_timeout)
            )
            self._fire_if(epoch, Event.ABORT)

    def _trick_done(self, epoch: int) -> None:
        """Caller holds the lock. The queue is empty: back home first if avoidance left the robot away.

        A trick whose poses were skipped (or whose way was changed by a detour) can end away from
        where it started; tricks are relative to the robot, so every later trick would start there
        and the show would wander off. With avoidance on, a robot ending more than
        ``~home_tolerance`` from home gets one more pose, home (once per trick). When home's stop
        zone holds the known obstacle (a wall the robot escaped from stands within the zone of
        home), that pose is skipped at once with its reason, as a trick pose would be, instead of
        walking into stop-and-go in front of the obstacle until it is classified again.
        """
        pose = self.perception.pose
        if (self.avoid.enabled and not self._returning and self.home is not None and pose is not None
                and math.hypot(pose[0] - self.home[0], pose[1] - self.home[1]) > self.avoid.home_tolerance):
            self._returning = True
            away = math.hypot(pose[0] - self.home[0], pose[1] - self.home[1])
            home = self.ports.make_pose(self.home[0], self.home[1], self.home_yaw)
            since = self._trick_episodes_since if self._trick_episodes_since is not None else self._now
            if self._goal_blocked(home, self.perception.obstacles(since - 5.0)):
                self.stats["gave_up"] += 1
                reason = "goal blocked: the stop zone at home would hold the obstacle"
                self.ports.log("warn", "trick done %.2f m from home, not walking back: %s" % (away, reason))
                self.ports.publish_avoidance({"event": "gave_up", "detail": reason})
            else:
                self.queue.append((home, "back home (%.2f m away after avoiding)" % away))
                self.ports.log("info", "trick done %.2f m from home: walking back" % away)
                self.ports.publish(self)
                return
        self._fire_if(epoch, Event.QUEUE_EMPTY)

    # ------------------------------------------------------------------ avoidance (issue 17)
    def _may_avoid(self, now: float) -> bool:
        """Avoidance may move the robot: zone fresh and valid, monitor alive, operator present."""
        p = self.perception
        reading, t = p.reading, p.reading_time
        return (
            reading is not None
            and reading.valid
            and t is not None
            and now - t <= 0.5
            and p.pose is not None
            and not self.lidar_lost
            and not self.fsm.operator_lost
        )

    def _blocked_pose(self) -> Any:
        """The trick pose the avoidance works towards (None when the trick has no pose left)."""
        if self.current is not None:
            return self.current[0]
        return self.queue[0][0] if self.queue else None

    def _goal_state(self, now: float, timeout: float) -> str:
        """Caller holds the lock. "none", "active", "done" or "failed" for the last goal sent."""
        if self.sent_at is None:
            return "none"
        if self.seen_running and self.status == "idle":
            self.sent_at = None
            return "done"
        if (not self.seen_running and now - self.sent_at > self.start_timeout) or now - self.sent_at > timeout:
            self.sent_at = None
            return "failed"
        return "active"

    def _give_up(self, epoch: int, reason: str) -> None:
        """Caller holds the lock. Drop the blocked pose (or head home) and go on with the trick."""
        self.stats["gave_up"] += 1
        self.ports.log("warn", "avoidance gave up (%s): %s" % (self.avoid.give_up, reason))
        self.ports.publish_avoidance({"event": "gave_up", "detail": reason, "plan": []})
        if self.avoid.give_up == "home" and self.trick_home is not None:
            x, y, yaw = self.trick_home
            self.queue = [(self.ports.make_pose(x, y, yaw), "return home (avoidance gave up)")]
        self.current = None
        self.sent_at = None
        self.detour = None
        self._drop_unreachable()
        self._episode_start = None
        self.perception.forget_blocking()
        self._fire_if(epoch, Event.GIVE_UP)

    def _goal_blocked(self, pose: Any, points: Any) -> int:
        """Known obstacle points inside the stop zone of a robot at the trick pose."""
        return zone_occupied_at(self.ports.pose_xy(pose), self.avoid.zone, points)

    def _known_obstacles(self) -> Any:
        """Caller holds the lock. The remembered obstacle points of this avoidance episode (from 5 s before it)."""
        since = self._episode_start if self._episode_start is not None else self._now
        return self.perception.obstacles(since - 5.0)

    def _drop_unreachable(self) -> None:
        """Caller holds the lock. Drop the queued poses whose zone the known obstacle occupies."""
        points = self._known_obstacles()
        while self.queue and self._goal_blocked(self.queue[0][0], points):
            _, name = self.queue.pop(0)
            self.stats["gave_up"] += 1
            reason = "goal blocked: the stop zone at %r would hold the obstacle" % name
            self.ports.log("warn", "skipping %r: %s" % (name, reason))
            self.ports.publish_avoidance({"event": "gave_up", "detail": reason})

    def _timed_out(self, now: float, epoch: int) -> bool:
        """Caller holds the lock. Give up when ~avoid_timeout passed without progress.

        Progress is an escape that cleared the zone or a detour pose reached, and only the time spent
        in BLOCKED, ESCAPING and AVOIDING counts (not stops for people, stale scans or the e-stop),
        so a slow but working avoidance is not cut short.
        """
        if self._episode_start is None:
            return False
        if self._active - self._progress_active > self.avoid.avoid_timeout:
            self._give_up(epoch, "no progress within avoid_timeout %.0f s" % self.avoid.avoid_timeout)
            return True
        return False

    def _tick_collision(self, now: float, epoch: int) -> None:
        """Stopped by the zone: classify the blocker (static -> BLOCKED; a visitor -> dodge)."""
        resume = self.fsm.resume
        if not self._may_avoid(now):
            return
        dodging = resume in (State.WAITING_FOR_GESTURE, State.DODGING) and self.avoid.dodge and self.home is not None
        if dodging and self.perception.recently_approached(now):
            with self.lock:
                if self.fsm.epoch == epoch:
                    self._reason = "approached while stopped"
                    self._fire_if(epoch, Event.DODGE)
            return
        if resume in (State.EXECUTING, State.AVOIDING, State.ESCAPING, State.WAITING_FOR_GESTURE,
                      State.GENERATING_PATH):
            # Also while idle: a robot put down (or left) facing a wall would never take a gesture.
            result, reason = self.perception.classify()
            with self.lock:
                if result == STATIC and self.fsm.epoch == epoch:
                    self._reason = reason
                    self.ports.log("info", "blocked by a static obstacle: %s" % reason)
                    self._fire_if(epoch, Event.BLOCKED_STATIC)

    def _tick_blocked(self, now: float, epoch: int) -> None:
        """BLOCKED: a moving blocker means a person (wait); else avoid after ~blocked_timeout."""
        result, reason = self.perception.classify()
        with self.lock:
            if self.fsm.epoch != epoch:
                return
            if result == MOVING:
                self.ports.log("info", "the blocker moves (%s): waiting" % reason)
                self._fire_if(epoch, Event.OBSTACLE_MOVING)
                return
            if not self.avoid.enabled or not self._may_avoid(now) or self._timed_out(now, epoch):
                return
            since = self._stop_since if self._stop_since is not None else now
            if now - since >= self.avoid.blocked_timeout:
                self.ports.log("info", "blocked for %.1f s by a static obstacle: avoiding" % (now - since))
                self._fire_if(epoch, Event.AVOID)

    def _tick_escaping(self, now: float, epoch: int) -> None:
        """Step away from the blocking side (guarded) until the zone is clear by the margin."""
        p = self.perception
        a = self.avoid
        with self.lock:
            if self.fsm.epoch != epoch or self._timed_out(now, epoch):
                return
            if not self._may_avoid(now):
                if p.reading is None or not p.reading.valid or self.lidar_lost:
                    self.ports.log("warn", "zone stale or invalid during the escape: stop")
                    self._fire_if(epoch, Event.ZONE_STALE)
                return
            timeout = a.escape_max / a.escape_speed * 1.5 + 3.0  # held by the guard this long: try another way
            goal = self._goal_state(now, timeout)
            if goal == "active":
                return
            if goal == "failed":
                self._attempts += 1
            reading, pose = p.reading, p.pose
            if clear_by_margin(reading, a.zone, 1, a.escape_margin):  # not one point within the margin
                self.stats["escapes"] += 1
                self._progress_active = self._active
                self.ports.log("info", "zone clear by %.2f m: planning the detour" % a.escape_margin)
                self.ports.publish_avoidance({"event": "escaped", "detail": "zone clear by %.2f m" % a.escape_margin})
                self._fire_if(epoch, Event.ESCAPED)
                return
            if self._attempts >= 3:
                self._give_up(epoch, "wedged: no escape after %d attempts" % self._attempts)
                return
            if now < self._retry_at:
                return
            arena = p.ensure_arena(self.home or (pose[0], pose[1]))
            # Like the position controller's guard: one critical point closes a side.
            esc, why = plan_escape(reading, a.zone, pose, 1, a.escape_margin, a.escape_max, arena=arena)
            if esc is None:
                self._attempts += 1
                self._retry_at = now + 1.0
                self.ports.log("warn", "no escape now: %s" % why)
                return
            self._sent_seq = self.status_seq
            self.seen_running = False
        accepted, message = self.ports.set_guarded_position(esc.target[0], esc.target[1], a.escape_speed)
        with self.lock:
            if self.fsm.epoch != epoch:
                return
            if not accepted:
                self._attempts += 1
                self._retry_at = now + 1.0
                self.ports.log("warn", "escape refused by the position controller: %s" % message)
                return
            self.sent_at = now
            self.ports.log("info", "escaping: %r" % esc)
            self.ports.publish_avoidance({"event": "escape", "detail": esc.reason, "target": esc.target})

    def _tick_avoiding(self, now: float, epoch: int) -> None:
        """Plan the detour to the blocked pose and drive it pose by pose (normal collision rules)."""
        p = self.perception
        a = self.avoid
        with self.lock:
            if self.fsm.epoch != epoch or self._timed_out(now, epoch):
                return
            if self.detour is None:
                goal_pose = self._blocked_pose()
                if goal_pose is None or p.pose is None:
                    self.detour = []
                    self._fire_if(epoch, Event.DETOUR_DONE)
                    return
                start = p.pose
                goal = self.ports.pose_xy(goal_pose)[:2]
                arena = p.ensure_arena(self.home or (start[0], start[1]))
                since = self._episode_start if self._episode_start is not None else now
                inside = self._goal_blocked(goal_pose, p.obstacles(since - 5.0))
                if inside:
                    self._give_up(epoch, "goal blocked: the stop zone at the goal would hold %d obstacle points"
                                  % inside)
                    return
        if self.detour is None:
            plan = self.planner.plan((start[0], start[1]), goal, p.grid, p.obstacles(since - 5.0), arena)
            with self.lock:
                if self.fsm.epoch != epoch:
                    return
                if not plan.ok:
                    self._give_up(epoch, plan.reason)
                    return
                limit = a.max_detour_factor * max(plan.direct, 0.5)
                if plan.length > limit:
                    self._give_up(epoch, "detour %.2f m > %.1f x the direct %.2f m" % (
                        plan.length, a.max_detour_factor, plan.direct))
                    return
                poses = []
                points = [(start[0], start[1])] + list(plan.waypoints)
                for i, (x, y) in enumerate(points[1:-1], start=1):
                    nx, ny = points[i + 1]
                    poses.append((self.ports.make_pose(x, y, math.atan2(ny - y, nx - x)), "detour %d" % i))
                self.detour = poses
                self.ports.log("info", "detour to (%.2f, %.2f): %r" % (goal[0], goal[1], plan))
                self.ports.publish_avoidance({"event": "plan", "detail": plan.reason, "plan": points})
        with self.lock:
            if self.fsm.epoch != epoch:
                return
            goal = self._goal_state(now, self.pose_timeout)
            if goal == "active":
                return
            if goal == "failed":
                self._give_up(epoch, "detour pose not reached")
                return
            if goal == "done" and self.detour:
                self.detour.pop(0)
                self._progress_active = self._active
            if not self.detour:
                self.ports.log("info", "detour done: continuing the trick")
                self._fire_if(epoch, Event.DETOUR_DONE)
                return
            pose, name = self.detour[0]
            self._sent_seq = self.status_seq
            self.seen_running = False
        accepted, message = self.ports.set_position(pose)
        with self.lock:
            if self.fsm.epoch != epoch:
                return
            if not accepted:
                # A refusal can race with a stop being released; try again, then give up.
                self._attempts += 1
                if self._attempts >= 4:
                    self._give_up(epoch, "position controller refused %s: %s" % (name, message))
                return
            self.sent_at = now
            self.ports.publish(self)

    def _tick_dodging(self, now: float, epoch: int) -> None:
        """Step away from an approaching visitor (guarded), return home when it is quiet."""
        p = self.perception
        a = self.avoid
        with self.lock:
            if self.fsm.epoch != epoch:
                return
            if not self._may_avoid(now):
                if p.reading is None or not p.reading.valid or self.lidar_lost:
                    self._fire_if(epoch, Event.ZONE_STALE)
                return
            goal = self._goal_state(now, a.dodge_max / a.dodge_speed * 3.0 + 5.0)
            if goal == "active":
                return
            pose, home = p.pose, self.home or (p.pose[0], p.pose[1])
            arena = p.ensure_arena(home)
            sides = p.recently_approached(now)
            kind = ""
            if sides:
                target, why = dodge_target(home, pose, sides[0], a.dodge_step, a.dodge_max, arena)
                kind = "dodge"
            else:
                away = math.hypot(pose[0] - home[0], pose[1] - home[1])
                if p.quiet_for(now) < a.dodge_return_after or not self._home_side_clear(pose, home):
                    return
                if away <= 0.05:
                    self.ports.log("info", "back home after the dodge")
                    self.ports.publish_avoidance({"event": "dodged", "detail": "back home"})
                    self._fire_if(epoch, Event.DODGE_DONE)
                    return
                target, why, kind = home, "back home (%.2f m)" % away, "home"
            if target is None:
                return
            self._sent_seq = self.status_seq
            self.seen_running = False
        accepted, message = self.ports.set_guarded_position(target[0], target[1], a.dodge_speed)
        with self.lock:
            if self.fsm.epoch != epoch:
                return
            if accepted:
                self.sent_at = now
                self.ports.log("info", "%s: %s" % (kind, why))
                self.ports.publish_avoidance({"event": kind, "detail": why, "target": target})
            else:
                self.ports.log("warn", "dodge refused by the position controller: %s" % message)

    def _home_side_clear(self, pose: Tuple[float, float, float], home: Tuple[float, float]) -> bool:
        """Nothing in the slowdown band on the sides the way home heads to."""
        reading = self.perception.reading
        if reading is None:
            return False
        dx, dy = home[0] - pose[0], home[1] - pose[1]
        c, s = math.cos(pose[2]), math.sin(pose[2])
        bx, by = c * dx + s * dy, -s * dx + c * dy
        band = [z + w for z, w in zip(self.avoid.zone, self.avoid.slowdown)]
        for side, (ux, uy) in TOWARDS.items():
            if ux * bx + uy * by > 0.02 and reading.min_distance[side] < band[side]:
                return False
        return True
