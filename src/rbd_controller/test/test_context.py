"""The behaviours' shared context (issue 27): goal tracking, the avoidance episode, stop syncing."""

from rbd_controller.context import Context, Episode, Goal, Ports
from rbd_controller.fsm import Event, Fsm, State
from rbd_controller.perception import AvoidParams


def make_context(calls):
    ports = Ports(
        get_gesture=lambda: "", generate_path=lambda c: (False, "", [], []), set_position=lambda p: (True, ""),
        set_body_pose=lambda r, p, h: True,
        pos_emergency=lambda on: calls.append(("pos_emergency", on)),
        pos_collision=lambda on: calls.append(("pos_collision", on)),
        publish_estop=lambda on: calls.append(("estop", on)),
        publish=lambda c: calls.append(("publish", c)), log=lambda level, msg: None)
    ctx = Context(ports, AvoidParams(), start_timeout=1.0)
    ctx.fsm = Fsm()
    ctx.controller = "the controller"
    return ctx


def test_goal_done_only_after_running_then_idle_reported_after_the_send():
    goal = Goal(start_timeout=1.0)
    assert goal.result(0.0, 10.0) == "none"
    goal.on_status("running")  # an old goal's status
    goal.on_status("idle")
    goal.sending()
    goal.sent_at = 0.0
    assert goal.result(0.5, 10.0) == "active"  # the idle before the send does not count
    goal.on_status("running")
    goal.on_status("idle")
    assert goal.result(0.6, 10.0) == "done" and goal.sent_at is None


def test_goal_fails_without_running_within_start_timeout_or_after_its_timeout():
    goal = Goal(start_timeout=1.0)
    goal.sending()
    goal.sent_at = 0.0
    assert goal.result(1.01, 10.0) == "failed"
    goal.sending()
    goal.sent_at = 0.0
    goal.on_status("running")
    assert goal.result(5.0, 10.0) == "active" and goal.result(10.5, 10.0) == "failed"


def test_episode_stalls_only_without_progress():
    ep = Episode()
    assert not ep.stalled(1.0)  # no episode
    ep.begin(3.0)
    ep.begin(9.0)  # one episode: the first start stays
    assert ep.start == 3.0 and ep.trick_since == 3.0
    ep.active = 1.5
    assert ep.stalled(1.0)
    ep.progressed()
    assert not ep.stalled(1.0)


def test_sync_stops_engages_before_it_releases_and_fire_if_checks_the_epoch():
    calls = []
    ctx = make_context(calls)
    ctx.sync_stops()  # power-up: e-stop
    assert calls == [("estop", True), ("pos_emergency", True), ("pos_collision", False)]
    del calls[:]
    ctx.fsm.fire(Event.COLLISION)  # remembered under the e-stop
    ctx.fire(Event.ESTOP_RELEASE)  # -> COLLISION_DETECTED: the collision hold first, then the release
    assert ctx.fsm.state == State.COLLISION_DETECTED
    assert calls == [("pos_collision", True), ("estop", False), ("pos_emergency", False), ("publish", "the controller")]
    epoch = ctx.fsm.epoch
    ctx.fsm.fire(Event.ESTOP)
    assert not ctx.fire_if(epoch, Event.ESTOP_RELEASE) and ctx.fsm.state == State.EMERGENCY_STOP


def test_may_avoid_needs_a_fresh_valid_zone_a_pose_and_the_monitor():
    from rbd_controller.escape import ZoneReading

    ctx = make_context([])
    assert not ctx.may_avoid(0.0)
    ctx.perception.on_pose(0.0, 0.0, 0.0, 0.0)
    ctx.perception.on_zone(0.0, ZoneReading([0] * 4, [1.0] * 4))
    assert ctx.may_avoid(0.4) and not ctx.may_avoid(0.6)  # older than 0.5 s: stale
    ctx.lidar_lost = True
    assert not ctx.may_avoid(0.1)
