#!/usr/bin/env python3
"""rostest: gesture topic -> GetLastGesture, once; unknown gestures filtered."""

import time
import unittest

import rospy
import rostest
from std_msgs.msg import String

from rbd_msgs.srv import GetLastGesture


class TestGestrec(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_gestrec", anonymous=True)
        rospy.wait_for_service("/rbd_gestrec/get_last_gesture", timeout=60.0)
        cls.srv = rospy.ServiceProxy("/rbd_gestrec/get_last_gesture", GetLastGesture)
        cls.pub = rospy.Publisher("/rbd_gestrec/gesture", String, queue_size=10)
        deadline = time.monotonic() + 10.0
        while cls.pub.get_num_connections() == 0 and time.monotonic() < deadline:
            time.sleep(0.05)

    def wait_command(self, timeout=3.0):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            command = self.srv().command
            if command:
                return command
            time.sleep(0.05)
        return ""

    def test_gesture_once_then_empty_and_unknown_filtered(self):
        self.assertEqual(self.srv().command, "")
        self.pub.publish(String("spin"))
        self.assertEqual(self.wait_command(), "spin")
        self.assertEqual(self.srv().command, "")
        self.pub.publish(String("self_destruct"))
        time.sleep(0.3)
        self.assertEqual(self.srv().command, "")

    def test_a_trick_name_of_rbd_navigation_is_accepted(self):
        # launch/rbd_gestrec.launch loads rbd_navigation's tricks.yaml: "bow" has no mapping
        # entry in gestures.yaml, but it is a trick, so a taught gesture's "bow" is understood;
        # "dance" is neither and is dropped (proved by the "spin" behind it coming through alone)
        self.pub.publish(String("dance"))
        self.pub.publish(String("bow"))
        self.assertEqual(self.wait_command(), "bow")
        self.pub.publish(String("dance"))
        self.pub.publish(String("spin"))
        self.assertEqual(self.wait_command(), "spin")
        self.assertEqual(self.srv().command, "")


if __name__ == "__main__":
    rostest.rosrun("rbd_gestrec", "gestrec_wiring", TestGestrec)
