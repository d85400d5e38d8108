#!/usr/bin/env python3
"""Feeds ekf_localization_node a synthetic IMU (frame os_imu) and ZED pose on a known circle.

Checks, against the analytic truth: odometry/filtered tracks the circle, a persistent 1 m ZED
jump is gated (the estimate does not jump), a silent ZED is reported stale on /diagnostics,
and the estimate stops when every sensor is silent.
"""

import math
import random
import threading
import unittest

import rospy
import tf2_ros
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseWithCovarianceStamped, TransformStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu

from rbd_geometry.rotation import yaw_to_quat
from rbd_testkit import wait_for
from rbd_testkit.ros import run_rostest, subscriber_nodes

V = 0.3  # forward speed [m/s]
W = 0.25  # yaw rate [rad/s]
G = 9.80665
JUMP_AT = 8.0  # [s] after start the ZED jumps +1 m in x ...
JUMP_END = 9.5  # [s] ... until it relocalises
POSE_STOP_AT = 14.0  # [s] ZED goes silent
IMU_STOP_AT = 18.0  # [s] IMU goes silent
END_AT = IMU_STOP_AT + 3.0  # [s] the script ends: every sensor silent for 3 s
# base_link -> os_sensor: mount yawed by +90 deg (exercises the frame rotation of the IMU data).
MOUNT_YAW = math.pi / 2


def truth(t):
    """Return the true (x, y, yaw) of base_link at t seconds after start."""
    yaw = W * t
    return V / W * math.sin(yaw), V / W * (1.0 - math.cos(yaw)), yaw


class Feeder:
    """Publishes the synthetic sensors from a thread."""

    def __init__(self):
        self.imu_pub = rospy.Publisher("/ouster/imu", Imu, queue_size=50)
        self.pose_pub = rospy.Publisher("/zed2/zed_node/pose_with_covariance", PoseWithCovarianceStamped, queue_size=5)
        self.rng = random.Random(4)
        self.start = None
        self.stop = False
        self.thread = threading.Thread(target=self.run)
        self.thread.daemon = True

    def run(self):
        rate = rospy.Rate(100)
        k = 0
        while not rospy.is_shutdown() and not self.stop:
            now = rospy.Time.now()
            t = (now - self.start).to_sec()
            if t >= END_AT:
                break
            if t < IMU_STOP_AT:
                self.imu_pub.publish(self.imu(now))
            if t < POSE_STOP_AT and k % 7 == 0:  # ~14 Hz
                self.pose_pub.publish(self.pose(now, t))
            k += 1
            rate.sleep()

    def imu(self, stamp):
        msg = Imu()
        msg.header.stamp = stamp
        msg.header.frame_id = "os_imu"
        msg.orientation.w = 1.0
        msg.orientation_covariance[0] = -1.0
        # Body: yaw rate W; specific force = centripetal V*W along +y plus gravity reaction +z.
        # Rotate into the IMU frame (yawed by MOUNT_YAW): v_imu = Rz(-MOUNT_YAW) v_body.
        c, s = math.cos(-MOUNT_YAW), math.sin(-MOUNT_YAW)
        fx, fy = 0.0, V * W
        msg.linear_acceleration.x = c * fx - s * fy + self.rng.gauss(0.0, 0.02)
        msg.linear_acceleration.y = s * fx + c * fy + self.rng.gauss(0.0, 0.02)
        msg.linear_acceleration.z = G + self.rng.gauss(0.0, 0.02)
        msg.angular_velocity.z = W + self.rng.gauss(0.0, 0.005)
        for i in (0, 4, 8):
            msg.linear_acceleration_covariance[i] = 0.01
            msg.angular_velocity_covariance[i] = 6e-4
        return msg

    def pose(self, stamp, t):
        x, y, yaw = truth(t)
        if JUMP_AT <= t < JUMP_END:
            x += 1.0
        msg = PoseWithCovarianceStamped()
        msg.header.stamp = stamp
        msg.header.frame_id = "map"
        msg.pose.pose.position.x = x + self.rng.gauss(0.0, 0.003)
        msg.pose.pose.position.y = y + self.rng.gauss(0.0, 0.003)
        q = yaw_to_quat(yaw + self.rng.gauss(0.0, 0.002))
        msg.pose.pose.orientation.x, msg.pose.pose.orientation.y = q[0], q[1]
        msg.pose.pose.orientation.z, msg.pose.pose.orientation.w = q[2], q[3]
        for i, var in zip((0, 7, 14, 21, 28, 35), (1e-4, 1e-4, 1e-4, 1e-5, 1e-5, 1e-5)):
            msg.pose.covariance[i] = var
        return msg


