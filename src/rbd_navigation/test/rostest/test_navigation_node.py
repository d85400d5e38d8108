#!/usr/bin/env python3
"""rostest: /rbd_navigation/generate_path answers around the current pose; unknown => no poses."""

import math
import unittest

import rospy
from geometry_msgs.msg import PoseStamped

from rbd_geometry.rotation import yaw_of, yaw_to_quat
from rbd_msgs.srv import GeneratePath
from rbd_testkit import wait_for
from rbd_testkit.ros import run_rostest


class TestNavigation(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_navigation", anonymous=True)
        rospy.wait_for_service("/rbd_navigation/generate_path", timeout=60.0)
        cls.srv = rospy.ServiceProxy("/rbd_navigation/generate_path", GeneratePath)
        cls.pub = rospy.Publisher("/test/pose", PoseStamped, queue_size=1)
        # Before any test publishes a pose: the node's answer without one.
        cls.no_pose = cls.srv(command="walk")

    def publish_pose(self, x, y, yaw):
        msg = PoseStamped()
        msg.header.frame_id = "map"
        msg.pose.position.x, msg.pose.position.y = x, y
        o = msg.pose.orientation
        o.x, o.y, o.z, o.w = yaw_to_quat(yaw)
        wait_for(lambda: self.pub.get_num_connections() > 0, 10.0, what="rbd_navigation subscribed to the pose")

        def taken():
            # the proof the node has this pose: "walk" starts 0.6 m ahead of it
            self.pub.publish(msg)
            res = self.srv(command="walk")
            p = res.poses[0].position if res.success else None
            return p and math.hypot(p.x - x - 0.6 * math.cos(yaw), p.y - y - 0.6 * math.sin(yaw)) < 1e-6

        wait_for(taken, 10.0, 0.05, what="rbd_navigation using the pose (%.2f, %.2f, %.2f)" % (x, y, yaw))

    def test_no_pose_no_path(self):
        res = self.no_pose
        self.assertFalse(res.success)
        self.assertIn("pose", res.message)
        self.assertEqual(res.count, 0)

    def test_walk_relative_to_pose(self):
        self.publish_pose(1.0, 2.0, math.pi / 2)
        res = self.srv(command="walk")
        self.assertTrue(res.success, res.message)
        self.assertEqual(res.count, len(res.poses))
        self.assertEqual(len(res.names), res.count)
        self.assertTrue(all(res.names))
        first = res.poses[0]
        self.assertAlmostEqual(first.position.x, 1.0, places=6)
        self.assertAlmostEqual(first.position.y, 2.6, places=6)
        o = first.orientation
        self.assertAlmostEqual(yaw_of(o), math.pi / 2, places=6)

    def test_unknown_command(self):
        self.publish_pose(0.0, 0.0, 0.0)
        res = self.srv(command="fly")
        self.assertFalse(res.success)
        self.assertIn("unknown command", res.message)
        self.assertIn("walk", res.message)
        self.assertEqual((res.count, len(res.poses), len(res.names)), (0, 0, 0))

    def test_body_pose_tricks(self):
        self.publish_pose(0.0, 0.0, 0.0)
        res = self.srv(command="lie_down")
        self.assertTrue(res.success)
        self.assertAlmostEqual(res.poses[0].position.z, -0.16, places=6)


if __name__ == "__main__":
    run_rostest("rbd_navigation", "navigation_wiring", TestNavigation)
