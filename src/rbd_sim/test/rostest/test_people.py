#!/usr/bin/env python3
"""rostest: people walk their scripts; markers and the OS1 cloud agree with the world file."""

import math
import os
import unittest

import cloud_check as cc
import numpy as np
import rospkg
import rospy
from sensor_msgs.msg import PointCloud2
from visualization_msgs.msg import Marker, MarkerArray

from rbd_sim.world_file import load_world
from rbd_testkit import wait_for
from rbd_testkit.ros import run_rostest


class TestPeople(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_people")
        cls.world = load_world(os.path.join(rospkg.RosPack().get_path("rbd_sim"), "worlds", "lab.yaml"))
        cls.people = {p.name: p for p in cls.world.people}
        cls.markers = cc.Latest("/rbd_sim/obstacles", MarkerArray, keep=100)
        cls.clouds = cc.Latest("/ouster/points", PointCloud2, keep=10)
        cls.clouds.wait_new(rospy.Time(0), timeout=60.0)
        wait_for(lambda: rospy.has_param("/rbd_sim/world_epoch"), 20.0, 0.1, what="/rbd_sim/world_epoch")
        cls.epoch = float(rospy.get_param("/rbd_sim/world_epoch"))

    def test_markers_follow_the_scripts(self):
        msgs = self.markers.window(2.0)
        self.assertGreater(len(msgs), 10)  # 10 Hz nominal
        self.assertLess(len(msgs), 40)
        seen = set()
        for msg in msgs:
            people = [m for m in msg.markers if m.ns == "people"]
            self.assertEqual(len(people), len(self.people))
            for m in people:
                self.assertEqual((m.type, m.action, m.header.frame_id), (Marker.CYLINDER, Marker.ADD, "world"))
                p = self.people[m.text]
                x, y = p.position(m.header.stamp.to_sec() - self.epoch)
                self.assertAlmostEqual(m.pose.position.x, x, places=6)
                self.assertAlmostEqual(m.pose.position.y, y, places=6)
                self.assertAlmostEqual(m.scale.x, 2 * p.radius)
                self.assertAlmostEqual(m.scale.z, p.height)
                seen.add((m.text, round(x, 2), round(y, 2)))
            statics = [m for m in msg.markers if m.ns == "cylinders"]
            self.assertEqual(sorted(m.text for m in statics), ["bin", "pillar"])
        moved = {name for name, _x, _y in seen}
        self.assertEqual(moved, set(self.people))
        self.assertGreater(len(seen), 2 * len(self.people))  # positions change over time

    def test_lidar_sees_people_where_the_world_puts_them(self):
        meta = cc.metadata()
        checked = 0
        for _ in range(5):
            msg = self.clouds.wait_new(rospy.Time.now())
            pts = cc.decode(msg)
            _alt, az, _o = cc.beam_geometry(meta, msg.width)
            t = msg.header.stamp.to_sec() - self.epoch
            for p in self.people.values():
                x, y = p.position(t)
                col = int(np.argmin(np.abs(np.angle(np.exp(1j * (az[15] - math.atan2(y, x)))))))
                got = float(np.median(pts["range"][14:17, col])) * 1e-3
                self.assertAlmostEqual(got, math.hypot(x, y) - p.radius, delta=0.08, msg="%s at t=%.2f" % (p.name, t))
                checked += 1
        self.assertEqual(checked, 5 * len(self.people))


if __name__ == "__main__":
    run_rostest("rbd_sim", "people", TestPeople)
