"""The dodging behaviour on its own (issue 27): stale zone, the step away, the way home."""

import math

from rbd_controller.core import MainController, Ports
from rbd_controller.escape import ZoneReading
from rbd_controller.fsm import Event, State
from rbd_controller.perception import AvoidParams


class Fake:
    def __init__(self):
        self.guarded = []
        self.ctl = MainController(
            Ports(get_gesture=lambda: "", generate_path=lambda c: (False, "", [], []),
                  set_position=lambda p: (True, ""),
                  set_body_pose=lambda r, p, h: True, pos_emergency=lambda on: None, pos_collision=lambda on: None,
                  publish_estop=lambda on: None, publish=lambda c: None, log=lambda level, msg: None,
                  set_guarded_position=lambda x, y, v: self.guarded.append((x, y, v)) or (True, "ok")),
            avoid=AvoidParams(dodge=True))

    def dodging(self, t=0.0):
        ctl = self.ctl
        ctl.perception.on_pose(t, 0.0, 0.0, 0.0)
        ctl.set_emergency(False)
        assert ctl.home == (0.0, 0.0)
        ctl.fsm.fire(Event.DODGE)
        assert ctl.state == State.DODGING
        return ctl.dodging


def test_a_stale_zone_stops_the_dodge():
    fake = Fake()
    dodging = fake.dodging()
    fake.ctl.perception.on_zone(0.0, ZoneReading([0] * 4, [math.inf] * 4, stale=True))
    dodging.tick(State.DODGING, 0.1, fake.ctl.fsm.epoch)
    assert fake.ctl.state == State.COLLISION_DETECTED and fake.guarded == []


def test_an_approach_from_the_front_steps_back_guarded_and_slow():
    fake = Fake()
    dodging = fake.dodging()
    p = fake.ctl.perception
    for i in range(6):  # something walks at the front of the band at 0.5 m/s
        p.on_pose(0.1 * i, 0.0, 0.0, 0.0)
        p.on_zone(0.1 * i, ZoneReading([0] * 4, [1.1 - 0.05 * i, math.inf, math.inf, math.inf]))
    dodging.tick(State.DODGING, 0.5, fake.ctl.fsm.epoch)
    assert len(fake.guarded) == 1
    x, y, v = fake.guarded[0]
    assert x < 0.0 and abs(y) < 1e-9 and v <= 0.2 and math.hypot(x, y) <= fake.ctl.avoid.dodge_max + 1e-9


def test_back_home_when_quiet_ends_the_dodge():
    fake = Fake()
    dodging = fake.dodging()
    p = fake.ctl.perception
    for i in range(30):
        p.on_pose(0.1 * i, 0.02, 0.0, 0.0)
        p.on_zone(0.1 * i, ZoneReading([0] * 4, [math.inf] * 4))
    dodging.tick(State.DODGING, 2.9, fake.ctl.fsm.epoch)
    assert fake.ctl.state == State.WAITING_FOR_GESTURE and fake.guarded == []
    assert fake.ctl.stats["dodges"] == 1
