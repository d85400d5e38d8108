"""The linger rule of the bridge's publishers (rbd_bridge.core.publishers): no ROS, a fake clock."""

import pytest

from rbd_bridge.core.fanout import ReplayWindow
from rbd_bridge.core.publishers import Publication, Publications
from rbd_bridge.core.types import BridgeError


class Pub(Publication):
    def __init__(self, type_name="std_msgs/String", latch=False):
        super().__init__(type_name, latch)
        self.revived = 0

    def revive(self):
        self.revived += 1


def make(linger=5.0):
    now = [100.0]
    return Publications(linger, clock=lambda: now[0]), now


def test_the_last_client_leaving_keeps_the_publisher_for_the_linger_then_it_goes():
    pubs, now = make(5.0)
    assert pubs.join("/t", "std_msgs/String", False, "a") == (None, None)  # none yet: make one
    pub = Pub()
    pubs.add("/t", pub, "a")
    assert pubs.join("/t", "std_msgs/String", True, "b") == (pub, None)  # in use: shared, latch as is
    assert pubs.leave("/t", "a") == ([], 0.0)  # b still uses it
    assert pubs.leave("/t", "b") == ([], 5.0)  # nobody: lingers, sweep due in 5 s
    assert pubs.held.get("/t") is pub and not pub.clients
    now[0] = 104.9
    assert pubs.sweep() == ([], pytest.approx(0.1))
    assert pubs.leave("/t", "a") == ([], 0.0)  # not a user: changes nothing
    now[0] = 105.0
    assert pubs.sweep() == ([pub], 0.0)
    assert pubs.held.get("/t") is None
    assert pubs.sweep() == ([], 0.0)


def test_an_advertise_within_the_linger_reuses_the_publisher():
    pubs, now = make(5.0)
    pub = Pub()
    pubs.add("/t", pub, "a")
    pubs.leave("/t", "a")
    now[0] = 103.0
    assert pubs.join("/t", "std_msgs/String", False, "b") == (pub, None)
    assert pub.clients == {"b"} and pub.revived == 1
    now[0] = 200.0  # long after the first deadline: b holds it
    assert pubs.sweep() == ([], 0.0)
    assert pubs.held.get("/t") is pub
    assert pubs.join("/t", "std_msgs/String", False, "c") == (pub, None)
    assert pub.revived == 1  # joined while in use: not a revival


@pytest.mark.parametrize("type_name, latch", [("std_msgs/Int32", False), ("std_msgs/String", True)])
def test_a_lingering_publisher_of_another_type_or_latching_is_replaced(type_name, latch):
    pubs, _ = make(5.0)
    pub = Pub("std_msgs/String", latch=False)
    pubs.add("/t", pub, "a")
    pubs.leave("/t", "a")
    assert pubs.join("/t", type_name, latch, "b") == (None, pub)  # unregister it, make a new one
    assert pubs.held.get("/t") is None and pub.revived == 0


def test_another_type_while_in_use_is_an_error():
    pubs, _ = make(5.0)
    pub = Pub()
    pubs.add("/t", pub, "a")
    with pytest.raises(BridgeError, match="already advertised with type std_msgs/String"):
        pubs.join("/t", "std_msgs/Int32", False, "b")
    assert pub.clients == {"a"}


def test_linger_zero_releases_at_once():
    pubs, _ = make(0.0)
    pub = Pub()
    pubs.add("/t", pub, "a")
    assert pubs.leave("/t", "a") == ([pub], 0.0)
    assert pubs.held.get("/t") is None


def test_sweep_is_due_at_the_earliest_deadline():
    pubs, now = make(5.0)
    first, second = Pub(), Pub()
    pubs.add("/a", first, "x")
    pubs.add("/b", second, "x")
    pubs.leave("/a", "x")
    now[0] = 102.0
    pubs.leave("/b", "x")
    now[0] = 103.0
    assert pubs.sweep() == ([], pytest.approx(2.0))
    now[0] = 105.5
    assert pubs.sweep() == ([first], pytest.approx(1.5))


def test_replay_window_reopens_for_a_revived_publisher():
    now = [10.0]
    window = ReplayWindow(1.0, 3, latch=False, clock=lambda: now[0])
    window.record("old")
    now[0] = 12.0
    window.record("closed")  # the window has closed: nothing kept
    assert window.replay() == []
    window.reopen()
    window.record("new")
    assert window.replay() == ["new"]
    now[0] = 13.0
    assert window.replay() == []
