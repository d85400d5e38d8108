"""The stops behaviour on its own (issue 27): the blockage clock, BLOCKED's decisions, its inputs."""

import pytest

from rbd_controller.core import MainController, Ports
from rbd_controller.escape import ZoneReading
from rbd_controller.fsm import Event, State
from rbd_controller.perception import AvoidParams
from rbd_controller.stops import REBLOCK_WINDOW, Stops


def make(**avoid):
    ports = Ports(
        get_gesture=lambda: "", generate_path=lambda c: (False, "", [], []), set_position=lambda p: (True, ""),
        set_body_pose=lambda r, p, h: True, pos_emergency=lambda on: None, pos_collision=lambda on: None,
        publish_estop=lambda on: None, publish=lambda c: None, log=lambda level, msg: None)
    params = dict(static_after=5.0, blocked_timeout=3.0)
    params.update(avoid)
    return MainController(ports, avoid=AvoidParams(**params))


def blocked(ctl, t=0.0):
    """An executing robot stopped by a box, classified static: BLOCKED."""
    ctl.set_emergency(False)
    ctl.fsm.fire(Event.GESTURE)
    ctl.fsm.fire(Event.PATH_READY)
    ctl.ctx.now = t
    ctl.set_collision(True)
    ctl.fsm.fire(Event.BLOCKED_STATIC)
    assert ctl.state == State.BLOCKED


def feed(ctl, t, points, low=False):
    ctl.perception.on_pose(t, 0.0, 0.0, 0.0)
    ctl.perception.on_zone(t, ZoneReading([10, 0, 0, 0], [0.4, 9.0, 9.0, 9.0]))
    ctl.perception.on_blocking_points(t, points, low)


def test_unknown_operator_policy_is_refused():
    with pytest.raises(ValueError):
        Stops(make().ctx, None, operator_policy="wander")


def test_a_new_stop_within_the_reblock_window_keeps_the_blockage_clock():
    ctl = make()
    stops = ctl.stops
    blocked(ctl, t=1.0)
    assert stops.stop_since == 1.0
    ctl.ctx.now = 2.0
    ctl.set_collision(False)  # resumes EXECUTING: the stop ended at 2.0
    assert ctl.state == State.EXECUTING and stops.last_stop_end == 2.0
    ctl.ctx.now = 2.0 + REBLOCK_WINDOW - 0.5
    ctl.set_collision(True)
    assert stops.stop_since == 1.0  # stop-and-go at the same obstacle: blocked since the first stop
    ctl.ctx.now = 20.0
    ctl.set_collision(False)
    ctl.ctx.now = 20.0 + REBLOCK_WINDOW + 0.5
    ctl.set_collision(True)
    assert stops.stop_since == ctl.ctx.now


def test_blocked_waits_blocked_timeout_unless_it_is_the_known_obstacle():
    box = [(0.5, y / 50.0) for y in range(-10, 11)]
    for known, expect in ((False, State.BLOCKED), (True, State.ESCAPING)):
        ctl = make()
        blocked(ctl, t=0.0)
        if known:
            ctl.perception.known_static = __import__("numpy").array(box)
        for i in range(8):  # 0.7 s of the same points, well before blocked_timeout (3 s)
            feed(ctl, 0.1 * i, box)
        ctl.stops.tick(State.BLOCKED, 0.7, ctl.fsm.epoch)
        assert ctl.state == expect, known


def test_a_low_obstacle_is_static_after_low_static_after_and_escaped_from_without_blocked_timeout():
    # Issue 27: a bag's 5 s classification plus nothing to wait for; a tall blocker keeps both waits.
    box = [(0.5, y / 50.0) for y in range(-10, 11)]
    for low in (False, True):
        ctl = make(low_static_after=1.5)
        ctl.set_emergency(False)
        ctl.fsm.fire(Event.GESTURE)
        ctl.fsm.fire(Event.PATH_READY)
        ctl.ctx.now = 0.0
        ctl.set_collision(True)
        states = []
        for i in range(25):  # 2.4 s of the same points
            t = 0.1 * i
            ctl.ctx.now = t
            feed(ctl, t, box, low)
            ctl.stops.tick(ctl.state, t, ctl.fsm.epoch)
            states.append((round(t, 1), ctl.state))
        if low:
            assert all(st == State.COLLISION_DETECTED for t, st in states if t < 1.45), states
            assert ctl.state == State.ESCAPING, states
            blocked_at = min(t for t, st in states if st != State.COLLISION_DETECTED)
            assert blocked_at <= 1.7, states
        else:
            assert all(st == State.COLLISION_DETECTED for _, st in states), states


def test_blocked_with_a_moving_blocker_goes_back_to_waiting_for_it():
    ctl = make()
    blocked(ctl)
    for i in range(8):
        feed(ctl, 0.1 * i, [(0.5, -0.4 + 0.1 * i + y / 50.0) for y in range(-5, 6)])  # walks across
    ctl.stops.tick(State.BLOCKED, 0.7, ctl.fsm.epoch)
    assert ctl.state == State.COLLISION_DETECTED and ctl.fsm.resume == State.EXECUTING


def test_remote_estop_held_refuses_releases():
    ctl = make()
    ctl.set_emergency(False)
    ctl.set_remote_estop(True)
    assert ctl.state == State.EMERGENCY_STOP and ctl.remote_held
    assert "refused" in ctl.set_emergency(False) and ctl.state == State.EMERGENCY_STOP
    ctl.set_remote_estop(False)
    ctl.set_emergency(False)
    assert ctl.state == State.WAITING_FOR_GESTURE
