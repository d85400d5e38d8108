"""The tricks behaviour on its own (issue 27): what the avoidance asks of the trick, its on_enter; the
localization gate (issue 29)."""

import math

import numpy as np

from rbd_controller.core import MainController, Ports
from rbd_controller.escape import ZoneReading
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


# ---------------------------------------------------------------------- the localization gate (issue 29)
class World:
    """Gestures, a three-pose path, a position controller that finishes each pose at once."""

    def __init__(self, dodge=False):
        self.gestures, self.sent, self.body_poses, self.guarded, self.logs = [], [], [], [], []
        self.ctl = MainController(
            Ports(get_gesture=lambda: self.gestures.pop(0) if self.gestures else "",
                  generate_path=lambda c: (True, "ok", ["p1", "p2", "p3"], ["a", "b", "c"]),
                  set_position=self.set_position, set_body_pose=lambda r, p, h: self.body_poses.append((r, p, h)),
                  pos_emergency=lambda on: None, pos_collision=lambda on: None, publish_estop=lambda on: None,
                  publish=lambda c: None, log=lambda level, msg: self.logs.append((level, msg)),
                  set_guarded_position=lambda x, y, v: self.guarded.append((x, y, v)) or (True, "ok")),
            avoid=AvoidParams(enabled=False, dodge=dodge))
        self.t = 0.0

    def set_position(self, pose):
        self.sent.append(pose)
        self.ctl.on_pos_status("running")
        self.ctl.on_pos_status("idle")
        return True, "ok"

    def run(self, ticks):
        for _ in range(ticks):
            self.ctl.tick(self.t)
            self.t += 0.25

    def show(self, gesture, ticks=20):
        """A gesture while waiting; the states the controller went through."""
        self.gestures.append(gesture)
        seen = []
        for _ in range(ticks):
            self.run(1)
            seen.append(self.ctl.state)
        return seen


def test_gestures_are_refused_while_not_localized_and_taken_once_localized():
    w = World()
    ctl = w.ctl
    ctl.on_localized(False)  # the map correction started in a loaded map
    assert ("warn", "not localized in the map: gestures are refused until it is") in w.logs
    ctl.set_emergency(False)
    w.run(2)  # the first poll (flushing)
    assert ctl.state == State.WAITING_FOR_GESTURE
    seen = w.show("walk")
    assert set(seen) == {State.WAITING_FOR_GESTURE} and w.sent == [] and w.gestures == []  # taken, refused
    refusals = [msg for level, msg in w.logs if level == "warn" and msg.startswith("refusing gesture 'walk'")]
    assert len(refusals) == 1 and "not localized in the map" in refusals[0]
    assert (0.0, 0.0, 0.0) not in w.body_poses  # not even the neutral body pose a trick starts with
    ctl.on_localized(False)  # repeated: nothing new
    assert sum(1 for _, msg in w.logs if msg.startswith("not localized")) == 1
    ctl.on_localized(True)
    assert ("info", "localized in the map: taking gestures again") in w.logs
    seen = w.show("walk")
    assert State.EXECUTING in seen and w.sent == ["p1", "p2", "p3"] and ctl.state == State.WAITING_FOR_GESTURE


def test_without_the_localized_topic_nothing_changes():
    w = World()
    w.ctl.set_emergency(False)
    w.run(2)
    assert w.ctl.ctx.localized is None
    assert State.EXECUTING in w.show("walk") and w.sent == ["p1", "p2", "p3"]
    assert not any("localized" in msg for _, msg in w.logs)


def test_localized_while_waiting_takes_home_again_from_the_converged_pose():
    w = World()
    ctl = w.ctl
    ctl.on_localized(False)
    ctl.perception.on_pose(0.0, 1.0, 2.0, 0.5)  # the unconverged start pose
    ctl.set_emergency(False)
    w.run(1)
    assert ctl.home == (1.0, 2.0) and ctl.home_yaw == 0.5
    ctl.perception.on_pose(0.1, 1.6, 2.3, 0.9)  # the search found the start 0.67 m / 23 deg away
    w.run(1)
    assert ctl.home == (1.0, 2.0)  # still the old one while not localized
    ctl.on_localized(True)
    w.run(1)
    assert ctl.home == (1.6, 2.3) and ctl.home_yaw == 0.9
    ctl.perception.on_pose(0.2, 1.7, 2.3, 0.9)  # localized: home stays where it was taken
    w.run(1)
    assert ctl.home == (1.6, 2.3)


def test_an_idle_robot_does_not_dodge_while_not_localized():
    def approach(w):
        p = w.ctl.perception
        w.ctl.set_emergency(False)
        for i in range(6):  # something walks at the front of the band at 0.5 m/s
            p.on_pose(0.1 * i, 0.0, 0.0, 0.0)
            p.on_zone(0.1 * i, ZoneReading([0] * 4, [1.1 - 0.05 * i, math.inf, math.inf, math.inf]))
        w.ctl.tick(0.5)
        return w.ctl.state

    localized = World(dodge=True)
    localized.ctl.on_localized(True)
    assert approach(localized) == State.DODGING  # the same approach dodges when localized
    w = World(dodge=True)
    w.ctl.on_localized(False)
    assert approach(w) == State.WAITING_FOR_GESTURE and w.guarded == []
