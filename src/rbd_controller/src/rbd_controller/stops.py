"""The stops behaviour: e-stop, collision, operator loss and BLOCKED, and when a stop turns into avoidance. ROS-free.

While COLLISION_DETECTED the blocker is classified (static -> BLOCKED; an approaching visitor of
an idle robot -> DODGING); BLOCKED waits for a moving blocker (a person) and starts the
avoidance after ~blocked_timeout. The stop states themselves hold the robot: the context tells
the driver gate and the position controller (:meth:`Context.sync_stops`).
"""

from typing import Any

from rbd_controller.blocking import MOVING, STATIC
from rbd_controller.context import Behaviour, Context
from rbd_controller.fsm import Event, State
from rbd_controller.watchdog import POLICIES, OperatorWatchdog

#: Stopped again within this many seconds of a resume: the same blockage (stop-and-go creeping) [s].
REBLOCK_WINDOW = 3.0
#: Entering these from COLLISION_DETECTED or BLOCKED ends a stop (for REBLOCK_WINDOW).
MOTION_STATES = (State.EXECUTING, State.ESCAPING, State.AVOIDING, State.DODGING)


class Stops(Behaviour):
    """EMERGENCY_STOP, COLLISION_DETECTED, OPERATOR_LOST and BLOCKED, and the inputs that stop.

    The inputs (e-stop service, the A1 remote's e-stop, collision service, operator heartbeat,
    collision monitor state and their watchdogs) are called from the node's callbacks and from
    the controller's tick; each fires its event, tells the stops and publishes.

    Args:
        ctx: the shared context.
        avoidance: the avoidance behaviour (its no-progress timeout also runs while BLOCKED).
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

    states = (State.EMERGENCY_STOP, State.COLLISION_DETECTED, State.OPERATOR_LOST, State.BLOCKED)

    def __init__(self, ctx: Context, avoidance: Any, operator_timeout: float = 0.0, operator_policy: str = "stop",
                 lidar_timeout: float = 0.0) -> None:
        super().__init__(ctx)
        if operator_policy not in POLICIES:
            raise ValueError("operator_policy must be one of %s, got %r" % (POLICIES, operator_policy))
        self.operator = OperatorWatchdog(operator_timeout)
        self.operator_policy = operator_policy
        self.lidar = OperatorWatchdog(lidar_timeout)
        self.remote_held = False  # the A1 remote's e-stop combination is held (rbd_a1_driver reports it)
        self.avoidance = avoidance
        self.stop_since = None  # type: Optional[float]  # first stop of the current blockage
        self.last_stop_end = -1e9

    def on_enter(self, state: State, previous: State) -> None:
        """A stop: forget the goal (re-sent on resume); track the blockage; count BLOCKED."""
        ctx = self.ctx
        ctx.goal.sent_at = None  # the interrupted pose is re-sent on resume
        if state == State.COLLISION_DETECTED and previous not in (State.BLOCKED, State.EMERGENCY_STOP):
            # A robot that creeps stop-and-go at the same obstacle (the zone shrinks when it stops)
            # is still blocked since the first stop.
            if self.stop_since is None or ctx.now - self.last_stop_end > REBLOCK_WINDOW:
                self.stop_since = ctx.now
        if state == State.BLOCKED:
            ctx.stats["blocked"] += 1
            ctx.ports.publish_avoidance({"event": "blocked", "detail": ctx.reason})

    def on_transition(self, previous: State, state: State) -> None:
        """Any transition (lock held): a motion after a collision stop ends that stop."""
        if state in MOTION_STATES and previous in (State.COLLISION_DETECTED, State.BLOCKED):
            self.last_stop_end = self.ctx.now

    def tick(self, state: State, now: float, epoch: int) -> None:
        """Classify the blocker while COLLISION_DETECTED or BLOCKED."""
        if state == State.COLLISION_DETECTED:
            self._tick_collision(now, epoch)
        elif state == State.BLOCKED:
            self._tick_blocked(now, epoch)

    def _tick_collision(self, now: float, epoch: int) -> None:
        """Stopped by the zone: classify the blocker (static -> BLOCKED; a visitor -> dodge)."""
        ctx = self.ctx
        resume = ctx.fsm.resume
        if not ctx.may_avoid(now):
            return
        dodging = resume in (State.WAITING_FOR_GESTURE, State.DODGING) and ctx.avoid.dodge and ctx.home is not None
        if dodging and ctx.perception.recently_approached(now):
            with ctx.lock:
                if ctx.fsm.epoch == epoch:
                    ctx.reason = "approached while stopped"
                    ctx.fire_if(epoch, Event.DODGE)
            return
        if resume in (State.EXECUTING, State.AVOIDING, State.ESCAPING, State.WAITING_FOR_GESTURE,
                      State.GENERATING_PATH):
            # Also while idle: a robot put down (or left) facing a wall would never take a gesture.
            result, reason = ctx.perception.classify()
            with ctx.lock:
                if result == STATIC and ctx.fsm.epoch == epoch:
                    ctx.reason = reason
                    ctx.ports.log("info", "blocked by a static obstacle: %s" % reason)
                    ctx.fire_if(epoch, Event.BLOCKED_STATIC)

    def _tick_blocked(self, now: float, epoch: int) -> None:
        """BLOCKED: a moving blocker means a person (wait); else avoid after ~blocked_timeout."""
        ctx = self.ctx
        result, reason = ctx.perception.classify()
        with ctx.lock:
            if ctx.fsm.epoch != epoch:
                return
            if result == MOVING:
                ctx.ports.log("info", "the blocker moves (%s): waiting" % reason)
                ctx.fire_if(epoch, Event.OBSTACLE_MOVING)
                return
            if not ctx.avoid.enabled or not ctx.may_avoid(now) or self.avoidance.timed_out(epoch):
                return
            since = self.stop_since if self.stop_since is not None else now
            if now - since >= ctx.avoid.blocked_timeout:
                ctx.ports.log("info", "blocked for %.1f s by a static obstacle: avoiding" % (now - since))
                ctx.fire_if(epoch, Event.AVOID)
            elif result == STATIC and ctx.perception.known_match:
                # The obstacle a detour is going around: no new wait for it to go away (issue 27).
                ctx.ports.log("info", "stopped again at the static obstacle being avoided: avoiding")
                ctx.fire_if(epoch, Event.AVOID)
            elif result == STATIC and ctx.perception.low_match:
                # A bag put down does not walk away: ~blocked_timeout is the time a person gets (issue 27).
                ctx.ports.log("info", "blocked by a low static obstacle (%s): avoiding" % reason)
                ctx.fire_if(epoch, Event.AVOID)

    # ------------------------------------------------------------------ stop inputs (node callbacks)
    def set_emergency(self, engaged: bool) -> str:
        """Engage/release the e-stop (service, CLI, GUI); returns a message.

        A release while the A1 remote's e-stop combination is held is refused (see
        :meth:`release_refusal`); the state does not change.
        """
        with self.ctx.lock:
            if not engaged and self.remote_held:
                return self.release_refusal()
            before = self.ctx.fsm.state
            if not engaged and self.operator.lost(self.ctx.now):
                self.operator.disarm()  # the release acknowledges the lost link
            self.ctx.fsm.fire(Event.ESTOP if engaged else Event.ESTOP_RELEASE)
            self.ctx.sync_stops()
            self.ctx.publish()
            return "%s -> %s" % (before.name, self.ctx.fsm.state.name)

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
        with self.ctx.lock:
            self.remote_held = bool(held)
            if not held:
                return "remote e-stop combination let go"
            return self.set_emergency(True)

    def set_collision(self, detected: bool) -> str:
        """Collision reported (True) or cleared (False) by rbd_lidar; returns a message."""
        with self.ctx.lock:
            before = self.ctx.fsm.state
            self.ctx.fsm.fire(Event.COLLISION if detected else Event.COLLISION_CLEAR)
            self.ctx.sync_stops()
            self.ctx.publish()
            return "%s -> %s" % (before.name, self.ctx.fsm.state.name)

    def on_heartbeat(self, now: float) -> None:
        """An operator heartbeat arrived at ``now`` [s]."""
        with self.ctx.lock:
            self.ctx.now = max(self.ctx.now, now)
            self.operator.beat(now)
            if self.ctx.fsm.operator_lost:
                before = self.ctx.fsm.state
                self.ctx.fsm.fire(Event.OPERATOR_BACK)
                self.ctx.sync_stops()
                self.ctx.publish()
                self.ctx.ports.log("info", "operator link back (%s -> %s)" % (before.name, self.ctx.fsm.state.name))

    def on_lidar_state(self, now: float, collision: bool, reading: Any = None) -> None:
        """A CollisionState from rbd_lidar arrived at ``now`` [s].

        Args:
            now: arrival time [s].
            collision: its ``collision`` flag.
            reading: the same as an :class:`rbd_controller.escape.ZoneReading` (per-side points and
                distances) for the avoidance; None when not available.
        """
        if reading is not None:
            self.ctx.perception.on_zone(now, reading)
        with self.ctx.lock:
            self.lidar.beat(now)
            if not self.ctx.lidar_lost:
                return
            self.ctx.lidar_lost = False
            self.ctx.ports.log("info", "collision monitor back (collision %s)" % collision)
            self.ctx.fsm.fire(Event.COLLISION if collision else Event.COLLISION_CLEAR)
            self.ctx.sync_stops()
            self.ctx.publish()

    def check_lidar(self, now: float) -> None:
        """No state from the collision monitor for lidar_timeout => collision; called from tick()."""
        with self.ctx.lock:
            if self.ctx.lidar_lost or not self.lidar.lost(now):
                return
            self.ctx.lidar_lost = True
            self.ctx.ports.log("error", "no /rbd_lidar/state for > %.2f s: collision (monitor lost)"
                               % self.lidar.timeout)
            self.ctx.fsm.fire(Event.COLLISION)
            self.ctx.sync_stops()
            self.ctx.publish()

    def check_operator(self, now: float) -> None:
        """Fire OPERATOR_LOST when the heartbeat is gone (per policy); called from tick()."""
        with self.ctx.lock:
            self.ctx.now = max(self.ctx.now, now)
            if self.ctx.fsm.operator_lost or not self.operator.lost(now):
                return
            if self.operator_policy == "finish" and self.ctx.fsm.state != State.WAITING_FOR_GESTURE:
                return  # let the current trick (or stop) run its course
            before = self.ctx.fsm.state
            self.ctx.fsm.fire(Event.OPERATOR_LOST)
            self.ctx.sync_stops()
            self.ctx.publish()
            self.ctx.ports.log(
                "warn",
                "operator heartbeat lost for > %.1f s (policy %s): %s -> %s"
                % (self.operator.timeout, self.operator_policy, before.name, self.ctx.fsm.state.name),
            )
