"""Main controller: routes the FSM's states to behaviours and stops the robot on a fault. ROS-free.

The node calls the stop inputs (the stops behaviour's, bound here) from its service and subscriber
callbacks and tick() from one loop thread. Each FSM state belongs to one behaviour, which owns
its own state, sets it up in ``on_enter`` and runs it in ``tick``:
:class:`~rbd_controller.tricks.Tricks` (waiting, generating, executing),
:class:`~rbd_controller.stops.Stops` (e-stop, collision, operator lost, blocked),
:class:`~rbd_controller.avoidance.Avoidance` (escaping, avoiding; issue 17) and
:class:`~rbd_controller.dodging.Dodging`. What they share is in
:class:`~rbd_controller.context.Context`; this file only routes.
"""

import traceback
from typing import Any, List, Tuple

from rbd_controller.avoidance import Avoidance
from rbd_controller.context import Context, Ports
from rbd_controller.dodging import Dodging
from rbd_controller.fsm import Event, Fsm, State
from rbd_controller.perception import AvoidParams
from rbd_controller.stops import Stops
from rbd_controller.tricks import Tricks

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
        avoid = avoid if avoid is not None else AvoidParams(enabled=False, dodge=False)
        self.ctx = ctx = Context(ports, avoid, start_timeout)
        self.ports, self.avoid, self.perception, self.lock = ctx.ports, ctx.avoid, ctx.perception, ctx.lock
        self.tricks = Tricks(ctx, attentive_pitch, gesture_period, pose_timeout)
        self.avoidance = Avoidance(ctx, self.tricks)
        self.stops = stops = Stops(ctx, self.avoidance, operator_timeout, operator_policy, lidar_timeout)
        self.dodging = Dodging(ctx)
        self.routes = {}  # type: Dict[State, Behaviour]
        for behaviour in (self.tricks, self.stops, self.avoidance, self.dodging):
            self.routes.update((state, behaviour) for state in behaviour.states)
        # The stop inputs (node callbacks) are the stops behaviour's.
        self.set_emergency, self.release_refusal, self.set_remote_estop = (
            stops.set_emergency, stops.release_refusal, stops.set_remote_estop)
        self.set_collision, self.on_heartbeat, self.on_lidar_state = (
            stops.set_collision, stops.on_heartbeat, stops.on_lidar_state)
        self.check_lidar, self.check_operator = stops.check_lidar, stops.check_operator
        self.on_localized = self.tricks.on_localized  # /rbd_localization/localized: tricks refused while false
        self.faults = 0  # behaviours that raised (each engaged the e-stop)
        self._fault = None  # type: Optional[Tuple[str, str]]  # raised in an on_enter hook, not handled yet
        self._last_tick = None  # type: Optional[float]
        ctx.controller = self
        ctx.fsm = self.fsm = Fsm(on_enter={state: self._on_enter for state in State})

    def _on_enter(self, previous: State) -> None:
        state = self.fsm.state
        try:
            self.stops.on_transition(previous, state)
            self.routes[state].on_enter(state, previous)
        except Exception as exc:  # noqa: BLE001 -- handled by the next tick: e-stop, not a dead node
            self._fault = ("entering %s" % state.name, "%s: %s" % (type(exc).__name__, exc))

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
    remote_held = property(lambda self: self.stops.remote_held, doc="The A1 remote holds its e-stop combination.")

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
        try:
            self.routes[state].tick(state, now, epoch)
        except Exception as exc:  # noqa: BLE001 -- a fault must stop the robot, not kill the node
            self._fault = ("%s tick" % state.name, "%s: %s\n%s" % (type(exc).__name__, exc, traceback.format_exc()))
        if self._fault is not None:
            self._stop_on_fault()

    def _stop_on_fault(self) -> None:
        """A behaviour raised: engage the e-stop (no motion until an operator releases it, then a new trick).

        The behaviour that raised may have left its state half-updated, so it is not resumed: the
        release goes to WAITING_FOR_GESTURE. The driver gate and the position controller are told
        first; publishing comes last.
        """
        with self.lock:
            where, what = self._fault
            self._fault = None
            self.faults += 1
            self.fsm.fire(Event.ESTOP)
            self.fsm.resume = State.WAITING_FOR_GESTURE
            self.ctx.sync_stops()
            self.ports.log("error", "fault in %s, e-stop engaged (a release waits for a new gesture): %s"
                           % (where, what))
            self.ctx.publish()
