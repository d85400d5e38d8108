"""The avoidance behaviour (issue 17): escape from a static blocker, then detour to the blocked pose. ROS-free.

ESCAPING sends guarded goals (the position controller gates them per zone side) until the zone is
clear by a margin; AVOIDING plans in a worker thread (never in the tick) with the SE(2) lattice, the
stop zone as footprint, and has the position controller follow the plan (follow_path); the grid
planner (a disc, driven pose by pose) only when the lattice finds nothing within its budget. Without
progress for ~avoid_timeout, or when the goal is blocked or the detour too long, it gives up: the
blocked pose is dropped (or the trick heads home) and the trick goes on. The decisions are in
ROS-free modules (escape, lattice, detour, arena, planner_worker); this one only sequences them.
"""

import math
from typing import Any, Tuple, Union

from rbd_controller.context import Behaviour, Context
from rbd_controller.detour import DetourPlanner, Plan
from rbd_controller.escape import clear_by_margin, plan_escape
from rbd_controller.footprint import ZoneGrowth, swept_hits
from rbd_controller.fsm import Event, State
from rbd_controller.lattice import LatticePlanner
from rbd_controller.lattice_plan import LatticePlan, progress_index, remaining_clear, speed_ahead
from rbd_controller.planner_worker import Outcome, PlannerWorker

