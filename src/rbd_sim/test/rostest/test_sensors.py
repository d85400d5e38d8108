#!/usr/bin/env python3
"""rostest: simulated OS1-32, IMU, ZED2 and world on a level robot at the origin.

World test/worlds/box_2m.yaml: a box with its near face at x = 2.0 m (os_sensor is at x = 0),
inside a closed 16 m hall with a 3 m ceiling. Ground truth: base_link at (0, 0, 0.28), level.
"""

import json
import math
import struct
import unittest

import cloud_check as cc
import numpy as np
import rospy
import tf2_ros
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped
from sensor_msgs.msg import CompressedImage, Imu, PointCloud2, PointField
from std_msgs.msg import String
from visualization_msgs.msg import MarkerArray

from rbd_msgs.srv import PlaceObstacle, PlaceObstacleRequest
from rbd_testkit.ros import run_rostest

BASE_Z = 0.28
MOUNT_Z = 0.07
EXPECTED_FIELDS = [
    ("x", 0, PointField.FLOAT32),
    ("y", 4, PointField.FLOAT32),
    ("z", 8, PointField.FLOAT32),
    ("intensity", 16, PointField.FLOAT32),
    ("t", 20, PointField.UINT32),
    ("reflectivity", 24, PointField.UINT16),
    ("ring", 26, PointField.UINT16),
    ("ambient", 28, PointField.UINT16),
    ("range", 32, PointField.UINT32),
]