class EkfSyntheticTest(unittest.TestCase):
    """One scripted run; the checks read what was recorded."""

    @classmethod
    def setUpClass(cls):
        rospy.init_node("ekf_synthetic_test")
        cls.lock = threading.Lock()
        cls.odoms = []  # (receive time since start, msg)
        cls.diag = []  # (receive time since start, sensor name, level, message)
        broadcaster = tf2_ros.StaticTransformBroadcaster()
        mount = TransformStamped()
        mount.header.stamp = rospy.Time.now()
        mount.header.frame_id = "base_link"
        mount.child_frame_id = "os_sensor"
        mount.transform.translation.z = 0.1
        q = yaw_to_quat(MOUNT_YAW)
        mount.transform.rotation.z, mount.transform.rotation.w = q[2], q[3]
        imu_tf = TransformStamped()
        imu_tf.header.stamp = mount.header.stamp
        imu_tf.header.frame_id = "os_sensor"
        imu_tf.child_frame_id = "os_imu"
        imu_tf.transform.translation.x = 0.006
        imu_tf.transform.rotation.w = 1.0
        broadcaster.sendTransform([mount, imu_tf])
        cls.broadcaster = broadcaster
        cls.feeder = Feeder()
        rospy.Subscriber("/odometry/filtered", Odometry, cls.on_odom, queue_size=50)
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls.on_diag, queue_size=20)
        wait_for(lambda: cls.feeder.imu_pub.get_num_connections() and cls.feeder.pose_pub.get_num_connections(),
                 20.0, what="ekf_localization_node subscribed")
        # The latched mount reaches a subscriber on connection: wait for the EKF's connection.
        wait_for(lambda: "/ekf_localization" in subscriber_nodes(broadcaster.pub_tf), 20.0,
                 what="ekf_localization_node's /tf_static connection")
        cls.feeder.start = rospy.Time.now()
        cls.feeder.thread.start()
        cls.feeder.thread.join(IMU_STOP_AT + 30.0)  # the feeder ends its script itself (END_AT)
        assert not cls.feeder.thread.is_alive(), "the feeder did not end its script"

    @classmethod
    def on_odom(cls, msg):
        if cls.feeder.start is None:
            return
        with cls.lock:
            cls.odoms.append(((rospy.Time.now() - cls.feeder.start).to_sec(), msg))

    @classmethod
    def on_diag(cls, msg):
        if cls.feeder.start is None:
            return
        t = (rospy.Time.now() - cls.feeder.start).to_sec()
        with cls.lock:
            for st in msg.status:
                for name in ("imu0", "pose0"):
                    if name in st.name:
                        cls.diag.append((t, name, ord(st.level) if isinstance(st.level, bytes) else st.level,
                                         st.message))

    def errors(self, t_from, t_to):
        out = []
        with self.lock:
            odoms = list(self.odoms)
        for _, msg in odoms:
            t = (msg.header.stamp - self.feeder.start).to_sec()
            if t_from <= t <= t_to:
                x, y, yaw = truth(t)
                p = msg.pose.pose
                est_yaw = 2.0 * math.atan2(p.orientation.z, p.orientation.w)
                dyaw = math.atan2(math.sin(est_yaw - yaw), math.cos(est_yaw - yaw))
                out.append((math.hypot(p.position.x - x, p.position.y - y), abs(dyaw), t))
        return out

    def test_tracks_the_circle(self):
        errs = self.errors(1.0, JUMP_AT - 0.1)
        self.assertGreater(len(errs), 100, "too few odometry/filtered messages")
        worst = max(errs)
        self.assertLess(worst[0], 0.10, "position error %.3f m at t=%.2f" % (worst[0], worst[2]))
        self.assertLess(max(e[1] for e in errs), math.radians(3.0))
        with self.lock:
            frame_ids = set((m.header.frame_id, m.child_frame_id) for _, m in self.odoms)
        self.assertEqual(frame_ids, {("odom", "base_link")})

    def test_zed_jump_is_gated(self):
        errs = self.errors(JUMP_AT, POSE_STOP_AT)
        self.assertGreater(len(errs), 100)
        worst = max(errs)
        series = " ".join("%.1f:%.2f" % (e[2], e[0]) for e in errs[::10])
        # Followed, the jump would put the estimate 1 m off.
        self.assertLess(worst[0], 0.15,
                        "estimate followed the jump: %.3f m at t=%.2f; %s" % (worst[0], worst[2], series))
        with self.lock:
            rejected = [d for d in self.diag if d[1] == "pose0" and "rejected" in d[3] and d[0] >= JUMP_AT]
        self.assertTrue(rejected, "no 'rejected' diagnostic for pose0 after the jump")

    def test_silent_zed_is_stale_in_diagnostics(self):
        with self.lock:
            before = [d for d in self.diag if d[1] == "pose0" and 2.0 < d[0] < JUMP_AT]
            after = [d for d in self.diag if d[1] == "pose0" and POSE_STOP_AT + 2.6 < d[0] < IMU_STOP_AT]
            imu_ok = [d for d in self.diag if d[1] == "imu0" and POSE_STOP_AT + 2.6 < d[0] < IMU_STOP_AT]
        self.assertTrue(before and all(d[2] == DiagnosticStatus.OK for d in before), before)
        self.assertTrue(after, "no diagnostics after the ZED stopped")
        self.assertTrue(all(d[2] == DiagnosticStatus.ERROR and "stale" in d[3] for d in after), after)
        self.assertTrue(imu_ok and all(d[2] == DiagnosticStatus.OK for d in imu_ok), imu_ok)

    def test_estimate_stops_when_all_sensors_are_silent(self):
        with self.lock:
            late = [t for t, _ in self.odoms if t > IMU_STOP_AT + 1.5]
            during = [t for t, _ in self.odoms if POSE_STOP_AT < t < IMU_STOP_AT]
        self.assertGreater(len(during), 20, "odometry stopped while the IMU was still alive")
        self.assertEqual(late, [], "odometry still published %d times after every sensor stopped" % len(late))


if __name__ == "__main__":
    run_rostest("rbd_localization", "ekf_synthetic", EkfSyntheticTest)
