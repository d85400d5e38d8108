#!/usr/bin/env python3
"""rostest: the body pose from /rbd_sim/ground_truth moves the sensor (512 x 20 Hz).

This test node is the ground-truth source: it publishes a level pose, then pitched, rolled and
lowered ones, and checks where the floor appears in the bottom beams' range field against the
geometry of the mount (base_link -> os_sensor = (0, 0, 0.07)).
"""

import math
import threading
import unittest

import cloud_check as cc
import numpy as np
import rospy
from nav_msgs.msg import Odometry
from sensor_msgs.msg import PointCloud2

from rbd_geometry.rotation import rpy_to_matrix, rpy_to_quat
from rbd_testkit.ros import run_rostest

MOUNT = np.array([0.0, 0.0, 0.07])


class TestTilt(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_sensors_tilt")
        cls.meta = cc.metadata()
        cls.pose = [0.0, 0.0, 0.28, 0.0, 0.0, 0.0]
        cls.lock = threading.Lock()
        cls.pub = rospy.Publisher("/rbd_sim/ground_truth", Odometry, queue_size=10)
        cls.timer = rospy.Timer(rospy.Duration(0.01), cls.publish)
        cls.clouds = cc.Latest("/ouster/points", PointCloud2, keep=5)
        cls.clouds.wait_new(rospy.Time(0), timeout=60.0)

    @classmethod
    def publish(cls, _event):
        with cls.lock:
            x, y, z, r, p, yaw = cls.pose
        msg = Odometry()
        msg.header.stamp = rospy.Time.now()
        msg.header.frame_id, msg.child_frame_id = "world", "base_link_gt"
        msg.pose.pose.position.x, msg.pose.pose.position.y, msg.pose.pose.position.z = x, y, z
        o = msg.pose.pose.orientation
        o.x, o.y, o.z, o.w = rpy_to_quat(r, p, yaw)
        try:
            cls.pub.publish(msg)
        except rospy.ROSException:  # shutting down
            pass

    @classmethod
    def tearDownClass(cls):
        cls.timer.shutdown()

    def cloud_at(self, pose):
        with self.lock:
            type(self).pose = list(pose)
        rospy.sleep(0.1)  # let the new pose reach os1_sim before the next scan starts
        return self.clouds.wait_new(rospy.Time.now())

    def expected_floor_range(self, pose, row, col, width):
        """Range [m] at which beam (row, col) meets the floor z = 0 for this base pose."""
        alt, az, origin = cc.beam_geometry(self.meta, width)
        n = self.meta["lidar_origin_to_beam_origin_mm"] * 1e-3
        d_s = np.array(
            [
                math.cos(alt[row]) * math.cos(az[row, col]),
                math.cos(alt[row]) * math.sin(az[row, col]),
                math.sin(alt[row]),
            ]
        )
        rot = rpy_to_matrix(*pose[3:])
        o = np.array(pose[:3]) + rot.dot(MOUNT + origin[col])
        d = rot.dot(d_s)
        self.assertLess(d[2], 0.0)
        return -o[2] / d[2] + n

    def floor_ranges(self, pose):
        msg = self.cloud_at(pose)
        self.assertEqual((msg.height, msg.width), (32, 512))
        pts = cc.decode(msg)
        _alt, az, _o = cc.beam_geometry(self.meta, msg.width)
        out = {}
        for name, angle in (("front", 0.0), ("back", math.pi), ("left", math.pi / 2), ("right", -math.pi / 2)):
            col = int(np.argmin(np.abs(np.angle(np.exp(1j * (az[31] - angle))))))
            for row in (29, 30, 31):
                got = pts["range"][row, col] * 1e-3
                want = self.expected_floor_range(pose, row, col, msg.width)
                self.assertAlmostEqual(got, want, delta=0.05, msg="%s row %d pose %s" % (name, row, pose))
            out[name] = pts["range"][31, col] * 1e-3
        return out, msg

    def test_body_pose_moves_the_floor(self):
        level, msg = self.floor_ranges([0.0, 0.0, 0.28, 0.0, 0.0, 0.0])
        self.assertAlmostEqual(msg.fields[-1].offset, 32)
        t = cc.decode(msg)["t"]
        self.assertAlmostEqual(t[0, -1], 511 * 1e9 / (20 * 512), delta=1.0)  # 20 Hz scan period
        self.assertAlmostEqual(level["front"], level["back"], delta=0.08)

        pitched, _ = self.floor_ranges([0.0, 0.0, 0.28, 0.0, 0.2, 0.0])  # nose down
        self.assertLess(pitched["front"], level["front"] - 0.25)
        self.assertGreater(pitched["back"], level["back"] + 0.5)

        rolled, _ = self.floor_ranges([0.0, 0.0, 0.28, 0.2, 0.0, 0.0])  # left side up
        self.assertGreater(rolled["left"], level["left"] + 0.5)
        self.assertLess(rolled["right"], level["right"] - 0.25)

        lowered, _ = self.floor_ranges([0.0, 0.0, 0.18, 0.0, 0.0, 0.0])  # body lowered by 10 cm
        for side in ("front", "back", "left", "right"):
            self.assertLess(lowered[side], level[side] - 0.15)

        moved, _ = self.floor_ranges([1.0, -0.5, 0.28, 0.0, 0.0, 1.0])  # elsewhere, turned
        self.assertAlmostEqual(moved["front"], level["front"], delta=0.08)

        # Bad input: a NaN ground truth is ignored; the sensor keeps scanning from the last good pose.
        msg = self.cloud_at([float("nan"), 0.0, 0.28, 0.0, 0.0, 0.0])
        msg = self.clouds.wait_new(msg.header.stamp)
        pts = cc.decode(msg)
        _alt, az, _o = cc.beam_geometry(self.meta, msg.width)
        col = int(np.argmin(np.abs(np.angle(np.exp(1j * az[31])))))
        self.assertAlmostEqual(pts["range"][31, col] * 1e-3, moved["front"], delta=0.08)


if __name__ == "__main__":
    run_rostest("rbd_sim", "sensors_tilt", TestTilt)
