#!/usr/bin/env python3
"""rostest: the position controller node drives the kinematic robot; stops on e-stop, stale pose."""

import math
import threading
import time
import unittest

import rospy
from geometry_msgs.msg import Pose, Pose2D, PoseStamped, Twist, Vector3
from std_msgs.msg import Float32, String
from std_srvs.srv import SetBool

from rbd_geometry.rotation import rpy_to_quat, yaw_of
from rbd_msgs.srv import FollowPath, SetPosition
from rbd_testkit import stays_unchanged, wait_for
from rbd_testkit.ros import messages_received, run_rostest

PERIOD = 1.0 / 20.0  # the controller's rate


def make_pose(x, y, yaw, roll=0.0, pitch=0.0, z=0.0):
    pose = Pose()
    pose.position.x, pose.position.y, pose.position.z = x, y, z
    o = pose.orientation
    o.x, o.y, o.z, o.w = rpy_to_quat(roll, pitch, yaw)
    return pose


class Recorder:
    def __init__(self):
        self.lock = threading.Lock()
        self.truth = None
        self.n_truth = 0  # ground-truth poses received (a window proves the pose kept coming)
        self.cmds = []  # (receipt time, Twist)
        self.status = []
        self.body = None
        rospy.Subscriber("/rbd_sim/ground_truth_pose", PoseStamped, self.on_truth)
        rospy.Subscriber("/cmd_vel", Twist, self.on_cmd)
        rospy.Subscriber("/rbd_pos_controller/status", String, lambda m: self.status.append(m.data))
        rospy.Subscriber("/kinematic_robot/body_pose", Vector3, self.on_body)

    def on_truth(self, msg):
        with self.lock:
            self.truth = msg.pose
            self.n_truth += 1

    def on_cmd(self, msg):
        with self.lock:
            self.cmds.append((time.monotonic(), msg))

    def on_body(self, msg):
        self.body = msg

    def xy_yaw(self):
        with self.lock:
            p = self.truth
        return p.position.x, p.position.y, yaw_of(p.orientation)


