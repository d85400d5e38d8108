#!/usr/bin/env python3
"""rostest: gesture topic -> GetLastGesture, once; unknown gestures filtered."""

import unittest

import rospy
from std_msgs.msg import String

from rbd_msgs.srv import GetLastGesture
from rbd_testkit import stays_unchanged, wait_for
from rbd_testkit.ros import RosoutWatcher, run_rostest

GESTURE_TOPIC = "/rbd_gestrec/gesture"
WRONG_TOPIC = "/rbd_gestrec/gesture_typo"


class TestGestrec(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_gestrec", anonymous=True)
        rospy.wait_for_service("/rbd_gestrec/get_last_gesture", timeout=60.0)
        cls.srv = rospy.ServiceProxy("/rbd_gestrec/get_last_gesture", GetLastGesture)
        cls.rosout = RosoutWatcher()
        cls.rosout.wait_connected("/rbd_gestrec")
        cls.pubs = {topic: rospy.Publisher(topic, String, queue_size=10) for topic in (GESTURE_TOPIC, WRONG_TOPIC)}
        wait_for(lambda: cls.pubs[GESTURE_TOPIC].get_num_connections() > 0, 10.0, what="rbd_gestrec subscribed")

    def setUp(self):
        self.srv()  # known state: nothing pending, whatever ran before

    def wait_command(self, timeout=3.0):
        return wait_for(lambda: self.srv().command, timeout) or ""

    def check_unknown_filtered(self, topic=GESTURE_TOPIC, proof_timeout=10.0):
        """An unknown gesture that reached the node is never returned.

        Proof that it arrived: the node's own warning about it (a new name is warned about at
        once, the same name once per 2 s: 'self_destruct' is sent by this check only). Published
        to a wrong topic, the proof never comes and this check fails
        (test_unknown_check_fails_on_a_wrong_topic).
        """
        mark = self.rosout.mark()
        stays_unchanged(
            lambda: self.srv().command,
            lambda: self.rosout.find("unknown gesture 'self_destruct'", node="/rbd_gestrec", since=mark),
            0.3,
            send=lambda: self.pubs[topic].publish(String("self_destruct")),
            timeout=proof_timeout,
            what="GetLastGesture's command",
            proof="rbd_gestrec rejecting the gesture",
        )

    def test_gesture_once_then_empty(self):
        self.assertEqual(self.srv().command, "")
        self.pubs[GESTURE_TOPIC].publish(String("spin"))
        self.assertEqual(self.wait_command(), "spin")
        self.assertEqual(self.srv().command, "")

    def test_unknown_filtered(self):
        self.check_unknown_filtered()

    def test_unknown_check_fails_on_a_wrong_topic(self):
        with self.assertRaisesRegex(AssertionError, "no proof of rbd_gestrec rejecting the gesture"):
            self.check_unknown_filtered(WRONG_TOPIC, proof_timeout=2.0)

    def test_a_trick_name_of_rbd_navigation_is_accepted(self):
        # launch/rbd_gestrec.launch loads rbd_navigation's tricks.yaml: "bow" has no mapping
        # entry in gestures.yaml, but it is a trick, so a taught gesture's "bow" is understood;
        # "dance" is neither and is dropped (proved by the "spin" behind it coming through alone)
        self.pubs[GESTURE_TOPIC].publish(String("dance"))
        self.pubs[GESTURE_TOPIC].publish(String("bow"))
        self.assertEqual(self.wait_command(), "bow")
        self.pubs[GESTURE_TOPIC].publish(String("dance"))
        self.pubs[GESTURE_TOPIC].publish(String("spin"))
        self.assertEqual(self.wait_command(), "spin")
        self.assertEqual(self.srv().command, "")


if __name__ == "__main__":
    run_rostest("rbd_gestrec", "gestrec_wiring", TestGestrec)
