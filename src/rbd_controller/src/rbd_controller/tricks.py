"""The tricks behaviour: wait for a gesture, generate its path, execute it pose by pose. ROS-free.

Slow calls (gesture poll, path generation, set_position, body pose) run in tick() without the
lock; their results are dropped if the FSM changed meanwhile (epoch check). While the map
correction says it is not localized in the loaded map, gestures are refused and the idle robot
does not dodge (:meth:`Tricks.refusal`).
"""

import math
from typing import Any, List, Tuple

from rbd_controller.context import Behaviour, Context
from rbd_controller.escape import SIDE_NAMES
from rbd_controller.fsm import Event, State


class Tricks(Behaviour):
    """WAITING_FOR_GESTURE, GENERATING_PATH and EXECUTING: the trick's command and pose queue.

    Args:
        ctx: the shared context.
        attentive_pitch: body pitch while waiting for a gesture [rad] (< 0: nose up).
        gesture_period: minimum time between two gesture polls [s].
        pose_timeout: longest time one pose may take before the trick is aborted [s].
    """

    states = (State.WAITING_FOR_GESTURE, State.GENERATING_PATH, State.EXECUTING)

    def __init__(self, ctx: Context, attentive_pitch: float, gesture_period: float, pose_timeout: float) -> None:
        super().__init__(ctx)
        self.attentive_pitch = attentive_pitch
        self.gesture_period = gesture_period
        self.pose_timeout = pose_timeout
        self.command = ""
        self.queue = []  # type: List[Tuple[Any, str]]
        self.current = None  # type: Optional[Tuple[Any, str]]
        self.trick_home = None  # type: Optional[Tuple[float, float, float]]  # where this trick started
        self._returning = False  # the "back home" pose of this trick is queued (tried once per trick)
        self._last_poll = -1e9
        self._body_pose_wanted = None  # type: Optional[Tuple[float, float, float]]
        self._body_pose_due = None  # type: Optional[Tuple[float, float, float]]
        self._flush_gesture = False

    def remaining(self) -> List[Tuple[Any, str]]:
        """The pose being executed (first) and the ones still queued."""
        return ([self.current] if self.current is not None else []) + list(self.queue)

    # ------------------------------------------------------------------ localization gate
    def refusal(self) -> str:
        """Why a gesture would be refused now ("" if it would not): not localized in the loaded map."""
        if self.ctx.localized is False:
            return "not localized in the map (/rbd_localization/localized is false); tricks wait until it is true"
        return ""

    def on_localized(self, localized: bool) -> None:
        """The latest /rbd_localization/localized. False: gestures are refused, no dodge; true: taken again.

        Turning true while waiting for a gesture takes home again from the next pose: a home taken
        before the start search converged may be off by the start's distance from the map's home.
        """
        ctx = self.ctx
        with ctx.lock:
            was, ctx.localized = ctx.localized, bool(localized)
            if was is ctx.localized:
                return
            if not ctx.localized:
                ctx.ports.log("warn", "not localized in the map: gestures are refused until it is")
            elif was is False:
                ctx.ports.log("info", "localized in the map: taking gestures again")
                if ctx.fsm.state == State.WAITING_FOR_GESTURE:
                    ctx.home = ctx.home_yaw = None

    # ------------------------------------------------------------------ on_enter
    def on_enter(self, state: State, previous: State) -> None:
        """Set up the trick state entered."""
        ctx = self.ctx
        if state == State.WAITING_FOR_GESTURE:
            pose = ctx.perception.pose
            if pose is not None and (ctx.home is None or previous == State.EMERGENCY_STOP):
                # Home is where the operator released the robot (carrying it elsewhere under the e-stop
                # and releasing it there moves the show), not wherever a trick happened to end.
                ctx.home, ctx.home_yaw = (pose[0], pose[1]), pose[2]
            self._returning = False
            ctx.perception.forget_static()
            ctx.episode.start = None
            ctx.episode.trick_since = None
            self.command = ""
            self.queue = []
            self.current = None
            ctx.goal.sent_at = None
            self._body_pose_wanted = (0.0, self.attentive_pitch, 0.0)
            self._flush_gesture = True  # a gesture made while busy or stopped is not acted on
        elif state == State.GENERATING_PATH:
            self._body_pose_wanted = (0.0, 0.0, 0.0)
            self.trick_home = ctx.perception.pose
            ctx.episode.trick_since = None
        else:
            ctx.goal.sent_at = None

    def latch_body_pose(self) -> None:
        """Caller holds the lock; every tick. The body pose wanted since the last tick is due now (or never)."""
        self._body_pose_due, self._body_pose_wanted = self._body_pose_wanted, None

    # ------------------------------------------------------------------ tick
    def tick(self, state: State, now: float, epoch: int) -> None:
        """One step of the trick state."""
        body_pose, self._body_pose_due = self._body_pose_due, None
        if body_pose is not None and state in (State.WAITING_FOR_GESTURE, State.GENERATING_PATH):
            self.ctx.ports.set_body_pose(*body_pose)
        if state == State.WAITING_FOR_GESTURE:
            self._tick_waiting(now, epoch)
        elif state == State.GENERATING_PATH:
            self._tick_generating(epoch)
        else:
            self._tick_executing(now, epoch)

    def _tick_waiting(self, now: float, epoch: int) -> None:
        ctx = self.ctx
        if ctx.home is None and ctx.perception.pose is not None:
            with ctx.lock:
                pose = ctx.perception.pose  # the first pose seen while waiting
                ctx.home, ctx.home_yaw = (pose[0], pose[1]), pose[2]
        if ctx.avoid.dodge and ctx.home is not None and ctx.localized is not False and ctx.may_avoid(now):
            sides = ctx.perception.recently_approached(now)
            if sides:
                with ctx.lock:
                    ctx.reason = "approached from the %s" % SIDE_NAMES[sides[0]]
                    ctx.ports.log("info", "visitor %s: dodging" % ctx.reason)
                    if ctx.fire_if(epoch, Event.DODGE):
                        return
        if now - self._last_poll < self.gesture_period:
            return
        self._last_poll = now
        command = ctx.ports.get_gesture()
        with ctx.lock:
            flush, self._flush_gesture = self._flush_gesture, False
        if flush and command:
            ctx.ports.log("info", "dropping gesture %r made before the robot was ready" % command)
            return
        if not command:
            return
        refusal = self.refusal()
        if refusal:
            ctx.ports.log("warn", "refusing gesture %r: %s" % (command, refusal))
            return
        with ctx.lock:
            if ctx.fsm.epoch == epoch:
                self.command = command
                ctx.ports.log("info", "gesture command %r" % command)
                ctx.fire_if(epoch, Event.GESTURE)

    def _tick_generating(self, epoch: int) -> None:
        ctx = self.ctx
        command = self.command
        ok, message, poses, names = ctx.ports.generate_path(command)
        with ctx.lock:
            if ctx.fsm.epoch != epoch:
                return
            if not ok or not poses:
                ctx.ports.log("warn", "no path for %r: %s" % (command, message or "empty path"))
                ctx.fire_if(epoch, Event.PATH_FAILED)
                return
            names = list(names) + [""] * (len(poses) - len(names))
            self.queue = list(zip(poses, names))
            self.current = None
            ctx.ports.log("info", "path for %r: %d poses" % (command, len(poses)))
            ctx.fire_if(epoch, Event.PATH_READY)

    def _tick_executing(self, now: float, epoch: int) -> None:
        ctx = self.ctx
        with ctx.lock:
            if ctx.fsm.epoch != epoch:
                return
            if self.current is not None and ctx.goal.sent_at is not None:
                self._check_progress(now, epoch)
                return
            if self.current is None:
                if not self.queue:
                    self._trick_done(epoch)
                    return
                self.current = self.queue.pop(0)
            pose, name = self.current
            ctx.goal.sending()
        accepted, message = ctx.ports.set_position(pose)
        with ctx.lock:
            if ctx.fsm.epoch != epoch:
                return  # preempted meanwhile: the pose is re-sent on resume
            if not accepted:
                ctx.ports.log("error", "position controller refused %r: %s; aborting trick" % (name, message))
                ctx.fire_if(epoch, Event.ABORT)
                return
            ctx.goal.sent_at = now
            ctx.publish()

    def _check_progress(self, now: float, epoch: int) -> None:
        """Caller holds the lock. Pose done when the position controller went running -> idle."""
        ctx = self.ctx
        goal = ctx.goal
        if goal.done():
            self.current = None
            goal.sent_at = None
            if ctx.episode.start is not None:
                ctx.stats["avoided"] += 1
                ctx.ports.publish_avoidance({"event": "avoided", "detail": "blocked pose reached after %.1f s" % (
                    now - ctx.episode.start)})
                ctx.episode.start = None
                ctx.perception.forget_blocking()
            ctx.publish()
            if not self.queue:
                self._trick_done(epoch)
            return
        if not goal.seen_running and now - goal.sent_at > goal.start_timeout:
            ctx.ports.log("error", "position controller never reported running; aborting trick")
            ctx.fire_if(epoch, Event.ABORT)
        elif now - goal.sent_at > self.pose_timeout:
            ctx.ports.log(
                "error", "pose %r not reached in %.0f s; aborting trick" % (self.current[1], self.pose_timeout)
            )
            ctx.fire_if(epoch, Event.ABORT)

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
        ctx = self.ctx
        pose, home = ctx.perception.pose, ctx.home
        if (ctx.avoid.enabled and not self._returning and home is not None and pose is not None
                and math.hypot(pose[0] - home[0], pose[1] - home[1]) > ctx.avoid.home_tolerance):
            self._returning = True
            away = math.hypot(pose[0] - home[0], pose[1] - home[1])
            home_pose = ctx.ports.make_pose(home[0], home[1], ctx.home_yaw)
            since = ctx.episode.trick_since if ctx.episode.trick_since is not None else ctx.now
            if ctx.goal_blocked(home_pose, ctx.known_obstacles(since)):
                ctx.stats["gave_up"] += 1
                reason = "goal blocked: the stop zone at home would hold the obstacle"
                ctx.ports.log("warn", "trick done %.2f m from home, not walking back: %s" % (away, reason))
                ctx.ports.publish_avoidance({"event": "gave_up", "detail": reason})
            else:
                self.queue.append((home_pose, "back home (%.2f m away after avoiding)" % away))
                ctx.ports.log("info", "trick done %.2f m from home: walking back" % away)
                ctx.publish()
                return
        ctx.fire_if(epoch, Event.QUEUE_EMPTY)

    # ------------------------------------------------------------------ for the avoidance
    def blocked_pose(self) -> Any:
        """The trick pose the avoidance works towards (None when the trick has no pose left)."""
        if self.current is not None:
            return self.current[0]
        return self.queue[0][0] if self.queue else None

    def drop_blocked(self, go_home: bool) -> None:
        """Caller holds the lock. Avoidance gave up: drop the blocked pose (or head home instead)."""
        if go_home and self.trick_home is not None:
            x, y, yaw = self.trick_home
            self.queue = [(self.ctx.ports.make_pose(x, y, yaw), "return home (avoidance gave up)")]
        self.current = None
        self.drop_unreachable()

    def drop_unreachable(self) -> None:
        """Caller holds the lock. Drop the queued poses whose zone the known obstacle occupies."""
        ctx = self.ctx
        points = ctx.known_obstacles()
        while self.queue and ctx.goal_blocked(self.queue[0][0], points):
            _, name = self.queue.pop(0)
            ctx.stats["gave_up"] += 1
            reason = "goal blocked: the stop zone at %r would hold the obstacle" % name
            ctx.ports.log("warn", "skipping %r: %s" % (name, reason))
            ctx.ports.publish_avoidance({"event": "gave_up", "detail": reason})