class TestPosController(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_pos_controller", anonymous=True)
        cls.rec = Recorder()
        for name in (
            "/rbd_pos_controller/set_position",
            "/rbd_pos_controller/emergency",
            "/kinematic_robot/pause_pose",
            "/rbd_pos_controller/follow_path",
        ):
            rospy.wait_for_service(name, timeout=60.0)
        cls.set_position = rospy.ServiceProxy("/rbd_pos_controller/set_position", SetPosition)
        cls.emergency = rospy.ServiceProxy("/rbd_pos_controller/emergency", SetBool)
        cls.pause = rospy.ServiceProxy("/kinematic_robot/pause_pose", SetBool)
        cls.follow_path = rospy.ServiceProxy("/rbd_pos_controller/follow_path", FollowPath)
        cls.scale_pub = rospy.Publisher("/rbd_lidar/speed_scale", Float32, queue_size=1, latch=True)
        assert wait_for(lambda: cls.rec.truth is not None and cls.rec.status, 30.0)
        # Our own pose subscription may connect before the controller's (CI: the first goal was
        # refused, "no robot pose received"): wait until it takes a goal at the robot's own pose.
        assert wait_for(cls.controller_has_pose, 30.0, 0.2), "the controller never received a pose"

    @classmethod
    def controller_has_pose(cls):
        x, y, yaw = cls.rec.xy_yaw()
        res = cls.set_position(pose=make_pose(x, y, yaw))
        assert res.accepted or "no robot pose" in res.message, res.message
        return res.accepted

    def setUp(self):
        """Known state, whatever ran before: no emergency, pose flowing, full speed, controller idle."""
        self.emergency(data=False)
        self.pause(data=False)
        self.scale_pub.publish(Float32(1.0))
        self.assertTrue(wait_for(self.idle, 40.0), "not idle, status %s" % self.rec.status[-3:])

    def idle(self):
        return self.rec.status and self.rec.status[-1] == "idle"

    def go(self, pose, timeout=40.0):
        res = self.set_position(pose=pose)
        self.assertTrue(res.accepted, res.message)
        self.assertTrue(wait_for(lambda: self.rec.status[-1] == "running", 5.0))
        self.assertTrue(wait_for(self.idle, timeout), "goal not reached, status %s" % self.rec.status[-3:])

    def last_cmd_after(self, t0):
        with self.rec.lock:
            return [m for t, m in self.rec.cmds if t > t0]

    def assert_robot_stopped(self, window=0.5):
        """The ground truth stays within 5 mm / 5 mrad for ``window`` s, while fresh poses keep coming.

        A pose that stopped coming (a stale stand-in) would look like a robot at rest: the check
        first waits for a pose newer than the baseline, and at the end asserts poses arrived during
        the window too (the stand-in sends 25 Hz).
        """
        x0, y0, yaw0 = self.rec.xy_yaw()
        n0 = self.rec.n_truth

        def still():
            x1, y1, yaw1 = self.rec.xy_yaw()
            return math.hypot(x1 - x0, y1 - y0) < 0.005 and abs(yaw1 - yaw0) < 0.005

        stays_unchanged(still, lambda: self.rec.n_truth > n0, hold=window, timeout=5.0,
                        what="the robot at rest", proof="a fresh ground-truth pose")
        n1 = self.rec.n_truth
        self.assertGreaterEqual(n1 - n0, 1 + int(window * 25 / 2), "ground truth stopped coming during the window")

    def test_reaches_goal_with_body_pose(self):
        self.go(make_pose(0.6, 0.3, 1.2, pitch=0.1, z=-0.05))
        x, y, yaw = self.rec.xy_yaw()
        self.assertLess(math.hypot(x - 0.6, y - 0.3), 0.03)
        self.assertLess(abs(yaw - 1.2), math.radians(2.0))
        self.assertAlmostEqual(self.rec.body.y, 0.1, places=3)
        self.assertAlmostEqual(self.rec.body.z, -0.05, places=3)
        # idle means zero velocity
        t0 = time.monotonic()
        wait_for(lambda: len(self.last_cmd_after(t0)) >= 3, 0.3, 0.01)
        cmds = self.last_cmd_after(t0)
        self.assertGreaterEqual(len(cmds), 3, "cmd_vel must keep coming at >= 10 Hz")
        self.assertTrue(all(c.linear.x == 0 and c.linear.y == 0 and c.angular.z == 0 for c in cmds))

    def test_follows_a_path_and_refuses_bad_ones(self):
        x, y, yaw = self.rec.xy_yaw()
        c, s = math.cos(yaw), math.sin(yaw)
        # Ahead 0.4 m, then 0.4 m ahead and 0.3 m left, then a final turn on the spot.
        pts = [(0.4, 0.0), (0.8, 0.3), (0.8, 0.3)]
        path = [Pose2D(x + c * px - s * py, y + s * px + c * py, yaw) for px, py in pts]
        path[-1].theta = yaw + 0.5
        for bad, speed in (([], 0.2), (path, 0.0), (path, 0.5), ([Pose2D(float("nan"), 0.0, 0.0)], 0.2)):
            res = self.follow_path(path=bad, max_speed=speed)
            self.assertFalse(res.accepted)
            self.assertTrue(res.message)
        self.assertTrue(self.idle())
        res = self.follow_path(path=path, max_speed=0.3)
        self.assertTrue(res.accepted, res.message)
        self.assertTrue(wait_for(lambda: self.rec.status[-1] == "running", 5.0))
        self.assertTrue(wait_for(self.idle, 40.0), "path not done, status %s" % self.rec.status[-3:])
        x1, y1, yaw1 = self.rec.xy_yaw()
        self.assertLess(math.hypot(x1 - path[-1].x, y1 - path[-1].y), 0.04)
        self.assertLess(abs(math.atan2(math.sin(yaw1 - yaw - 0.5), math.cos(yaw1 - yaw - 0.5))), 0.05)

    def test_bad_goals_rejected_without_motion(self):
        x0, y0, _ = self.rec.xy_yaw()
        non_unit, zero = make_pose(x0 + 0.5, y0, 0.0), make_pose(x0 + 0.5, y0, 0.0)
        non_unit.orientation.w = 3.0
        zero.orientation.w = 0.0  # all four zero: malformed, not heading 0
        for pose in (make_pose(float("nan"), 0.0, 0.0), non_unit, zero):
            res = self.set_position(pose=pose)
            self.assertFalse(res.accepted)
            self.assertTrue(res.message)
        self.assertIn("unit quaternion", res.message)
        self.assertTrue(self.idle())
        self.assert_robot_stopped()

    def test_emergency_zeroes_within_one_period_and_releases_to_idle(self):
        x, y, _ = self.rec.xy_yaw()
        res = self.set_position(pose=make_pose(x - 1.0, y, math.pi))
        self.assertTrue(res.accepted)
        self.assertTrue(
            wait_for(lambda: any(abs(c.angular.z) > 0.1 for c in self.last_cmd_after(time.monotonic() - 0.1)), 5.0)
        )
        t0 = time.monotonic()
        self.emergency(data=True)
        self.assertTrue(wait_for(lambda: self.rec.status[-1] == "emergency", 30.0))
        # every cmd_vel received more than one period after the call is zero
        self.assertTrue(wait_for(lambda: len(self.last_cmd_after(t0 + PERIOD + 0.05)) >= 10, 30.0))
        late = self.last_cmd_after(t0 + PERIOD + 0.05)
        self.assertTrue(all(c.angular.z == 0.0 and c.linear.x == 0.0 for c in late))
        self.assert_robot_stopped()
        self.assertFalse(self.set_position(pose=make_pose(x, y, 0.0)).accepted)
        self.emergency(data=False)
        self.assertTrue(wait_for(self.idle, 30.0))

    def test_stale_pose_stops_then_continues(self):
        x, y, yaw = self.rec.xy_yaw()
        goal = make_pose(x + 0.8 * math.cos(yaw), y + 0.8 * math.sin(yaw), yaw)
        self.assertTrue(self.set_position(pose=goal).accepted)
        self.assertTrue(
            wait_for(lambda: any(abs(c.linear.x) > 0.1 for c in self.last_cmd_after(time.monotonic() - 0.1)), 5.0)
        )
        t0 = time.monotonic()
        self.pause(data=True)
        self.assertTrue(wait_for(lambda: len(self.last_cmd_after(t0 + 0.5 + PERIOD + 0.1)) >= 10, 30.0))
        late = self.last_cmd_after(t0 + 0.5 + PERIOD + 0.1)
        self.assertTrue(all(c.linear.x == 0.0 for c in late))
        self.assertEqual(self.rec.status[-1], "running")
        self.pause(data=False)
        self.assertTrue(wait_for(self.idle, 30.0))
        x1, y1, _ = self.rec.xy_yaw()
        self.assertLess(math.hypot(x1 - goal.position.x, y1 - goal.position.y), 0.03)

    def test_speed_scale_zero_holds_robot(self):
        n = messages_received("/rbd_pos_controller", "/rbd_lidar/speed_scale")
        self.scale_pub.publish(Float32(0.0))
        self.assertTrue(wait_for(lambda: messages_received("/rbd_pos_controller", "/rbd_lidar/speed_scale") > n, 5.0),
                        "the speed scale never reached the controller")
        x, y, yaw = self.rec.xy_yaw()
        self.assertTrue(
            self.set_position(pose=make_pose(x + 0.5 * math.cos(yaw), y + 0.5 * math.sin(yaw), yaw)).accepted
        )
        self.assertTrue(wait_for(lambda: self.rec.status[-1] == "running", 5.0), self.rec.status[-3:])
        self.assert_robot_stopped(1.0)  # a goal taken at full speed moves it within a control period
        self.scale_pub.publish(Float32(1.0))
        self.assertTrue(wait_for(self.idle, 30.0))


if __name__ == "__main__":
    run_rostest("rbd_pos_controller", "pos_controller_wiring", TestPosController)
