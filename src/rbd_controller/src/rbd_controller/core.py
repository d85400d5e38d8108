"""Main controller behaviour around the FSM, with the ROS side injected as ports. ROS-free.

The node calls the stop handlers from its service callbacks and tick() from one loop
thread. Slow calls (gesture poll, path generation, set_position, body pose) run in tick()
without the lock; their results are dropped if the FSM changed meanwhile (epoch check).
"""

import threading
from typing import Any, Callable, List, Sequence, Tuple

from rbd_controller.fsm import Event, Fsm, State
from rbd_controller.watchdog import POLICIES, OperatorWatchdog

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
        self.remote_held = False  # the A1 remote's e-stop combination is held (rbd_a1_driver reports it)
        self.fsm = Fsm(
            on_enter={
                State.EMERGENCY_STOP: self._enter_stop,
                State.COLLISION_DETECTED: self._enter_stop,
                State.OPERATOR_LOST: self._enter_stop,
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

    def on_lidar_state(self, now: float, collision: bool) -> None:
        """A CollisionState from rbd_lidar arrived at ``now`` [s] (its ``collision`` flag)."""
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
        collision = self.fsm.state in (State.COLLISION_DETECTED, State.OPERATOR_LOST)
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
    def _enter_stop(self, _previous: State) -> None:
        self.sent_at = None  # the interrupted pose is re-sent on resume

    def _enter_waiting(self, previous: State) -> None:
        self.command = ""
        self.queue = []
        self.current = None
        self.sent_at = None
        self._body_pose_wanted = (0.0, self.attentive_pitch, 0.0)
        self._flush_gesture = True  # a gesture made while busy or stopped is not acted on

    def _enter_generating(self, _previous: State) -> None:
        self._body_pose_wanted = (0.0, 0.0, 0.0)

    def _enter_executing(self, _previous: State) -> None:
        self.sent_at = None

    # ------------------------------------------------------------------ loop
    def tick(self, now: float) -> None:
        """One step of the work states; call periodically from a single thread."""
        self.check_lidar(now)
        self.check_operator(now)
        with self.lock:
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

    def _fire_if(self, epoch: int, event: Event) -> bool:
        """Fire event only if nothing changed the FSM since epoch (caller holds the lock)."""
        if self.fsm.epoch != epoch:
            return False
        self.fsm.fire(event)
        self.ports.publish(self)
        return True

    def _tick_waiting(self, now: float, epoch: int) -> None:
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
                    self._fire_if(epoch, Event.QUEUE_EMPTY)
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
            self.ports.publish(self)
            if not self.queue:
                self._fire_if(epoch, Event.QUEUE_EMPTY)
            return
        if not self.seen_running and now - self.sent_at > self.start_timeout:
            self.ports.log("error", "position controller never reported running; aborting trick")
            self._fire_if(epoch, Event.ABORT)
        elif now - self.sent_at > self.pose_timeout:
            self.ports.log(
                "error", "pose %r not reached in %.0f s; aborting trick" % (self.current[1], self.pose_timeout)
            )
            self._fire_if(epoch, Event.ABORT)
