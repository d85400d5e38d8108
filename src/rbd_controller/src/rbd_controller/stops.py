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

#: Stopped again within this many seconds of a resume: the same blockage (stop-and-go creeping) [s].
REBLOCK_WINDOW = 3.0
#: Entering these from COLLISION_DETECTED or BLOCKED ends a stop (for REBLOCK_WINDOW).
MOTION_STATES = (State.EXECUTING, State.ESCAPING, State.AVOIDING, State.DODGING)


class Stops(Behaviour):
    """EMERGENCY_STOP, COLLISION_DETECTED, OPERATOR_LOST and BLOCKED.

    Args:
        ctx: the shared context.
        avoidance: the avoidance behaviour (its no-progress timeout also runs while BLOCKED).
    """

    states = (State.EMERGENCY_STOP, State.COLLISION_DETECTED, State.OPERATOR_LOST, State.BLOCKED)

    def __init__(self, ctx: Context, avoidance: Any) -> None:
        super().__init__(ctx)
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
