"""The dodging behaviour: an idle robot steps away from an approaching visitor and back home. ROS-free.

The steps are guarded goals (the position controller gates them per zone side); the targets come
from :func:`rbd_controller.dodge.dodge_target`, kept inside the arena.
"""

import math
from typing import Tuple

from rbd_controller.context import Behaviour
from rbd_controller.dodge import dodge_target
from rbd_controller.escape import TOWARDS
from rbd_controller.fsm import Event, State


class Dodging(Behaviour):
    """DODGING (entered from WAITING_FOR_GESTURE, or from a collision stop of an idle robot)."""

    states = (State.DODGING,)

    def on_enter(self, state: State, previous: State) -> None:
        """Forget the goal; count the dodge."""
        self.ctx.goal.sent_at = None
        self.ctx.stats["dodges"] += 1

    def tick(self, state: State, now: float, epoch: int) -> None:
        """Step away from an approaching visitor (guarded), return home when it is quiet."""
        ctx = self.ctx
        p = ctx.perception
        a = ctx.avoid
        with ctx.lock:
            if ctx.fsm.epoch != epoch:
                return
            if not ctx.may_avoid(now):
                if p.reading is None or not p.reading.valid or ctx.lidar_lost:
                    ctx.fire_if(epoch, Event.ZONE_STALE)
                return
            goal = ctx.goal.result(now, a.dodge_max / a.dodge_speed * 3.0 + 5.0)
            if goal == "active":
                return
            pose, home = p.pose, ctx.home or (p.pose[0], p.pose[1])
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
                    ctx.ports.log("info", "back home after the dodge")
                    ctx.ports.publish_avoidance({"event": "dodged", "detail": "back home"})
                    ctx.fire_if(epoch, Event.DODGE_DONE)
                    return
                target, why, kind = home, "back home (%.2f m)" % away, "home"
            if target is None:
                return
            ctx.goal.sending()
        accepted, message = ctx.ports.set_guarded_position(target[0], target[1], a.dodge_speed)
        with ctx.lock:
            if ctx.fsm.epoch != epoch:
                return
            if accepted:
                ctx.goal.sent_at = now
                ctx.ports.log("info", "%s: %s" % (kind, why))
                ctx.ports.publish_avoidance({"event": kind, "detail": why, "target": target})
            else:
                ctx.ports.log("warn", "dodge refused by the position controller: %s" % message)

    def _home_side_clear(self, pose: Tuple[float, float, float], home: Tuple[float, float]) -> bool:
        """Nothing in the slowdown band on the sides the way home heads to."""
        reading = self.ctx.perception.reading
        if reading is None:
            return False
        dx, dy = home[0] - pose[0], home[1] - pose[1]
        c, s = math.cos(pose[2]), math.sin(pose[2])
        bx, by = c * dx + s * dy, -s * dx + c * dy
        band = [z + w for z, w in zip(self.ctx.avoid.zone, self.ctx.avoid.slowdown)]
        for side, (ux, uy) in TOWARDS.items():
            if ux * bx + uy * by > 0.02 and reading.min_distance[side] < band[side]:
                return False
        return True