#: Wall-clock budget of one lattice search [s], then the grid planner (the README says why 4 s).
LATTICE_BUDGET = 4.0
#: Heading bins of the lattice (32: 11.25 degrees; 48 cost ~25 % more CPU on the stroll's box scene).
LATTICE_HEADINGS = 32
#: The rest of a followed detour is checked against the scan this often [s].
REPLAN_CHECK = 0.5

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
        self.planner = DetourPlanner(inflation=ctx.avoid.inflation, clearance=ctx.avoid.clearance)  # the fallback
        self.lattice = LatticePlanner(ctx.avoid.zone, headings=LATTICE_HEADINGS)
        self.worker = PlannerWorker()
        self.budget = LATTICE_BUDGET  # wall-clock seconds of one lattice search
        self.plan = None  # type: Optional[Union[LatticePlan, Plan]]  # the detour being driven
        self.kind = ""  # which planner made it: "lattice" (followed) or "grid" (driven pose by pose)
        self.plan_start = None  # type: Optional[Tuple[float, float]]
        # grid: its poses still to drive; lattice: the speed limit the path was last sent with (None: not sent)
        self.detour = None  # type: Any
        self._progress = 0  # lattice: index of the plan's next pose
        self._checked_at = 0.0
        self._resend = False  # lattice: a new plan replaces the running path
        self._job = None  # type: Optional[Tuple[str, int]]  # key of the planner job wanted
        self._attempts = 0
        self._retry_at = 0.0

    def set_zone_growth(self, growth: ZoneGrowth, origin: Tuple[float, float] = (0.0, 0.0)) -> None:
        """rbd_lidar's growth parameters and its zone's origin in base_link for the lattice (the node reads them)."""
        self.lattice = LatticePlanner(self.ctx.avoid.zone, growth, origin=origin, headings=LATTICE_HEADINGS)

    def on_enter(self, state: State, previous: State) -> None:
        """Forget the goal; a new plan unless a stop that cleared by itself interrupted the detour."""
        ctx = self.ctx
        ctx.goal.sent_at = None
        if not (state == State.AVOIDING and previous in RESUMED_FROM):
            # A new obstacle (after BLOCKED / ESCAPING) means a new plan; after a stop that cleared
            # by itself (a person passed, a stale scan, an e-stop) the current detour pose is re-sent.
            self.plan = None
            self.detour = None
            self._job = None
            self.worker.cancel()
        self._resend = False
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
        self._job = None
        self.worker.cancel()
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
            esc, why = plan_escape(reading, a.zone, pose, 1, a.escape_margin, a.escape_max, arena=arena,
                                   room=self.lattice.turn_room())  # room for the detour's first turn at full rate
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
        """Plan the detour to the blocked pose once (in the worker), then drive it."""
        with self.ctx.lock:
            if self.ctx.fsm.epoch != epoch or self.timed_out(epoch):
                return
        if self.plan is None:
            self._plan_detour(now, epoch)
            return
        (self._follow_detour if self.kind == "lattice" else self._drive_detour)(self.plan, now, epoch)

    def _plan_job(self, start: Any, goal: Any, grid: Any, points: Any, arena: Any) -> Tuple[str, Any, str]:
        """In the worker: the lattice within its budget, else the grid planner. (kind, plan, lattice's answer)."""
        plan = self.lattice.plan(start, goal, grid, points, arena, any_heading=True, budget=self.budget)
        if plan.ok:
            return "lattice", plan, plan.reason
        grid_plan = self.planner.plan((start[0], start[1]), (goal[0], goal[1]), grid, points, arena)
        return "grid", grid_plan, plan.reason

    def _plan_detour(self, now: float, epoch: int) -> None:
        """Submit the plan to the blocked pose to the worker, or take its answer (stale answers are dropped)."""
        ctx = self.ctx
        p = ctx.perception
        with ctx.lock:
            if ctx.fsm.epoch != epoch:
                return
            if self._job is not None and self._job[1] != epoch:
                self.worker.cancel()  # planned before a stop: the scene may have changed
                self._job = None
            if self._job is not None:
                done = self.worker.poll()
                if done is None:
                    return  # still planning: the robot stands (stopped since the escape)
                if done.key != self._job:
                    ctx.ports.log("info", "dropped a stale plan (%r)" % (done,))
                    self._job = None
                    return
                self._job = None
                self._take_plan(done, now, epoch)
                return
            goal_pose = self.tricks.blocked_pose()
            if goal_pose is None or p.pose is None:
                ctx.fire_if(epoch, Event.DETOUR_DONE)
                return
            start = tuple(p.pose[:3])
            goal = tuple(ctx.ports.pose_xy(goal_pose)[:3])
            arena = p.ensure_arena(ctx.home or (start[0], start[1]))
            points = ctx.known_obstacles()
            inside = ctx.goal_blocked(goal_pose, points)
            if inside:
                self.give_up(epoch, "goal blocked: the stop zone at the goal would hold %d obstacle points" % inside)
                return
            key = ("plan", epoch)
            grid = p.grid
            if self.worker.submit(key, lambda: self._plan_job(start, goal, grid, points, arena)):
                self._job = key
                self.plan_start = start

    def _take_plan(self, done: Outcome, now: float, epoch: int) -> None:
        """Caller holds the lock. Accept the worker's answer (or give up with its reason)."""
        ctx = self.ctx
        if done.error:
            ctx.ports.log("error", "detour planner crashed after %.2f s: %s\n%s" % (done.seconds, done.error,
                                                                                    done.trace))
            self.give_up(epoch, "planner error: %s" % done.error)
            return
        kind, plan, lattice_reason = done.result
        if kind == "grid":
            ctx.ports.log("warn", "lattice found no detour in %.2f s (%s): grid planner (disc, pose by pose)" % (
                self.budget, lattice_reason))
        if not self._accept(plan, epoch):
            return
        start = self.plan_start
        self.plan, self.kind, self.detour = plan, kind, None
        self._progress, self._checked_at, self._resend = 0, now, False
        ctx.perception.remember_static()  # going around it: a stop at it is not classified from scratch
        ctx.ports.log("info", "detour (%s planner, %.2f s wall) to the blocked pose: %r" % (kind, done.seconds, plan))
        self._publish_plan(start, plan, kind, done.seconds)

    def _accept(self, plan: Union[LatticePlan, Plan], epoch: int) -> bool:
        """Caller holds the lock. Give up on a failed or too long plan."""
        a = self.ctx.avoid
        if not plan.ok:
            self.give_up(epoch, plan.reason)
            return False
        limit = a.max_detour_factor * max(plan.direct, 0.5)
        if plan.length > limit:
            self.give_up(epoch, "detour %.2f m > %.1f x the direct %.2f m" % (plan.length, a.max_detour_factor,
                                                                             plan.direct))
            return False
        return True

    def _publish_plan(self, start: Any, plan: Union[LatticePlan, Plan], kind: str, seconds: float) -> None:
        info = {"event": "plan", "detail": "%s planner, %.2f s: %s" % (kind, seconds, plan.reason), "planner": kind}
        if isinstance(plan, LatticePlan):
            info.update({"plan": [(start[0], start[1])] + [q[:2] for q in plan.poses],
                         "poses": [tuple(start[:3])] + list(plan.poses), "speeds": list(plan.speeds),
                         "zones": [list(z) for z in plan.zones]})
        else:
            info["plan"] = [(start[0], start[1])] + list(plan.waypoints)
        self.ctx.ports.publish_avoidance(info)

    def _follow_detour(self, plan: LatticePlan, now: float, epoch: int) -> None:
        """Follow the lattice plan continuously (follow_path), speed-limited, replanned; DETOUR_DONE at its end.

        Sent once, again (no stop) when the speed limit ahead changes or a new plan arrives; every
        REPLAN_CHECK s a known obstacle in the rest of the swept zones starts a replan in the worker
        while the robot follows on. After a stop that cleared by itself the rest is sent again.
        """
        ctx = self.ctx
        p = ctx.perception
        with ctx.lock:
            if ctx.fsm.epoch != epoch:
                return
            pose = p.pose
            if pose is None:
                return
            if self._job is not None and self._job[1] != epoch:
                self.worker.cancel()
                self._job = None
            if self._job is not None:
                done = self.worker.poll()
                if done is not None:
                    self._job, key = None, done.key
                    if key != ("replan", epoch):
                        ctx.ports.log("info", "dropped a stale replan (%r)" % (done,))
                    elif done.error or done.result[0] != "lattice":
                        why = done.error or done.result[2]
                        ctx.ports.log("warn", "the scan changed, no new plan (%s): following the old one" % why)
                        self._checked_at = now + 3.0 * REPLAN_CHECK
                    elif self._accept(done.result[1], epoch):
                        self.plan = plan = done.result[1]
                        self._progress, self._resend = 0, True
                        ctx.ports.log("info", "the scan changed: replanned %r in %.2f s" % (plan, done.seconds))
                        self._publish_plan(self.plan_start, plan, "lattice", done.seconds)
                    else:
                        return  # gave up
            progress = progress_index(plan, pose, self._progress)
            if progress > self._progress:
                ctx.episode.progressed()  # a pose of the detour passed: ~pose_timeout counts from here
                ctx.goal.sent_at = now if ctx.goal.sent_at is not None else None
            self._progress = progress
            remaining = plan.poses[self._progress:]
            speed = speed_ahead(plan, self._progress)
            if self.detour is not None:
                goal = ctx.goal.result(now, self.tricks.pose_timeout)
                if goal == "failed":
                    self.give_up(epoch, "detour not followed to its end")
                    return
                if goal == "done" or goal == "none":
                    end = plan.poses[-1]
                    if math.hypot(pose[0] - end[0], pose[1] - end[1]) <= 0.1:
                        ctx.episode.progressed()
                        if self._chain_next(pose, now):
                            return
                        ctx.ports.log("info", "detour done: continuing the trick")
                        ctx.fire_if(epoch, Event.DETOUR_DONE)
                        return
                    self.detour = None  # stopped short of the end (a refusal raced a release): send the rest
                elif goal == "active":
                    if self._job is None and now - self._checked_at >= REPLAN_CHECK:
                        self._checked_at = now
                        self._submit_replan(pose, plan, epoch)
                    if not self._resend and abs(speed - self.detour) < 1e-9:
                        return
            fresh = self.detour is None
            if fresh:
                ctx.goal.sending()
        accepted, message = ctx.ports.follow_path(list(remaining), speed)
        with ctx.lock:
            if ctx.fsm.epoch != epoch:
                return
            if not accepted:
                # A refusal can race with a stop being released; try again, then give up.
                self._attempts += 1
                if self._attempts >= 4:
                    self.give_up(epoch, "position controller refused the detour: %s" % message)
                self.detour = None
                return
            self.detour, self._resend = speed, False
            if fresh:
                ctx.goal.sent_at = now
            ctx.publish()

    def _chain_next(self, pose: Any, now: float) -> bool:
        """Caller holds the lock. At the blocked pose: plan on when the way to the next pose crosses the obstacle.

        The trick's next motion (turn, walk straight) is checked against the static obstacle being avoided
        (the stroll's way back passes the bag again): then the blocked pose counts as reached and the next
        one is planned for at once, instead of walking into a new stop, classification and escape.
        """
        ctx = self.ctx
        tricks = self.tricks
        static = ctx.perception.known_static
        if tricks.current is None or not tricks.queue or not len(static):
            return False
        gx, gy = ctx.ports.pose_xy(tricks.queue[0][0])[:2]
        if math.hypot(gx - pose[0], gy - pose[1]) < 0.05:
            return False
        face = math.atan2(gy - pose[1], gx - pose[0])
        path = [tuple(pose[:3]), (pose[0], pose[1], face), (gx, gy, face)]
        if swept_hits(path, self.lattice.zone_for(self.lattice.speed), static) < ctx.avoid.point_threshold:
            return False
        name = tricks.current[1]
        tricks.current = tricks.queue.pop(0)  # the new blocked pose (a give-up drops it)
        ctx.stats["avoided"] += 1
        since = ctx.episode.start if ctx.episode.start is not None else now
        ctx.ports.publish_avoidance({"event": "avoided", "detail": "blocked pose reached after %.1f s" % (now - since)})
        ctx.ports.log("info", "%r reached by the detour; the way to %r crosses the obstacle being avoided: planning on"
                      % (name, tricks.current[1]))
        self.plan, self.detour, self._job = None, None, None
        ctx.goal.sent_at = None
        return True

    def _submit_replan(self, pose: Any, plan: LatticePlan, epoch: int) -> None:
        """Caller holds the lock. A new plan from pose to the detour's end if the rest holds known obstacles."""
        ctx = self.ctx
        points = ctx.known_obstacles()
        if remaining_clear(plan, self._progress, pose, points, ctx.avoid.point_threshold):
            return
        p = ctx.perception
        start, goal = tuple(pose[:3]), tuple(plan.poses[-1])
        arena = p.ensure_arena(ctx.home or (start[0], start[1]))
        grid = p.grid
        key = ("replan", epoch)

        def job() -> Tuple[str, Any, str]:
            new = self.lattice.plan(start, goal, grid, points, arena, any_heading=True, budget=self.budget)
            return ("lattice" if new.ok else "none"), new, new.reason

        if self.worker.submit(key, job):
            self._job = key
            self.plan_start = start
            ctx.ports.log("info", "the scan puts known obstacles into the rest of the detour: replanning")

    def _drive_detour(self, plan: Plan, now: float, epoch: int) -> None:
        """Drive the grid plan pose by pose (turn towards the next waypoint at each); DETOUR_DONE at its end."""
        ctx = self.ctx
        with ctx.lock:
            if ctx.fsm.epoch != epoch:
                return
            if self.detour is None:
                points = [self.plan_start[:2]] + list(plan.waypoints)
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
