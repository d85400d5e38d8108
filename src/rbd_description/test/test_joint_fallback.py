"""rbd_description.joint_fallback: the standing pose is shown only while nobody else publishes joint states."""

import pytest

from rbd_description.joint_fallback import OK, WARN, JointStateWatch


def test_publishes_from_start_until_the_robot_speaks_and_again_when_it_falls_silent():
    w = JointStateWatch(1.0, now=100.0)
    assert not w.should_publish(100.5)  # give the driver its timeout first
    assert w.should_publish(101.0)
    level, text = w.status(101.0)
    assert level == WARN and "nominal standing pose" in text and "v3.3" in text
    w.on_message("/rbd_a1_driver", 101.2, own="/joint_state_fallback")
    assert not w.should_publish(101.3)
    assert w.status(101.3) == (OK, "joint angles from /rbd_a1_driver")
    assert not w.should_publish(102.1)
    assert w.should_publish(102.2)
    level, text = w.status(102.7)
    assert level == WARN and "from /rbd_a1_driver for 1.5 s" in text


def test_its_own_messages_do_not_count():
    w = JointStateWatch(0.5, now=0.0)
    for t in (0.6, 0.7, 0.8):
        w.on_message("/joint_state_fallback", t, own="/joint_state_fallback")
    assert w.should_publish(0.9)
    assert w.received == 0 and w.source == ""


def test_bad_timeout():
    with pytest.raises(ValueError):
        JointStateWatch(0.0, now=0.0)
