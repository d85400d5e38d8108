"""The laptop app's status words are the robot's (rbd_msgs/PosControllerStatus), read from the .msg file."""

import os
import re

from rbd_local import robot_names

MSG = os.path.join(os.path.dirname(__file__), "..", "..", "src", "rbd_msgs", "msg", "PosControllerStatus.msg")


def test_status_words_match_the_robots_message():
    with open(MSG) as fh:
        constants = dict(re.findall(r"^string (\w+)=(\S+)$", fh.read(), re.M))
    assert set(constants) == {"IDLE", "RUNNING", "EMERGENCY", "COLLISION"}
    for name, word in constants.items():
        assert getattr(robot_names, "STATUS_" + name) == word
