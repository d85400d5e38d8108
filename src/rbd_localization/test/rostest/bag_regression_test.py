#!/usr/bin/env python3
"""Bag regression (as robot_localization's bag tests): the final corrected pose after playing a
bag recorded from the seeded simulator must be within `tolerance` of the true final pose
(`final_x`, `final_y`, `final_yaw` test parameters, taken from the simulator's ground truth).
"""

import math
import threading
import time
import unittest

import rosbag
import rospy
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry

from rbd_geometry.rotation import yaw_of
from rbd_testkit import wait_for
from rbd_testkit.ros import run_rostest


class BagRegressionTest(unittest.TestCase):
    """Wait for the bag to end, then compare the last pose."""

    def test_final_pose(self):
        rospy.init_node("bag_regression_test")
        final_x = rospy.get_param("~final_x")
        final_y = rospy.get_param("~final_y")
        final_yaw = rospy.get_param("~final_yaw")
        tolerance = rospy.get_param("~tolerance")
        yaw_tolerance = math.radians(rospy.get_param("~yaw_tolerance_deg", 1.0))
        bag_duration = rospy.get_param("~bag_duration")
        bag_path = rospy.get_param("~bag", "")
        lock = threading.Lock()
        last = {}

        def on_pose(msg):
            with lock:
                last["pose"] = msg

        def on_odom(msg):
            with lock:
                last["odom"] = msg

        rospy.Subscriber("/rbd_localization/pose", PoseStamped, on_pose)
        rospy.Subscriber("/odometry/filtered", Odometry, on_odom)
        # Sim time from the bag (/clock): wait until it has played to its end. The end is the
        # bag's own last stamp (this node may start after the first /clock under load).
        wall_end = time.time() + 3 * bag_duration + 60.0
        wait_for(lambda: rospy.get_time() > 0.0, wall_end - time.time(), 0.1, abort=rospy.is_shutdown)
        if bag_path:
            with rosbag.Bag(bag_path) as bag:
                deadline = bag.get_end_time() - 0.3
        else:
            deadline = rospy.get_time() + bag_duration - 0.5
        wait_for(lambda: rospy.get_time() >= deadline, max(0.0, wall_end - time.time()), 0.1, abort=rospy.is_shutdown)
        with lock:
            self.assertIn("pose", last, "no /rbd_localization/pose")
            pose = last["pose"].pose
        q = pose.orientation
        yaw = yaw_of(q)
        err = math.hypot(pose.position.x - final_x, pose.position.y - final_y)
        dyaw = abs(math.atan2(math.sin(yaw - final_yaw), math.cos(yaw - final_yaw)))
        rospy.loginfo("bag final error %.3f m %.2f deg", err, math.degrees(dyaw))
        self.assertLess(err, tolerance)
        self.assertLess(dyaw, yaw_tolerance)


if __name__ == "__main__":
    run_rostest("rbd_localization", "bag_regression", BagRegressionTest)
