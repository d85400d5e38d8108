"""The avoidance behaviour (issue 17): escape from a static blocker, then detour to the blocked pose. ROS-free.

ESCAPING sends guarded goals (the position controller gates them per zone side) until the zone
is clear by a margin; AVOIDING plans a detour to the blocked trick pose and drives it
(:meth:`Avoidance._drive_detour`) under the normal collision rules. Without progress for
~avoid_timeout, or when the goal is blocked or the detour too long, it gives up: the blocked
pose is dropped (or the trick heads home) and the trick goes on. The decisions are in ROS-free
modules (escape, detour, arena); this one only sequences them.
"""

import math
from typing import Any, Optional

from rbd_controller.context import Behaviour, Context
from rbd_controller.detour import DetourPlanner, Plan
from rbd_controller.escape import clear_by_margin, plan_escape
from rbd_controller.fsm import Event, State

#: Stops after which AVOIDING goes on with its detour instead of planning a new one.
RESUMED_FROM = (State.COLLISION_DETECTED, State.EMERGENCY_STOP, State.OPERATOR_LOST)


class Avoidance(Behaviour):
    """ESCAPING and AVOIDING.

    Args:
        ctx: the shared context.
        tricks: the tricks behaviour (the blocked pose, the pose timeout; what a give-up drops).
    """

    states = (State.ESCAPING, State.AVOIDING)

    def __init__(self, ctx: Context, tricks: Any) -> None:
        super().__init__(ctx)
        self.tricks = tricks
        self.planner = DetourPlanner(inflation=ctx.avoid.inflation, clearance=ctx.avoid.clearance)
        self.plan = None  # type: Optional[Plan]  # the detour being driven
        self.plan_start = None  # type: Optional[Tuple[float, float]]
        self.detour = None  # type: Optional[List[Tuple[Any, str]]]  # its poses still to drive
        self._attempts = 0
        self._retry_at = 0.0

    def on_enter(self, state: State, previous: State) -> None:
        """Forget the goal; a new plan unless a stop that cleared by itself interrupted the detour."""
        ctx = self.ctx
        ctx.goal.sent_at = None
        if not (state == State.AVOIDING and previous in RESUMED_FROM):
            # A new obstacle (after BLOCKED / ESCAPING) means a new plan; after a stop that cleared
            # by itself (a person passed, a stale scan, an e-stop) the current detour pose is re-sent.
            self.plan = None
            self.detour = None
        self._attempts = 0
        self._retry_at = 0.0
        ctx.episode.begin(ctx.now)

    def tick(self, state: State, now: float, epoch: int) -> None:
        """One step of the escape or the detour."""
        if state == State.ESCAPING:
            self._tick_escaping(now, epoch)
        else:
            self._tick_avoiding(now, epoch)

    # ------------------------------------------------------------------ give up
    def timed_out(self, epoch: int) -> bool:
        """Caller holds the lock. Give up when ~avoid_timeout passed without progress.

        Progress is an escape that cleared the zone or a detour pose reached, and only the time spent
        in BLOCKED, ESCAPING and AVOIDING counts (not stops for people, stale scans or the e-stop),
        so a slow but working avoidance is not cut short.
        """
        if self.ctx.episode.stalled(self.ctx.avoid.avoid_timeout):
            self.give_up(epoch, "no progress within avoid_timeout %.0f s" % self.ctx.avoid.avoid_timeout)
            return True
        return False

    def give_up(self, epoch: int, reason: str) -> None:
        """Caller holds the lock. Drop the blocked pose (or head home) and go on with the trick."""
        ctx = self.ctx
        ctx.stats["gave_up"] += 1
        ctx.ports.log("warn", "avoidance gave up (%s): %s" % (ctx.avoid.give_up, reason))
        ctx.ports.publish_avoidance({"event": "gave_up", "detail": reason, "plan": []})
        ctx.goal.sent_at = None
        self.plan = None
        self.detour = None
        self.tricks.drop_blocked(ctx.avoid.give_up == "home")
        ctx.episode.start = None
        ctx.perception.forget_blocking()
        ctx.fire_if(epoch, Event.GIVE_UP)

    # ------------------------------------------------------------------ escape
    def _tick_escaping(self, now: float, epoch: int) -> None:
        """Step away from the blocking side (guarded) until the zone is clear by the margin."""
        ctx = self.ctx
        p = ctx.perception
        a = ctx.avoid
        with ctx.lock:
            if ctx.fsm.epoch != epoch or self.timed_out(epoch):
                return
            if not ctx.may_avoid(now):
                if p.reading is None or not p.reading.valid or ctx.lidar_lost:
                    ctx.ports.log("warn", "zone stale or invalid during the escape: stop")
                    ctx.fire_if(epoch, Event.ZONE_STALE)
                return
            timeout = a.escape_max / a.escape_speed * 1.5 + 3.0  # held by the guard this long: try another way
            goal = ctx.goal.result(now, timeout)
            if goal == "active":
                return
            if goal == "failed":
                self._attempts += 1
            reading, pose = p.reading, p.pose
            if clear_by_margin(reading, a.zone, 1, a.escape_margin):  # not one point within the margin
                ctx.stats["escapes"] += 1
                ctx.episode.progressed()
                ctx.ports.log("info", "zone clear by %.2f m: planning the detour" % a.escape_margin)
                ctx.ports.publish_avoidance({"event": "escaped", "detail": "zone clear by %.2f m" % a.escape_margin})
                ctx.fire_if(epoch, Event.ESCAPED)
                return
            if self._attempts >= 3:
                self.give_up(epoch, "wedged: no escape after %d attempts" % self._attempts)
                return
            if now < self._retry_at:
                return
            arena = p.ensure_arena(ctx.home or (pose[0], pose[1]))
            # Like the position controller's guard: one critical point closes a side.
            esc, why = plan_escape(reading, a.zone, pose, 1, a.escape_margin, a.escape_max, arena=arena)
            if esc is None:
                self._attempts += 1
                self._retry_at = now + 1.0
                ctx.ports.log("warn", "no escape now: %s" % why)
                return
            ctx.goal.sending()
        accepted, message = ctx.ports.set_guarded_position(esc.target[0], esc.target[1], a.escape_speed)
        with ctx.lock:
            if ctx.fsm.epoch != epoch:
                return
            if not accepted:
                self._attempts += 1
                self._retry_at = now + 1.0
                ctx.ports.log("warn", "escape refused by the position controller: %s" % message)
                return
            ctx.goal.sent_at = now
            ctx.ports.log("info", "escaping: %r" % esc)
            ctx.ports.publish_avoidance({"event": "escape", "detail": esc.reason, "target": esc.target})

    # ------------------------------------------------------------------ detour
    def _tick_avoiding(self, now: float, epoch: int) -> None:
        """Plan the detour to the blocked pose once, then drive it."""
        with self.ctx.lock:
            if self.ctx.fsm.epoch != epoch or self.timed_out(epoch):
                return
        if self.plan is None:
            plan = self._plan_detour(now, epoch)
            if plan is None:
                return
        self._drive_detour(self.plan, now, epoch)

    def _plan_detour(self, now: float, epoch: int) -> Optional[Plan]:
        """Plan to the blocked pose; None (after DETOUR_DONE or a give-up) when there is nothing to drive."""
        ctx = self.ctx
        p = ctx.perception
        a = ctx.avoid
        with ctx.lock:
            goal_pose = self.tricks.blocked_pose()
            if goal_pose is None or p.pose is None:
                ctx.fire_if(epoch, Event.DETOUR_DONE)
                return None
            start = p.pose
            goal = ctx.ports.pose_xy(goal_pose)[:2]
            arena = p.ensure_arena(ctx.home or (start[0], start[1]))
            points = ctx.known_obstacles()
            inside = ctx.goal_blocked(goal_pose, points)
            if inside:
                self.give_up(epoch, "goal blocked: the stop zone at the goal would hold %d obstacle points" % inside)
                return None
        plan = self.planner.plan((start[0], start[1]), goal, p.grid, points, arena)
        with ctx.lock:
            if ctx.fsm.epoch != epoch:
                return None
            if not plan.ok:
                self.give_up(epoch, plan.reason)
                return None
            limit = a.max_detour_factor * max(plan.direct, 0.5)
            if plan.length > limit:
                self.give_up(epoch, "detour %.2f m > %.1f x the direct %.2f m" % (
                    plan.length, a.max_detour_factor, plan.direct))
                return None
            self.plan, self.plan_start, self.detour = plan, (start[0], start[1]), None
            p.remember_static()  # going around it: a stop at it is not classified from scratch
            ctx.ports.log("info", "detour to (%.2f, %.2f): %r" % (goal[0], goal[1], plan))
            ctx.ports.publish_avoidance({"event": "plan", "detail": plan.reason,
                                         "plan": [self.plan_start] + list(plan.waypoints)})
            return plan

    def _drive_detour(self, plan: Plan, now: float, epoch: int) -> None:
        """Drive the plan pose by pose (turn towards the next waypoint at each); DETOUR_DONE at its end."""
        ctx = self.ctx
        with ctx.lock:
            if ctx.fsm.epoch != epoch:
                return
            if self.detour is None:
                points = [self.plan_start] + list(plan.waypoints)
                self.detour = []
                for i, (x, y) in enumerate(points[1:-1], start=1):
                    nx, ny = points[i + 1]
                    self.detour.append((ctx.ports.make_pose(x, y, math.atan2(ny - y, nx - x)), "detour %d" % i))
            goal = ctx.goal.result(now, self.tricks.pose_timeout)
            if goal == "active":
                return
            if goal == "failed":
                self.give_up(epoch, "detour pose not reached")
                return
            if goal == "done" and self.detour:
                self.detour.pop(0)
                ctx.episode.progressed()
            if not self.detour:
                ctx.ports.log("info", "detour done: continuing the trick")
                ctx.fire_if(epoch, Event.DETOUR_DONE)
                return
            pose, name = self.detour[0]
            ctx.goal.sending()
        accepted, message = ctx.ports.set_position(pose)
        with ctx.lock:
            if ctx.fsm.epoch != epoch:
                return
            if not accepted:
                # A refusal can race with a stop being released; try again, then give up.
                self._attempts += 1
                if self._attempts >= 4:
                    self.give_up(epoch, "position controller refused %s: %s" % (name, message))
                return
            ctx.goal.sent_at = now
            ctx.publish()
