"""The avoidance behaviour on its own (issue 27): the detour's driving, resuming it, giving up."""

import math

import fsm_scenes

from rbd_controller.core import MainController, Ports
from rbd_controller.detour import Plan
from rbd_controller.fsm import Event, State
from rbd_controller.perception import AvoidParams


class Fake:
    def __init__(self):
        self.sent = []
        self.events = []
        self.refuse = False
        self.ctl = MainController(
            Ports(get_gesture=lambda: "", generate_path=lambda c: (False, "", [], []), set_position=self.send,
                  set_body_pose=lambda r, p, h: True, pos_emergency=lambda on: None, pos_collision=lambda on: None,
                  publish_estop=lambda on: None, publish=lambda c: None, log=lambda level, msg: None,
                  publish_avoidance=self.events.append),
            avoid=AvoidParams(static_after=0.5))

    def send(self, pose):
        if self.refuse:
            return False, "held"
        self.sent.append(pose)
        return True, "ok"

    def avoiding(self):
        """An executing trick, blocked and escaped: AVOIDING towards the pose (2, 0)."""
        return fsm_scenes.avoiding(self.ctl)

def done(ctl):
    ctl.on_pos_status("running")
    ctl.on_pos_status("idle")


def test_drive_detour_sends_the_waypoints_facing_the_next_then_detour_done():
    fake = Fake()
    av = fake.avoiding()
    plan = Plan(True, [(1.0, 1.0), (2.0, 1.0), (2.0, 0.0)], 3.4, 2.0, "test")
    av.plan, av.plan_start = plan, (0.0, 0.0)
    ctl = fake.ctl
    for i in range(2):
        av._drive_detour(plan, 0.1 * i, ctl.fsm.epoch)
        done(ctl)
    assert [p[:2] for p in fake.sent] == [(1.0, 1.0), (2.0, 1.0)]  # the goal itself is the trick's pose
    assert math.isclose(fake.sent[0][2], 0.0) and math.isclose(fake.sent[1][2], -math.pi / 2)
    av._drive_detour(plan, 0.3, ctl.fsm.epoch)
    assert ctl.state == State.EXECUTING


def test_a_detour_resumed_after_a_collision_stop_keeps_its_plan_and_a_new_blockage_replans():
    fake = Fake()
    av = fake.avoiding()
    av.plan, av.plan_start = Plan(True, [(1.0, 1.0), (2.0, 0.0)], 2.9, 2.0, "test"), (0.0, 0.0)
    ctl = fake.ctl
    ctl.set_collision(True)
    ctl.set_collision(False)  # a person passed
    assert ctl.state == State.AVOIDING and av.plan is not None
    ctl.set_collision(True)
    ctl.fsm.fire(Event.BLOCKED_STATIC)
    ctl.fsm.fire(Event.AVOID)  # a new blockage: escape, then a new plan
    assert ctl.state == State.ESCAPING and av.plan is None


def test_refused_detour_poses_are_retried_then_given_up():
    fake = Fake()
    av = fake.avoiding()
    plan = Plan(True, [(1.0, 1.0), (2.0, 0.0)], 2.9, 2.0, "test")
    av.plan, av.plan_start = plan, (0.0, 0.0)
    fake.refuse = True
    for i in range(4):
        av._drive_detour(plan, 0.1 * i, fake.ctl.fsm.epoch)
    assert fake.ctl.state == State.EXECUTING and fake.ctl.stats["gave_up"] == 1
    assert fake.ctl.tricks.current is None  # the blocked pose is dropped
    assert [e["event"] for e in fake.events][-1] == "gave_up"


def test_no_progress_for_avoid_timeout_gives_up():
    fake = Fake()
    av = fake.avoiding()
    ctl = fake.ctl
    ctl.ctx.episode.active = ctl.avoid.avoid_timeout + 1.0
    assert av.timed_out(ctl.fsm.epoch) and ctl.state == State.EXECUTING
    assert ctl.ctx.episode.start is None
