"""The tricks behaviour on its own (issue 27): what the avoidance asks of the trick, its on_enter."""

import numpy as np

from rbd_controller.core import MainController, Ports
from rbd_controller.fsm import State
from rbd_controller.perception import AvoidParams


def make(log=None):
    ports = Ports(
        get_gesture=lambda: "", generate_path=lambda c: (False, "", [], []), set_position=lambda p: (True, ""),
        set_body_pose=lambda r, p, h: True, pos_emergency=lambda on: None, pos_collision=lambda on: None,
        publish_estop=lambda on: None, publish=lambda c: None,
        log=(lambda level, msg: log.append((level, msg))) if log is not None else (lambda level, msg: None))
    return MainController(ports, avoid=AvoidParams(static_after=0.5))


def test_blocked_pose_is_the_current_pose_else_the_next_queued():
    tricks = make().tricks
    assert tricks.blocked_pose() is None
    tricks.queue = [((1.0, 0.0, 0.0), "a"), ((2.0, 0.0, 0.0), "b")]
    assert tricks.blocked_pose() == (1.0, 0.0, 0.0)
    tricks.current = ((0.5, 0.0, 0.0), "now")
    assert tricks.blocked_pose() == (0.5, 0.0, 0.0)
    assert [name for _, name in tricks.remaining()] == ["now", "a", "b"]


def test_drop_blocked_skips_the_pose_and_every_queued_pose_the_obstacle_holds():
    logs = []
    ctl = make(logs)
    tricks = ctl.tricks
    ctl.perception.on_blocking_points(0.0, np.array([(2.3, 0.0), (2.3, 0.1)]))  # in the front zone at (2, 0)
    tricks.current = ((1.0, 0.0, 0.0), "blocked")
    tricks.queue = [((2.0, 0.0, 0.0), "held by the box"), ((0.0, 0.0, 0.0), "home")]
    tricks.drop_blocked(go_home=False)
    assert tricks.current is None and [name for _, name in tricks.queue] == ["home"]
    assert ctl.stats["gave_up"] == 1 and any("held by the box" in msg for _, msg in logs)


def test_drop_blocked_with_give_up_home_queues_the_trick_start():
    tricks = make().tricks
    tricks.trick_home = (0.2, 0.3, 1.0)
    tricks.current = ((1.0, 0.0, 0.0), "blocked")
    tricks.queue = [((2.0, 0.0, 0.0), "b")]
    tricks.drop_blocked(go_home=True)
    assert tricks.queue == [((0.2, 0.3, 1.0), "return home (avoidance gave up)")]


def test_entering_waiting_sets_home_and_forgets_the_trick_and_the_known_obstacle():
    ctl = make()
    ctl.perception.on_pose(0.0, 1.0, 2.0, 0.5)
    ctl.perception.known_static = np.array([(1.0, 1.0)])
    ctl.tricks.queue = [((2.0, 0.0, 0.0), "b")]
    ctl.set_emergency(False)
    assert ctl.state == State.WAITING_FOR_GESTURE
    assert ctl.home == (1.0, 2.0) and ctl.home_yaw == 0.5
    assert ctl.queue == [] and len(ctl.perception.known_static) == 0
    ctl.tricks.latch_body_pose()
    assert ctl.tricks._body_pose_due == (0.0, ctl.tricks.attentive_pitch, 0.0)
    ctl.tricks.latch_body_pose()  # one tick later: not again
    assert ctl.tricks._body_pose_due is None