class TestSensors(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_sensors")
        cls.columns = int(rospy.get_param("~columns", 1024))
        cls.meta = cc.metadata()
        cls.clouds = cc.Latest("/ouster/points", PointCloud2, keep=5)
        cls.imu = cc.Latest("/ouster/imu", Imu, keep=400)
        cls.zed = cc.Latest("/zed2/zed_node/pose", PoseStamped, keep=100)
        cls.zed_cov = cc.Latest("/zed2/zed_node/pose_with_covariance", PoseWithCovarianceStamped, keep=100)
        cls.markers = cc.Latest("/rbd_sim/obstacles", MarkerArray, keep=50)
        cls.camera = cc.Latest("/zed2/zed_node/left/image_rect_color/compressed", CompressedImage, keep=60)
        rospy.wait_for_service("/rbd_sim/place_obstacle", timeout=60.0)
        cls.place = rospy.ServiceProxy("/rbd_sim/place_obstacle", PlaceObstacle)
        cls.first = cls.clouds.wait_new(rospy.Time(0), timeout=60.0)

    def setUp(self):
        """Known state, whatever ran before: none of the obstacles these tests place."""
        for name in ("p1", "close"):
            self.place(PlaceObstacleRequest(name=name, remove=True))  # success=False when absent

    def fresh_cloud(self):
        """A cloud whose scan started after now (so it reflects the world as of now)."""
        return self.clouds.wait_new(rospy.Time.now())

    # -- layout ---------------------------------------------------------------------------
    def test_layout_matches_ouster_ros_byte_for_byte(self):
        msg = self.first
        self.assertEqual(msg.header.frame_id, "os_sensor")
        self.assertEqual(
            [(f.name, f.offset, f.datatype, f.count) for f in msg.fields], [e + (1,) for e in EXPECTED_FIELDS]
        )
        self.assertEqual(msg.point_step, 48)
        self.assertEqual(msg.height, 32)
        self.assertEqual(msg.width, self.columns)
        self.assertEqual(msg.row_step, 48 * self.columns)
        self.assertFalse(msg.is_bigendian)
        self.assertEqual(len(msg.data), msg.row_step * msg.height)
        data = bytes(msg.data)
        w = msg.width
        for row in (0, 15, 31):
            for col in (0, w // 3, w - 1):
                off = (row * w + col) * 48
                x, y, z, pad = struct.unpack_from("<ffff", data, off)
                intensity, t = struct.unpack_from("<fI", data, off + 16)
                refl, ring, amb = struct.unpack_from("<HHH", data, off + 24)
                (rng,) = struct.unpack_from("<I", data, off + 32)
                self.assertEqual(ring, row)  # row-major, row 0 = top beam
                self.assertEqual(pad, 1.0)  # PCL's data[3]
                self.assertAlmostEqual(t, col * 1e9 / (10 * w), delta=1.0)  # column time since the scan stamp
                self.assertGreater(rng, 300)  # every beam returns in this closed hall
                p = np.array([x, y, z])
                self.assertTrue(np.all(np.isfinite(p)))
                self.assertGreaterEqual(intensity, 0.0)
                self.assertGreater(refl, 0)
                self.assertGreater(amb, 0)

    def test_beam_angles_recomputed_from_xyz(self):
        pts = cc.decode(self.first)
        alt, _az, origin = cc.beam_geometry(self.meta, self.columns)
        d = np.stack([pts["x"], pts["y"], pts["z"]], axis=-1).astype(np.float64) - origin[None, :, :]
        d /= np.linalg.norm(d, axis=-1, keepdims=True)
        elev = np.degrees(np.arcsin(d[..., 2]))
        med = np.nanmedian(elev, axis=1)
        np.testing.assert_allclose(med, self.meta["beam_altitude_angles"], atol=0.02)
        # Azimuth offset of each beam (the U0 unit's -4.25 deg), relative to the encoder angle.
        te = 2 * math.pi * (1 - np.arange(self.columns) / float(self.columns))
        ang = np.arctan2(-d[..., 1], -d[..., 0])  # back into the lidar frame (180 deg turn)
        off = np.degrees(np.angle(np.exp(1j * (ang - te[None, :]))))
        np.testing.assert_allclose(np.median(off, axis=1), -np.array(self.meta["beam_azimuth_angles"]), atol=0.02)

    def test_floor_seen_from_mount_height(self):
        pts = cc.decode(self.first)
        z = pts["z"][-1]  # bottom beam (-21.5 deg) hits the floor all around except at the box
        self.assertAlmostEqual(float(np.median(z)), -(BASE_Z + MOUNT_Z), delta=0.02)

    def test_box_two_metres_in_front_in_range_field(self):
        pts = cc.decode(self.fresh_cloud())
        alt, az, origin = cc.beam_geometry(self.meta, self.columns)
        n = self.meta["lidar_origin_to_beam_origin_mm"] * 1e-3
        checked_box = checked_miss = 0
        for row in range(32):
            cols = np.flatnonzero(np.abs(az[row]) < math.radians(1.0))
            self.assertGreater(cols.size, 0)
            for col in cols:
                rng = pts["range"][row, col] * 1e-3
                dx = math.cos(alt[row]) * math.cos(az[row, col])
                s = (2.0 - origin[col, 0]) / dx
                z_hit = origin[col, 2] + BASE_Z + MOUNT_Z + s * math.sin(alt[row])
                if 0.02 < z_hit < 0.98:  # this beam meets the box face
                    self.assertAlmostEqual(rng, s + n, delta=0.05, msg="row %d col %d" % (row, col))
                    if abs(alt[row]) < math.radians(2.0):
                        self.assertAlmostEqual(rng, 2.0, delta=0.05)
                        checked_box += 1
                elif z_hit > 1.02:  # passes over the box to the hall wall or ceiling
                    self.assertGreater(rng, 2.3, msg="row %d col %d passes over the box" % (row, col))
                    checked_miss += 1
                elif z_hit < -0.02:  # meets the floor before the box
                    floor = -(origin[col, 2] + BASE_Z + MOUNT_Z) / math.sin(alt[row]) + n
                    self.assertAlmostEqual(rng, floor, delta=0.05, msg="row %d col %d floor" % (row, col))
                    self.assertLess(rng, 2.0)
                    checked_miss += 1
        self.assertGreater(checked_box, 0)
        self.assertGreater(checked_miss, 0)

    # -- place_obstacle ---------------------------------------------------------------------
    def column_towards(self, angle):
        _alt, az, _o = cc.beam_geometry(self.meta, self.columns)
        return int(np.argmin(np.abs(np.angle(np.exp(1j * (az[15] - angle))))))

    def mid_range(self, msg, angle):
        pts = cc.decode(msg)
        col = self.column_towards(angle)
        return float(np.median(pts["range"][13:18, col])) * 1e-3

    def placed_markers(self, name):
        msg = self.markers.wait_received()
        return [m for m in msg.markers if m.ns == "placed" and m.text == name]

    def test_place_move_remove_obstacle(self):
        left, right = math.pi / 2, -math.pi / 2
        self.assertGreater(self.mid_range(self.fresh_cloud(), left), 7.0)  # the hall wall at 8 m
        res = self.place(PlaceObstacleRequest(name="p1", x=0.0, y=1.5, radius=0.25, height=1.8, remove=False))
        self.assertTrue(res.success, res.message)
        self.assertAlmostEqual(self.mid_range(self.fresh_cloud(), left), 1.25, delta=0.05)
        (m,) = self.placed_markers("p1")
        self.assertAlmostEqual(m.pose.position.y, 1.5)
        self.assertAlmostEqual(m.scale.x, 0.5)
        self.assertAlmostEqual(m.scale.z, 1.8)
        self.assertEqual(m.header.frame_id, "world")

        res = self.place(PlaceObstacleRequest(name="p1", x=0.0, y=-2.0, radius=0.25, height=1.8, remove=False))
        self.assertTrue(res.success, res.message)
        cloud = self.fresh_cloud()
        self.assertAlmostEqual(self.mid_range(cloud, right), 1.75, delta=0.05)
        self.assertGreater(self.mid_range(cloud, left), 7.0)

        res = self.place(PlaceObstacleRequest(name="p1", remove=True))
        self.assertTrue(res.success, res.message)
        self.assertGreater(self.mid_range(self.fresh_cloud(), right), 7.0)
        self.assertEqual(self.placed_markers("p1"), [])

    def test_bad_obstacle_requests_rejected(self):
        res = self.place(PlaceObstacleRequest(name="bad", x=1.0, y=1.0, radius=-0.2, height=1.0, remove=False))
        self.assertFalse(res.success)
        self.assertIn("radius", res.message)
        res = self.place(PlaceObstacleRequest(name="bad", x=float("nan"), y=1.0, radius=0.2, height=1.0, remove=False))
        self.assertFalse(res.success)
        res = self.place(PlaceObstacleRequest(name="never_placed", remove=True))
        self.assertFalse(res.success)
        self.assertIn("no such obstacle", res.message)

    def test_returns_closer_than_min_range_read_zero_and_nan(self):
        res = self.place(PlaceObstacleRequest(name="close", x=-0.3, y=0.0, radius=0.12, height=1.0, remove=False))
        self.assertTrue(res.success, res.message)
        try:
            msg = self.fresh_cloud()
            pts = cc.decode(msg)
            col = self.column_towards(math.pi)
            rows = slice(10, 22)
            self.assertTrue(np.all(pts["range"][rows, col] == 0))
            self.assertTrue(np.all(np.isnan(pts["x"][rows, col])))
            self.assertFalse(msg.is_dense)
        finally:
            self.place(PlaceObstacleRequest(name="close", remove=True))

    # -- IMU, ZED2, metadata, TF ------------------------------------------------------------
    def test_imu_level_reads_gravity_and_no_orientation(self):
        msgs = self.imu.window(2.0)
        self.assertGreater(len(msgs), 100)  # 100 Hz nominal; loose bound for a loaded machine
        self.assertLess(len(msgs), 300)
        for m in msgs:
            self.assertEqual(m.header.frame_id, "os_imu")
            self.assertEqual(list(m.orientation_covariance), [-1.0] * 9)
            self.assertEqual((m.orientation.x, m.orientation.y, m.orientation.z, m.orientation.w), (0, 0, 0, 1))
        acc = np.array([[m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z] for m in msgs])
        gyro = np.array([[m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z] for m in msgs])
        self.assertAlmostEqual(acc[:, 2].mean(), 9.80665, delta=0.3)
        self.assertLess(np.abs(acc[:, :2].mean(axis=0)).max(), 0.3)
        self.assertLess(np.abs(gyro.mean(axis=0)).max(), 0.02)
        self.assertGreater(acc[:, 2].std(), 0.001)  # noisy, not a constant

    def test_zed2_pose_in_map_near_truth(self):
        msgs = self.zed.window(2.0)
        self.assertGreater(len(msgs), 15)  # 15 Hz nominal
        self.assertLess(len(msgs), 45)
        for m in msgs:
            self.assertEqual(m.header.frame_id, "map")
            self.assertLess(math.hypot(m.pose.position.x, m.pose.position.y), 0.5)
            self.assertAlmostEqual(m.pose.position.z, BASE_Z, delta=0.2)
        cov = self.zed_cov.wait_new(rospy.Time.now())
        self.assertEqual(cov.header.frame_id, "map")
        c = np.array(cov.pose.covariance).reshape(6, 6)
        self.assertTrue(np.all(np.diag(c) > 0))

    def test_zed2_left_image_compressed_jpeg(self):
        import cv2  # decodes the bytes on its own: the JPEG standard is the truth here

        self.camera.wait_new(rospy.Time.now())
        msgs = self.camera.window(2.0)
        self.assertGreater(len(msgs), 15)  # 15 Hz nominal (the ZED wrapper's pub_frame_rate)
        self.assertLess(len(msgs), 45)
        stamps = [m.header.stamp.to_sec() for m in msgs]
        self.assertTrue(all(b > a for a, b in zip(stamps, stamps[1:])), stamps)
        for m in msgs[:3]:
            self.assertEqual(m.header.frame_id, "zed2_left_camera_optical_frame")
            self.assertIn("jpeg", m.format)
            img = cv2.imdecode(np.frombuffer(bytes(m.data), np.uint8), cv2.IMREAD_COLOR)
            self.assertIsNotNone(img)
            self.assertEqual(img.shape, (376, 672, 3))  # the ZED2's VGA mode (placeholder scene)

    def test_metadata_latched(self):
        msg = rospy.wait_for_message("/ouster/metadata", String, timeout=10.0)
        meta = json.loads(msg.data)
        self.assertEqual(meta["lidar_mode"], "%dx10" % self.columns)
        self.assertEqual(meta["beam_altitude_angles"], self.meta["beam_altitude_angles"])
        self.assertEqual(meta["prod_line"], "OS-1-32-U0")

    def test_static_transforms(self):
        buf = tf2_ros.Buffer()
        tf2_ros.TransformListener(buf)
        expect = {
            ("base_link", "os_sensor"): ((0.0, 0.0, MOUNT_Z), (0, 0, 0, 1)),
            ("os_sensor", "os_lidar"): ((0.0, 0.0, 0.03618), (0, 0, 1, 0)),
            ("os_sensor", "os_imu"): ((0.006253, -0.011775, 0.007645), (0, 0, 0, 1)),
        }
        for (parent, child), (xyz, q) in expect.items():
            tf = buf.lookup_transform(parent, child, rospy.Time(0), rospy.Duration(10.0))
            t, r = tf.transform.translation, tf.transform.rotation
            np.testing.assert_allclose([t.x, t.y, t.z], xyz, atol=1e-6)
            got = np.array([r.x, r.y, r.z, r.w])
            self.assertAlmostEqual(abs(float(np.dot(got, q))), 1.0, places=6)


if __name__ == "__main__":
    run_rostest("rbd_sim", "sensors", TestSensors)
