"""Main controller: routes the FSM's states to behaviours, takes the stop inputs. ROS-free.

The node calls the stop inputs from its service and subscriber callbacks and tick() from one loop
thread. Each FSM state belongs to one behaviour, which owns its own state, sets it up in
``on_enter`` and runs it in ``tick``: :class:`~rbd_controller.tricks.Tricks` (waiting, generating,
executing), :class:`~rbd_controller.stops.Stops` (e-stop, collision, operator lost, blocked),
:class:`~rbd_controller.avoidance.Avoidance` (escaping, avoiding; issue 17) and
:class:`~rbd_controller.dodging.Dodging`. What they share is in
:class:`~rbd_controller.context.Context`; this file only routes.
"""

from typing import Any, List, Tuple

from rbd_controller.avoidance import Avoidance
from rbd_controller.context import Context, Ports
from rbd_controller.dodging import Dodging
from rbd_controller.fsm import Event, Fsm, State
from rbd_controller.perception import AvoidParams
from rbd_controller.stops import Stops
from rbd_controller.tricks import Tricks
from rbd_controller.watchdog import POLICIES, OperatorWatchdog

__all__ = ["MainController", "Ports"]
#: States whose time counts on the avoidance episode's no-progress clock.
EPISODE_STATES = (State.BLOCKED, State.ESCAPING, State.AVOIDING)


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
        self.remote_held = False  # the A1 remote's e-stop combination is held (rbd_a1_driver reports it)
        avoid = avoid if avoid is not None else AvoidParams(enabled=False, dodge=False)
        self.ctx = ctx = Context(ports, avoid, start_timeout)
        self.ports, self.avoid, self.perception, self.lock = ctx.ports, ctx.avoid, ctx.perception, ctx.lock
        self.tricks = Tricks(ctx, attentive_pitch, gesture_period, pose_timeout)
        self.avoidance = Avoidance(ctx, self.tricks)
        self.stops = Stops(ctx, self.avoidance)
        self.dodging = Dodging(ctx)
        self.routes = {}  # type: Dict[State, Behaviour]
        for behaviour in (self.tricks, self.stops, self.avoidance, self.dodging):
            self.routes.update((state, behaviour) for state in behaviour.states)
        self._last_tick = None  # type: Optional[float]
        ctx.controller = self
        ctx.fsm = self.fsm = Fsm(on_enter={state: self._on_enter for state in State})

    def _on_enter(self, previous: State) -> None:
        state = self.fsm.state
        self.stops.on_transition(previous, state)
        self.routes[state].on_enter(state, previous)

    # ------------------------------------------------------------------ properties
    @property
    def state(self) -> State:
        """Current FSM state."""
        return self.fsm.state

    def remaining(self) -> List[Tuple[Any, str]]:
        """The pose being executed (first) and the ones still queued."""
        with self.lock:
            return self.tricks.remaining()

    command = property(lambda self: self.tricks.command, doc="The current trick's command.")
    queue = property(lambda self: self.tricks.queue, doc="The trick's poses still queued.")
    home = property(lambda self: self.ctx.home, doc="Where the show is (x, y) [m] (None before the first pose).")
    home_yaw = property(lambda self: self.ctx.home_yaw, doc="The robot's yaw at home [rad].")
    stats = property(lambda self: self.ctx.stats, doc="Avoidance counters (avoided, gave_up, escapes, ...).")

    @property
    def pose_timeout(self) -> float:
        """Longest time one pose may take [s]."""
        return self.tricks.pose_timeout

    @pose_timeout.setter
    def pose_timeout(self, value: float) -> None:
        self.tricks.pose_timeout = value

    # ------------------------------------------------------------------ start
    def start(self) -> None:
        """Publish the power-up state (EMERGENCY_STOP) and stop the position controller."""
        with self.lock:
            self.ctx.sync_stops()
            self.ctx.publish()

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
            if not engaged and self.operator.lost(self.ctx.now):
                self.operator.disarm()  # the release acknowledges the lost link
            self.fsm.fire(Event.ESTOP if engaged else Event.ESTOP_RELEASE)
            self.ctx.sync_stops()
            self.ctx.publish()
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
            self.ctx.sync_stops()
            self.ctx.publish()
            return "%s -> %s" % (before.name, self.fsm.state.name)

    def on_heartbeat(self, now: float) -> None:
        """An operator heartbeat arrived at ``now`` [s]."""
        with self.lock:
            self.ctx.now = max(self.ctx.now, now)
            self.operator.beat(now)
            if self.fsm.operator_lost:
                before = self.fsm.state
                self.fsm.fire(Event.OPERATOR_BACK)
                self.ctx.sync_stops()
                self.ctx.publish()
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
            if not self.ctx.lidar_lost:
                return
            self.ctx.lidar_lost = False
            self.ports.log("info", "collision monitor back (collision %s)" % collision)
            self.fsm.fire(Event.COLLISION if collision else Event.COLLISION_CLEAR)
            self.ctx.sync_stops()
            self.ctx.publish()

    def check_lidar(self, now: float) -> None:
        """No state from the collision monitor for lidar_timeout => collision; called from tick()."""
        with self.lock:
            if self.ctx.lidar_lost or not self.lidar.lost(now):
                return
            self.ctx.lidar_lost = True
            self.ports.log("error", "no /rbd_lidar/state for > %.2f s: collision (monitor lost)" % self.lidar.timeout)
            self.fsm.fire(Event.COLLISION)
            self.ctx.sync_stops()
            self.ctx.publish()

    def check_operator(self, now: float) -> None:
        """Fire OPERATOR_LOST when the heartbeat is gone (per policy); called from tick()."""
        with self.lock:
            self.ctx.now = max(self.ctx.now, now)
            if self.fsm.operator_lost or not self.operator.lost(now):
                return
            if self.operator_policy == "finish" and self.fsm.state != State.WAITING_FOR_GESTURE:
                return  # let the current trick (or stop) run its course
            before = self.fsm.state
            self.fsm.fire(Event.OPERATOR_LOST)
            self.ctx.sync_stops()
            self.ctx.publish()
            self.ports.log(
                "warn",
                "operator heartbeat lost for > %.1f s (policy %s): %s -> %s"
                % (self.operator.timeout, self.operator_policy, before.name, self.fsm.state.name),
            )

    def on_pos_status(self, status: str) -> None:
        """Status message from the position controller (idle/running/emergency/collision)."""
        with self.lock:
            self.ctx.goal.on_status(status)

    # ------------------------------------------------------------------ loop
    def tick(self, now: float) -> None:
        """One step of the current state's behaviour; call periodically from a single thread."""
        self.check_lidar(now)
        self.check_operator(now)
        with self.lock:
            if self._last_tick is not None and self.fsm.state in EPISODE_STATES:
                self.ctx.episode.active += max(0.0, min(now - self._last_tick, 1.0))
            self._last_tick = now
            self.ctx.now = max(self.ctx.now, now)
            epoch = self.fsm.epoch
            state = self.fsm.state
            self.tricks.latch_body_pose()
        self.routes[state].tick(state, now, epoch)
