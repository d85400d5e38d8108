#!/usr/bin/env python3
"""Drives a virtual robot round a square in a known 2D room while people walk nearby.

Odometry (TF odom -> base_link and /odometry/filtered) drifts in scale and heading; scans come
from the true pose. map_correction_node must build the map while the robot stands still, then
keep /rbd_localization/pose on the truth and publish map -> odom and /map at their rates.
"""

import math
import os
import subprocess
import tempfile
import threading
import unittest

import numpy as np
import rospy
import tf2_ros
import yaml
from geometry_msgs.msg import PoseStamped, TransformStamped
from nav_msgs.msg import OccupancyGrid, Odometry
from sensor_msgs.msg import LaserScan
from tf2_msgs.msg import TFMessage

from rbd_geometry.rotation import wrap_angle, yaw_of, yaw_to_quat
from rbd_testkit import wait_for
from rbd_testkit.ros import run_rostest, subscriber_nodes

WALLS = np.array([
    (-3, -2.5, 5, -2.5), (5, -2.5, 5, 3.5), (5, 3.5, -3, 3.5), (-3, 3.5, -3, -2.5),
    (2, 1, 3, 1), (3, 1, 3, 1.6), (3, 1.6, 2, 1.6), (2, 1.6, 2, 1),
    (-2, -1.5, -1.5, -1.5), (-1.5, -1.5, -1.5, -1), (-1.5, -1, -2, -1), (-2, -1, -2, -1.5),
    (3.5, -2.5, 3.5, -1.2), (3.5, -1.2, 4.2, -1.2),
], dtype=float)
BEAMS = 720
STILL = 3.0  # [s] standing still while the map is built
SIDE_V, SIDE_T = 0.4, 3.0  # forward 1.2 m per side
TURN_W = 0.8
TURN_T = (math.pi / 2) / TURN_W
LOOP_T = 4 * (SIDE_T + TURN_T)
SCALE_ERR, YAW_RATE_BIAS = 1.06, 0.03  # odometry drift
LIDAR_X = -0.05  # lidar behind base_link, frame yawed by pi (as the OS1's os_lidar)


def command(t):
    """Return the commanded (v, w) at t seconds after start."""
    if t < STILL or t >= STILL + LOOP_T:
        return 0.0, 0.0
    phase = (t - STILL) % (SIDE_T + TURN_T)
    return (SIDE_V, 0.0) if phase < SIDE_T else (0.0, TURN_W)


def people(t):
    """Return an (N, 3) array of (x, y, r): three people walking back and forth."""
    return np.array([
        (-1.0 + 0.8 * math.sin(0.5 * t), 1.8, 0.25),
        (0.6, -1.6 + 0.5 * math.sin(0.7 * t), 0.25),
        (3.9 + 0.4 * math.sin(0.4 * t), 0.5, 0.22),
    ])


def cast(x, y, yaw, t):
    """Return BEAMS ranges of a planar scan from (x, y) with the beam fan starting at yaw - pi."""
    ang = yaw + (-math.pi + 2 * math.pi * np.arange(BEAMS) / BEAMS)
    d = np.stack([np.cos(ang), np.sin(ang)], axis=1)
    a = WALLS[:, :2]
    e = WALLS[:, 2:] - a
    den = d[:, 0:1] * e[None, :, 1] - d[:, 1:2] * e[None, :, 0]
    ao = a[None, :, :] - np.array([x, y])[None, None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        tt = (ao[:, :, 0] * e[None, :, 1] - ao[:, :, 1] * e[None, :, 0]) / den
        uu = (ao[:, :, 0] * d[:, 1:2] - ao[:, :, 1] * d[:, 0:1]) / den
    hit = (tt > 0) & (uu >= 0) & (uu <= 1) & np.isfinite(tt)
    best = np.where(hit, tt, np.inf).min(axis=1)
    for px, py, r in people(t):
        oc = np.array([x - px, y - py])
        b = d @ oc
        disc = b * b - (oc @ oc - r * r)
        tc = -b - np.sqrt(np.maximum(disc, 0.0))
        best = np.where((disc >= 0) & (tc > 0), np.minimum(best, tc), best)
    return best


class MapCorrectionTest(unittest.TestCase):
    """One scripted drive; the checks read what was recorded."""

    @classmethod
    def setUpClass(cls):
        rospy.init_node("map_correction_test")
        cls.lock = threading.Lock()
        cls.truth = []  # (stamp sec, x, y, yaw)
        cls.poses = []  # (receive sec, PoseStamped)
        cls.map_to_odom = []  # receive sec
        cls.maps = []
        cls.rng = np.random.RandomState(5)
        static = tf2_ros.StaticTransformBroadcaster()
        lidar = TransformStamped()
        lidar.header.stamp = rospy.Time.now()
        lidar.header.frame_id = "base_link"
        lidar.child_frame_id = "os_lidar"
        lidar.transform.translation.x = LIDAR_X
        lidar.transform.translation.z = 0.15
        lidar.transform.rotation.z = 1.0  # yaw pi
        static.sendTransform(lidar)
        cls.static = static
        cls.tf_pub = tf2_ros.TransformBroadcaster()
        cls.odom_pub = rospy.Publisher("/odometry/filtered", Odometry, queue_size=10)
        cls.scan_pub = rospy.Publisher("/scan", LaserScan, queue_size=2)
        rospy.Subscriber("/rbd_localization/pose", PoseStamped, cls.on_pose, queue_size=50)
        rospy.Subscriber("/tf", TFMessage, cls.on_tf, queue_size=100)
        rospy.Subscriber("/map", OccupancyGrid, cls.on_map, queue_size=2)
        wait_for(lambda: cls.scan_pub.get_num_connections() and cls.odom_pub.get_num_connections(), 20.0,
                 what="map_correction_node subscribed")
        # the latched LiDAR mount reaches a subscriber on connection: wait for the node's
        wait_for(lambda: "/map_correction" in subscriber_nodes(static.pub_tf), 20.0,
                 what="map_correction_node's /tf_static connection")
        cls.run_drive()

    @classmethod
    def run_drive(cls):
        rate = rospy.Rate(50)
        start = rospy.Time.now()
        cls.start = start
        x = y = yaw = 0.0  # truth
        ox = oy = oyaw = 0.0  # drifting odometry
        last = start
        k = 0
        while not rospy.is_shutdown():
            now = rospy.Time.now()
            t = (now - start).to_sec()
            if t > STILL + LOOP_T + 2.0:
                break
            dt = (now - last).to_sec()
            last = now
            v, w = command(t)
            x += v * dt * math.cos(yaw)
            y += v * dt * math.sin(yaw)
            yaw += w * dt
            moving = v != 0.0 or w != 0.0
            ov, ow = v * SCALE_ERR, w + (YAW_RATE_BIAS if moving else 0.0)
            ox += ov * dt * math.cos(oyaw)
            oy += ov * dt * math.sin(oyaw)
            oyaw += ow * dt
            with cls.lock:
                cls.truth.append((now.to_sec(), x, y, yaw))
            tf = TransformStamped()
            tf.header.stamp = now
            tf.header.frame_id = "odom"
            tf.child_frame_id = "base_link"
            tf.transform.translation.x, tf.transform.translation.y = ox, oy
            _, _, tf.transform.rotation.z, tf.transform.rotation.w = yaw_to_quat(oyaw)
            cls.tf_pub.sendTransform(tf)
            od = Odometry()
            od.header = tf.header
            od.child_frame_id = "base_link"
            od.pose.pose.position.x, od.pose.pose.position.y = ox, oy
            od.pose.pose.orientation = tf.transform.rotation
            cls.odom_pub.publish(od)
            if k % 5 == 0:  # 10 Hz scans
                lx, ly = x + LIDAR_X * math.cos(yaw), y + LIDAR_X * math.sin(yaw)
                ranges = cast(lx, ly, yaw + math.pi, t) + cls.rng.normal(0.0, 0.015, BEAMS)
                scan = LaserScan()
                scan.header.stamp = now
                scan.header.frame_id = "os_lidar"
                scan.angle_min = -math.pi
                scan.angle_increment = 2 * math.pi / BEAMS
                scan.angle_max = scan.angle_min + (BEAMS - 1) * scan.angle_increment
                scan.range_min, scan.range_max = 0.1, 30.0
                scan.ranges = [float(r) if np.isfinite(r) else float("inf") for r in ranges]
                cls.scan_pub.publish(scan)
            k += 1
            rate.sleep()
        cls.final_odom = (ox, oy, oyaw)

    @classmethod
    def on_pose(cls, msg):
        with cls.lock:
            cls.poses.append((rospy.Time.now().to_sec(), msg))

    @classmethod
    def on_tf(cls, msg):
        for tr in msg.transforms:
            if tr.header.frame_id == "map" and tr.child_frame_id == "odom":
                with cls.lock:
                    cls.map_to_odom.append(rospy.Time.now().to_sec())

    @classmethod
    def on_map(cls, msg):
        with cls.lock:
            cls.maps.append(msg)

    def truth_at(self, stamp):
        times = np.array([tr[0] for tr in self.truth])
        i = int(np.argmin(np.abs(times - stamp)))
        return self.truth[i]

    def pose_error(self, msg):
        _, x, y, yaw = self.truth_at(msg.header.stamp.to_sec())
        dyaw = wrap_angle(yaw_of(msg.pose.orientation) - yaw)
        return math.hypot(msg.pose.position.x - x, msg.pose.position.y - y), abs(dyaw)

    def test_final_pose_is_corrected(self):
        with self.lock:
            poses = list(self.poses)
        self.assertTrue(poses, "no /rbd_localization/pose received")
        last = poses[-1][1]
        self.assertEqual(last.header.frame_id, "map")
        err, dyaw = self.pose_error(last)
        rospy.loginfo("final corrected error %.3f m %.2f deg", err, math.degrees(dyaw))
        self.assertLess(err, 0.05)
        self.assertLess(dyaw, math.radians(1.0))
        # The drift the correction removed was real.
        _, x, y, _ = self.truth[-1]
        self.assertGreater(math.hypot(self.final_odom[0] - x, self.final_odom[1] - y), 0.3)

    def test_pose_stays_close_during_the_drive(self):
        with self.lock:
            poses = [p for t, p in self.poses if p.header.stamp.to_sec() > self.start.to_sec() + STILL + 1.0]
        errs = [self.pose_error(p)[0] for p in poses]
        self.assertGreater(len(errs), 100)
        self.assertLess(max(errs), 0.15, "max error while driving %.3f m" % max(errs))

    def test_output_rates(self):
        end = self.start.to_sec() + STILL + LOOP_T
        with self.lock:
            poses = [t for t, _ in self.poses if end - 5.0 <= t < end]
            tfs = [t for t in self.map_to_odom if end - 5.0 <= t < end]
        self.assertGreaterEqual(len(poses) / 5.0, 10.0, "pose rate %.1f Hz" % (len(poses) / 5.0))
        self.assertGreaterEqual(len(tfs) / 5.0, 20.0, "map->odom rate %.1f Hz" % (len(tfs) / 5.0))

    def test_map_published(self):
        with self.lock:
            maps = list(self.maps)
        self.assertTrue(maps, "no /map")
        m = maps[-1]
        self.assertEqual(m.header.frame_id, "map")
        data = np.array(m.data, dtype=np.int16)
        self.assertEqual(data.size, m.info.width * m.info.height)
        occupied = np.count_nonzero(data > 65)
        free = np.count_nonzero((data >= 0) & (data < 35))
        self.assertGreater(occupied, 200)
        self.assertGreater(free, 2000)
        # Wall cells of the room are occupied, the room's inside is free: west wall at
        # (-3, 0), east wall at (5, -0.5); (1, -0.5) is open floor.
        res = m.info.resolution
        grid = data.reshape(m.info.height, m.info.width)

        def window(x, y):
            cx = int((x - m.info.origin.position.x) / res)
            cy = int((y - m.info.origin.position.y) / res)
            return grid[cy - 1:cy + 2, cx - 1:cx + 2]

        self.assertGreater(window(-3.0, 0.0).max(), 65)
        self.assertGreater(window(5.0, -0.5).max(), 65)
        self.assertTrue(((window(1.0, -0.5) >= 0) & (window(1.0, -0.5) < 35)).all())

    def test_saved_map_read_as_map_server_matches_the_room(self):
        """Save with the save_map tool, read back with map_server's documented semantics."""
        d = tempfile.mkdtemp(prefix="rbd_saved_map_")
        out = subprocess.run(["rosrun", "rbd_localization", "save_map", d, "room"], stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, universal_newlines=True, timeout=60)
        self.assertEqual(out.returncode, 0, out.stdout)
        self.assertEqual(sorted(f for f in os.listdir(d) if not f.startswith(".")),
                         ["room.pgm", "room.rbdmap", "room.yaml"])
        occ, free, xy = read_map_server(os.path.join(d, "room.yaml"))
        ox, oy = xy(np.nonzero(occ))
        self.assertGreater(ox.size, 200)
        dist = wall_distance(ox, oy)
        # Every occupied cell is a wall of the room (cell 5 cm: within 0.1 m), none is a person;
        # 2 % slack for the stray cells of a starved process (8 of 779 in one CI run, 0 in four
        # runs here beside three busy loops): the message lists where they are.
        off = dist >= 0.1
        where = np.round(np.stack([ox[off], oy[off]], 1), 2).tolist()
        self.assertGreaterEqual(np.mean(~off), 0.98, "occupied cells off the walls: %d of %d at %s (m from a wall %s)"
                                % (np.count_nonzero(off), dist.size, where, np.round(dist[off], 2).tolist()))
        for i in range(4):  # each outer wall is there
            near = segment_distance(WALLS[i], ox, oy) < 0.1
            self.assertGreater(np.count_nonzero(near), 40, "outer wall %d missing" % i)
        fx, fy = xy(np.nonzero(free))
        self.assertGreater(fx.size, 2000)
        self.assertGreater(np.min(wall_distance(fx, fy)), 0.0)
        self.assertGreaterEqual(np.mean(wall_distance(fx, fy) > 0.05), 0.99)


def read_map_server(path):
    """Return (occupied, free, cell_to_xy) of a map_server map: map_server's wiki semantics.

    p = (255 - v) / 255 (or v / 255 with negate); occupied if p > occupied_thresh, free if
    p < free_thresh; origin is the lower-left pixel, image row 0 is the top.
    """
    with open(path) as f:
        meta = yaml.safe_load(f)
    img_path = os.path.join(os.path.dirname(path), meta["image"])
    with open(img_path, "rb") as f:
        raw = f.read()
    tokens, pos = [], 0
    while len(tokens) < 4:
        while raw[pos:pos + 1].isspace():
            pos += 1
        if raw[pos:pos + 1] == b"#":
            pos = raw.index(b"\n", pos) + 1
            continue
        end = pos
        while not raw[end:end + 1].isspace():
            end += 1
        tokens.append(raw[pos:end])
        pos = end
    assert tokens[0] == b"P5", tokens
    w, h, maxval = int(tokens[1]), int(tokens[2]), int(tokens[3])
    pix = np.frombuffer(raw[pos + 1:pos + 1 + w * h], dtype=np.uint8).reshape(h, w).astype(float) * 255.0 / maxval
    p = pix / 255.0 if meta.get("negate", 0) else (255.0 - pix) / 255.0
    res = float(meta["resolution"])
    x0, y0 = float(meta["origin"][0]), float(meta["origin"][1])

    def xy(rows_cols):
        rows, cols = rows_cols
        return x0 + (cols + 0.5) * res, y0 + (h - 1 - rows + 0.5) * res

    return p > float(meta["occupied_thresh"]), p < float(meta["free_thresh"]), xy


def segment_distance(seg, x, y):
    """Distance of points (x, y) to one wall segment (x1, y1, x2, y2)."""
    ax, ay, bx, by = seg
    ex, ey = bx - ax, by - ay
    t = np.clip(((x - ax) * ex + (y - ay) * ey) / (ex * ex + ey * ey), 0.0, 1.0)
    return np.hypot(x - ax - t * ex, y - ay - t * ey)


def wall_distance(x, y):
    """Distance of points to the nearest wall of the room."""
    return np.min([segment_distance(w, x, y) for w in WALLS], axis=0)


if __name__ == "__main__":
    run_rostest("rbd_localization", "map_correction_synthetic", MapCorrectionTest)
